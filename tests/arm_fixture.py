"""A 6-joint arm with a parallel gripper (the ROS 2 lab kit's layout) for the arm judge's tests."""

from __future__ import annotations

import math
from typing import Any

from rosbridge_mcp_server.robot.arm.urdf import Robot, parse_urdf
from rosbridge_mcp_server.robot.arm_scene import ArmScene

_JOINTS = [
    # name, type, axis, parent, child, xyz, limit (lower, upper, velocity)
    (
        "shoulder_pan_joint",
        "revolute",
        "0 0 1",
        "arm_base_link",
        "shoulder_link",
        "0 0 0.1",
        (-3.1416, 3.1416, 2.0),
    ),
    (
        "shoulder_lift_joint",
        "revolute",
        "0 1 0",
        "shoulder_link",
        "upper_arm_link",
        "0 0.12 0.06",
        (-2.0944, 2.0944, 2.0),
    ),
    (
        "elbow_joint",
        "revolute",
        "0 1 0",
        "upper_arm_link",
        "forearm_link",
        "0 -0.1 0.4",
        (-2.7925, 2.7925, 3.0),
    ),
    ("wrist_1_joint", "revolute", "0 0 1", "forearm_link", "wrist_1_link", "0 0 0.2", (-3.1416, 3.1416, 3.0)),
    (
        "wrist_2_joint",
        "revolute",
        "0 1 0",
        "wrist_1_link",
        "wrist_2_link",
        "0 0 0.17",
        (-2.0944, 2.0944, 3.0),
    ),
    (
        "wrist_3_joint",
        "revolute",
        "0 0 1",
        "wrist_2_link",
        "wrist_3_link",
        "0 0 0.08",
        (-6.2832, 6.2832, 3.0),
    ),
]


def _joint(spec: tuple[Any, ...]) -> str:
    name, kind, axis, parent, child, xyz, limit = spec
    lower, upper, velocity = limit
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="0 0 0"/><axis xyz="{axis}"/>'
        f'<limit lower="{lower}" upper="{upper}" velocity="{velocity}" effort="100"/></joint>'
    )


def arm_urdf() -> str:
    links = [
        "base_link",
        "arm_base_link",
        "tool0",
        "gripper_base_link",
        "gripper_left_finger_link",
        "gripper_right_finger_link",
    ] + [j[4] for j in _JOINTS]
    parts = [f'<link name="{link}"/>' for link in links]
    parts.append(
        '<joint name="arm_mount_joint" type="fixed"><parent link="base_link"/>'
        '<child link="arm_base_link"/><origin xyz="0 0 0.1"/></joint>'
    )
    parts += [_joint(j) for j in _JOINTS]
    parts.append(
        '<joint name="tool0_joint" type="fixed"><parent link="wrist_3_link"/><child link="tool0"/>'
        '<origin xyz="0 0 0.03"/></joint>'
    )
    parts.append(
        '<joint name="gripper_mount_joint" type="fixed"><parent link="tool0"/>'
        '<child link="gripper_base_link"/><origin xyz="0 0 0" rpy="0 0 1.5708"/></joint>'
    )
    parts.append(
        '<joint name="gripper_finger_joint" type="prismatic"><parent link="gripper_base_link"/>'
        '<child link="gripper_left_finger_link"/><origin xyz="0 0 0.05"/><axis xyz="0 1 0"/>'
        '<limit lower="0" upper="0.04" velocity="0.05" effort="40"/></joint>'
    )
    parts.append(
        '<joint name="gripper_right_finger_joint" type="prismatic"><parent link="gripper_base_link"/>'
        '<child link="gripper_right_finger_link"/><origin xyz="0 0 0.05"/><axis xyz="0 -1 0"/>'
        '<limit lower="0" upper="0.04" velocity="0.05" effort="40"/>'
        '<mimic joint="gripper_finger_joint"/></joint>'
    )
    return f'<?xml version="1.0"?><robot name="test_arm">{"".join(parts)}</robot>'


ROBOT: Robot = parse_urdf(arm_urdf())
ARM_JOINTS = tuple(j[0] for j in _JOINTS)
HOME = {
    "shoulder_pan_joint": 0.0,
    "shoulder_lift_joint": -0.3,
    "elbow_joint": 1.2,
    "wrist_1_joint": 0.0,
    "wrist_2_joint": 0.8,
    "wrist_3_joint": 0.0,
    "gripper_finger_joint": 0.04,
}


def scene(positions: dict[str, float] | None = None) -> ArmScene:
    return ArmScene(ROBOT, dict(HOME if positions is None else positions))


def degrees(**values: float) -> dict[str, float]:
    """HOME with some joints set in degrees."""
    out = dict(HOME)
    out.update({name: math.radians(value) for name, value in values.items()})
    return out
