"""move_arm's plan (``robot/arm_plan.py``): the controller that moves the joints, every joint it claims in the
goal (those not named held), the time from the URDF speeds and the speed scale, each dialect's spelling."""

from __future__ import annotations

import math

import pytest

from arm_fixture import ARM_JOINTS, HOME, ROBOT
from rosbridge_mcp_server.robot.arm.controllers import parse_controllers
from rosbridge_mcp_server.robot.arm_plan import PlanError, plan_motion

CONTROLLERS = parse_controllers(
    {
        "controller": [
            {
                "name": "arm_controller",
                "type": "joint_trajectory_controller/JointTrajectoryController",
                "state": "active",
                "claimed_interfaces": [f"{joint}/position" for joint in ARM_JOINTS],
            },
            {
                "name": "gripper_controller",
                "type": "position_controllers/GripperActionController",
                "state": "active",
                "claimed_interfaces": ["gripper_finger_joint/position"],
            },
        ]
    }
)


def test_a_goal_names_every_joint_of_its_controller_and_is_timed_by_the_slowest_joint() -> None:
    """Elbow 1.2 → 0.2 rad at a quarter of 3 rad/s takes 1.334 s (rounded up to the millisecond)."""
    plan = plan_motion(
        ROBOT,
        HOME,
        {"elbow_joint": 0.2},
        controllers=CONTROLLERS,
        controller=None,
        speed_scale=0.25,
        ros_version=2,
    )
    assert plan.action == "/arm_controller/follow_joint_trajectory"
    assert plan.joints == ARM_JOINTS
    assert plan.target == tuple(0.2 if name == "elbow_joint" else HOME[name] for name in ARM_JOINTS)
    assert plan.duration == pytest.approx(math.ceil(1.0 / 0.75 * 1000) / 1000)
    point = plan.goal["trajectory"]["points"][0]  # type: ignore[index]
    assert point["time_from_start"] == {"sec": 1, "nanosec": 334_000_000}
    assert "velocities" not in point  # positions only: the controller interpolates linearly, never faster


def test_ros1_spells_the_time_secs_nsecs_and_a_smaller_scale_takes_longer() -> None:
    plan = plan_motion(
        ROBOT,
        HOME,
        {"shoulder_pan_joint": 1.0},
        controllers=(),
        controller=None,
        speed_scale=0.1,
        ros_version=1,
    )
    assert plan.action == "/arm_controller/follow_joint_trajectory"
    assert plan.duration == pytest.approx(5.0)
    assert plan.goal["trajectory"]["points"][0]["time_from_start"] == {"secs": 5, "nsecs": 0}  # type: ignore[index]


def test_a_gripper_joint_is_not_sent_to_the_arm_controller() -> None:
    with pytest.raises(
        PlanError, match="no trajectory controller of the controller manager moves gripper_finger_joint"
    ):
        plan_motion(
            ROBOT,
            HOME,
            {"gripper_finger_joint": 0.0},
            controllers=CONTROLLERS,
            controller=None,
            speed_scale=0.25,
            ros_version=2,
        )


def test_a_joint_whose_position_is_unknown_cannot_be_planned() -> None:
    with pytest.raises(PlanError, match="was not read from /joint_states"):
        plan_motion(
            ROBOT,
            {},
            {"elbow_joint": 0.2},
            controllers=CONTROLLERS,
            controller=None,
            speed_scale=0.25,
            ros_version=2,
        )
