"""The simulated arm's description: a 6-joint arm and a two-finger gripper on the turtle's ``base_link``.

Laid out as the ROS 2 lab's arm (``../shared/labs/ros2/NOTES.md``, "The arm"), so that what a client learns
here holds there: ros2_control's usual joint names, the same limits, speeds and origins, the gripper's right
finger mimicking the left. Zero pose: the arm straight up; it starts at *home*.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = [
    "ARM_JOINTS",
    "FINGER",
    "HOME",
    "JOINTS",
    "NAMED_POSES",
    "ArmJoint",
    "arm_urdf",
    "joint_transform",
    "srdf",
]

Vector = tuple[float, float, float]


@dataclass(frozen=True)
class ArmJoint:
    """One joint of the arm, as its URDF says."""

    name: str
    kind: str  #: revolute, prismatic or fixed
    parent: str
    child: str
    xyz: Vector
    yaw: float = 0.0  #: the origin's rotation (only about z in this arm)
    axis: Vector = (0.0, 0.0, 1.0)
    lower: float = 0.0
    upper: float = 0.0
    velocity: float = 0.0
    effort: float = 0.0
    mimic: str | None = None


PI = 3.1416
JOINTS: tuple[ArmJoint, ...] = (
    ArmJoint("arm_mount_joint", "fixed", "base_link", "arm_base_link", (0.0, 0.0, 0.1)),
    ArmJoint("shoulder_pan_joint", "revolute", "arm_base_link", "shoulder_link", (0, 0, 0.1), 0, (0, 0, 1),
             -PI, PI, 2.0, 150.0),
    ArmJoint("shoulder_lift_joint", "revolute", "shoulder_link", "upper_arm_link", (0, 0.12, 0.06), 0,
             (0, 1, 0), -2.0944, 2.0944, 2.0, 150.0),
    ArmJoint("elbow_joint", "revolute", "upper_arm_link", "forearm_link", (0, -0.1, 0.4), 0, (0, 1, 0),
             -2.7925, 2.7925, 3.0, 150.0),
    ArmJoint("wrist_1_joint", "revolute", "forearm_link", "wrist_1_link", (0, 0, 0.2), 0, (0, 0, 1),
             -PI, PI, 3.0, 28.0),
    ArmJoint("wrist_2_joint", "revolute", "wrist_1_link", "wrist_2_link", (0, 0, 0.17), 0, (0, 1, 0),
             -2.0944, 2.0944, 3.0, 28.0),
    ArmJoint("wrist_3_joint", "revolute", "wrist_2_link", "wrist_3_link", (0, 0, 0.08), 0, (0, 0, 1),
             -6.2832, 6.2832, 3.0, 28.0),
    ArmJoint("tool0_joint", "fixed", "wrist_3_link", "tool0", (0.0, 0.0, 0.03)),
    ArmJoint("gripper_mount_joint", "fixed", "tool0", "gripper_base_link", (0.0, 0.0, 0.0), math.pi / 2),
    ArmJoint("gripper_finger_joint", "prismatic", "gripper_base_link", "gripper_left_finger_link",
             (0, 0, 0.05), 0, (0, 1, 0), 0.0, 0.04, 0.05, 20.0),
    ArmJoint("gripper_right_finger_joint", "prismatic", "gripper_base_link", "gripper_right_finger_link",
             (0, 0, 0.05), 0, (0, -1, 0), 0.0, 0.04, 0.05, 20.0, mimic="gripper_finger_joint"),
)  # fmt: skip

#: The six joints the arm controller moves, in its order.
ARM_JOINTS = tuple(j.name for j in JOINTS if j.kind == "revolute")
#: The gripper's one commanded joint (0 closed, 0.04 open).
FINGER = "gripper_finger_joint"
#: Named poses (the SRDF's group states) of the arm group.
NAMED_POSES: dict[str, tuple[float, ...]] = {
    "home": (0.0, -0.3, 1.2, 0.0, 0.8, 0.0),
    "ready": (0.0, 0.5, 1.0, 0.0, 1.2, 0.0),
    "zero": (0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
}
HOME = dict(zip(ARM_JOINTS, NAMED_POSES["home"], strict=True)) | {FINGER: 0.04}
#: Each link's collision shape (a cylinder's radius, or a box's size), as a URDF gives a link's size;
#: tool0 and the mount have none.
SHAPES: dict[str, str] = {
    "shoulder_link": '<cylinder radius="0.06" length="0.12"/>',
    "upper_arm_link": '<cylinder radius="0.05" length="0.4"/>',
    "forearm_link": '<cylinder radius="0.04" length="0.2"/>',
    "wrist_1_link": '<cylinder radius="0.035" length="0.17"/>',
    "wrist_2_link": '<cylinder radius="0.035" length="0.08"/>',
    "wrist_3_link": '<cylinder radius="0.03" length="0.03"/>',
    "gripper_base_link": '<box size="0.1 0.04 0.04"/>',
    "gripper_left_finger_link": '<box size="0.01 0.02 0.05"/>',
    "gripper_right_finger_link": '<box size="0.01 0.02 0.05"/>',
}


def _joint_xml(joint: ArmJoint) -> str:
    x, y, z = joint.xyz
    text = (
        f'  <joint name="{joint.name}" type="{joint.kind}">\n    <parent link="{joint.parent}"/>\n'
        f'    <child link="{joint.child}"/>\n'
        f'    <origin xyz="{x:g} {y:g} {z:g}" rpy="0 0 {joint.yaw:.6g}"/>\n'
    )
    if joint.kind != "fixed":
        ax, ay, az = joint.axis
        text += (
            f'    <axis xyz="{ax:g} {ay:g} {az:g}"/>\n'
            f'    <limit lower="{joint.lower:g}" upper="{joint.upper:g}" velocity="{joint.velocity:g}"'
            f' effort="{joint.effort:g}"/>\n'
        )
    if joint.mimic:
        text += f'    <mimic joint="{joint.mimic}" multiplier="1" offset="0"/>\n'
    return text + "  </joint>\n"


def _link_xml(name: str) -> str:
    shape = SHAPES.get(name)
    if shape is None:
        return f'  <link name="{name}"/>\n'
    return f'  <link name="{name}">\n    <collision><geometry>{shape}</geometry></collision>\n  </link>\n'


def arm_urdf() -> str:
    """The arm's links and joints, to go inside the robot's ``<robot>`` (its root link is ``base_link``)."""
    links = "".join(_link_xml(joint.child) for joint in JOINTS)
    return links + "".join(_joint_xml(joint) for joint in JOINTS)


def srdf() -> str:
    """The semantic description: the arm and gripper groups, the named poses, the end effector."""
    poses = "".join(
        f'  <group_state name="{name}" group="arm">\n'
        + "".join(f'    <joint name="{j}" value="{v:g}"/>\n' for j, v in zip(ARM_JOINTS, values, strict=True))
        + "  </group_state>\n"
        for name, values in NAMED_POSES.items()
    )
    gripper = "".join(
        f'  <group_state name="{name}" group="gripper">\n    <joint name="{FINGER}" value="{v:g}"/>\n'
        "  </group_state>\n"
        for name, v in (("open", 0.04), ("closed", 0.0))
    )
    return (
        '<?xml version="1.0"?>\n<robot name="sim_turtle">\n'
        '  <group name="arm">\n    <chain base_link="arm_base_link" tip_link="tool0"/>\n  </group>\n'
        f'  <group name="gripper">\n    <joint name="{FINGER}"/>\n  </group>\n'
        + poses
        + gripper
        + '  <end_effector name="hand" parent_link="tool0" group="gripper" parent_group="arm"/>\n</robot>\n'
    )


def _quaternion(axis: Vector, angle: float) -> tuple[float, float, float, float]:
    s = math.sin(angle / 2)
    return (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2))


def _multiply(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, float, float, float]:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def joint_transform(joint: ArmJoint, position: float) -> tuple[Vector, tuple[float, float, float, float]]:
    """The child link's translation and rotation (x, y, z, w) in the parent link's frame at *position*."""
    origin = _quaternion((0.0, 0.0, 1.0), joint.yaw)
    x, y, z = joint.xyz
    if joint.kind == "revolute":
        return (x, y, z), _multiply(origin, _quaternion(joint.axis, position))
    if joint.kind == "prismatic":
        c, s = math.cos(joint.yaw), math.sin(joint.yaw)
        ax, ay, az = joint.axis
        return (x + (c * ax - s * ay) * position, y + (s * ax + c * ay) * position, z + az * position), origin
    return (x, y, z), origin
