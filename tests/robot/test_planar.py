"""The domain's planar pieces: one yaw of a quaternion (a message's or a transform's), a transform's planar
pose, a lifecycle answer read, and a navigation goal's progress from its feedback."""

from __future__ import annotations

import math

import pytest

from rosbridge_mcp_server.robot.lifecycle import LifecycleState, read_state
from rosbridge_mcp_server.robot.navigation import Progress, navigation_action, pose_message
from rosbridge_mcp_server.robot.occupancy import Pose2D, yaw_of
from rosbridge_mcp_server.robot.transforms import Transform


def quaternion(yaw: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


@pytest.mark.parametrize("yaw", [0.0, 0.5, -2.0, math.pi / 2, 3.0])
def test_a_message_and_a_transform_have_the_same_yaw(yaw: float) -> None:
    """A geometry_msgs/Quaternion and a tf rotation tuple give the yaw they were made with."""
    x, y, z, w = quaternion(yaw)
    assert yaw_of({"x": x, "y": y, "z": z, "w": w}) == pytest.approx(yaw)
    assert yaw_of((x, y, z, w)) == pytest.approx(yaw)
    assert Transform((0.0, 0.0, 0.0), (x, y, z, w)).rpy_degrees()[2] == pytest.approx(math.degrees(yaw))


@pytest.mark.parametrize("bad", [None, "north", (1.0, 2.0), {"z": "half"}, (math.nan, 0.0, 0.0, 1.0)])
def test_a_malformed_quaternion_is_no_turn(bad: object) -> None:
    """Missing, malformed or non-finite parts are taken as the identity's."""
    assert yaw_of(bad) == 0.0


def test_a_transform_is_a_planar_pose() -> None:
    """A transform's planar pose is its x, y and yaw; z is dropped."""
    pose = Transform((1.5, -2.0, 0.3), quaternion(1.0)).planar()
    assert (pose.x, pose.y, pose.yaw) == pytest.approx((1.5, -2.0, 1.0))
    assert pose.rounded() == [1.5, -2.0, round(math.degrees(1.0), 1)]


def test_a_goal_pose_message_turns_back_into_its_pose() -> None:
    """The PoseStamped sent for a goal reads back as the goal's pose."""
    message = pose_message("map", Pose2D(2.0, 1.0, math.pi / 2))
    assert message["header"]["frame_id"] == "map"
    assert yaw_of(message["pose"]["orientation"]) == pytest.approx(math.pi / 2)


def test_the_navigator_is_chosen_by_ros_version_and_waypoints() -> None:
    """move_base on ROS 1; Nav2's NavigateThroughPoses for waypoints, else NavigateToPose."""
    assert navigation_action(ros1=True, waypoints=False).name == "/move_base"
    assert navigation_action(ros1=False, waypoints=True).type == "nav2_msgs/action/NavigateThroughPoses"
    assert navigation_action(ros1=False, waypoints=False).name == "/navigate_to_pose"


def test_a_lifecycle_answer_is_read_as_its_state() -> None:
    """get_state's current_state says active or not; an answer without one is no state."""
    active = read_state({"current_state": {"id": 3, "label": "active"}})
    inactive = read_state({"current_state": {"id": 2, "label": "inactive"}})
    assert active == LifecycleState(3, "active")
    assert active.active
    assert inactive is not None
    assert not inactive.active
    assert inactive.label == "inactive"
    assert read_state({"current_state": "active"}) is None
    assert read_state([]) is None


def test_progress_follows_the_feedback() -> None:
    """Nav2's feedback extends the path driven and counts recoveries; move_base's gives the distance left."""
    progress = Progress(Pose2D(0.0, 0.0, 0.0), Pose2D(3.0, 4.0, 0.0))
    said = progress.feed(
        "g1",
        {
            "current_pose": {"pose": {"position": {"x": 3.0, "y": 0.0}}},
            "distance_remaining": 4.0,
            "estimated_time_remaining": {"sec": 9, "nanosec": 0},
            "number_of_recoveries": 2,
        },
    )
    assert said.startswith("goal g1, 4.00 m to go, ")
    assert said.endswith(", ~9 s left, 2 recoveries")
    assert progress.recoveries == 2
    assert progress.feed("g1", {"base_position": {"pose": {"position": {"x": 3.0, "y": 1.0}}}}).startswith(
        "goal g1, 3.00 m to go"
    )
    progress.ended_at(Pose2D(3.0, 4.0, 0.0))
    assert progress.driven == pytest.approx(7.0)


def test_malformed_feedback_is_no_position() -> None:
    """A pose that is not an object leaves the path as it was."""
    progress = Progress(Pose2D(0.0, 0.0, 0.0), Pose2D(1.0, 0.0, 0.0))
    progress.feed("g1", {"current_pose": {"pose": "here"}})
    assert progress.track == [(0.0, 0.0)]
