"""Which goal a publish or a service call starts, as the stops remember it (robot/goals/caused.py), and which
action servers the E-STOP counts as moving the robot (robot/goals/stopping.py)."""

from __future__ import annotations

import base64

import pytest

from rosbridge_mcp_server.robot.effects import service_effects, topic_effects
from rosbridge_mcp_server.robot.goals.caused import CausedGoal, caused_by_call, caused_by_publish
from rosbridge_mcp_server.robot.goals.stopping import motion_action_type


def published(topic: str, type_name: str, message: dict[str, object], dialect: int = 1) -> CausedGoal | None:
    return caused_by_publish(topic, message, topic_effects(topic, type_name), dialect)


def test_a_goal_on_an_actionlib_goal_topic_is_remembered_by_its_id() -> None:
    goal = published(
        "/move_base/goal", "move_base_msgs/MoveBaseActionGoal", {"goal_id": {"id": "g"}, "goal": {}}
    )
    assert goal is not None
    assert (goal.action, goal.goal_id, goal.carrier) == ("/move_base", "g", "/move_base/goal")


@pytest.mark.parametrize("goal_id", [{}, {"id": ""}, None])
def test_a_goal_without_an_id_is_every_goal_of_its_action(goal_id: object) -> None:
    """The action server names a goal sent without an id: the stop cannot know it, so cancels them all."""
    goal = published("/move_base/goal", "move_base_msgs/MoveBaseActionGoal", {"goal_id": goal_id, "goal": {}})
    assert goal is not None
    assert (goal.action, goal.goal_id) == ("/move_base", None)


@pytest.mark.parametrize(
    ("topic", "type_name", "dialect", "action"),
    [
        ("/goal_pose", "geometry_msgs/msg/PoseStamped", 2, "/navigate_to_pose"),
        ("/robot1/goal_pose", "geometry_msgs/msg/PoseStamped", 2, "/robot1/navigate_to_pose"),
        ("/move_base_simple/goal", "geometry_msgs/PoseStamped", 1, "/move_base"),
        ("/robot2/move_base_simple/goal", "geometry_msgs/PoseStamped", 1, "/robot2/move_base"),
    ],
)
def test_a_goal_pose_is_every_goal_of_its_navigator(
    topic: str, type_name: str, dialect: int, action: str
) -> None:
    goal = published(topic, type_name, {"pose": {}}, dialect)
    assert goal is not None
    assert (goal.action, goal.goal_id, goal.dialect, goal.carrier) == (action, None, dialect, topic)
    assert goal.describe() == f"every goal on {action} (sent on {topic})"


def test_other_publishes_start_no_goal() -> None:
    assert published("/chatter", "std_msgs/String", {"data": "goal"}) is None
    assert published("/cmd_vel", "geometry_msgs/Twist", {}) is None
    assert published("/move_base/cancel", "actionlib_msgs/GoalID", {"id": "g"}) is None
    assert published("/my_goal_pose", "geometry_msgs/msg/PoseStamped", {}, 2) is None


@pytest.mark.parametrize("uuid", [list(range(16)), base64.b64encode(bytes(range(16))).decode()])
def test_a_send_goal_call_is_remembered_by_its_uuid(uuid: object) -> None:
    service = "/navigate_to_pose/_action/send_goal"
    request = {"goal_id": {"uuid": uuid}, "goal": {}}
    effects = service_effects(service, "nav2_msgs/action/NavigateToPose_SendGoal", request, 2)
    goal = caused_by_call(service, request, effects, 2)
    assert goal is not None
    assert (goal.action, goal.goal_id) == ("/navigate_to_pose", bytes(range(16)).hex())
    cancel = "/navigate_to_pose/_action/cancel_goal"
    assert caused_by_call(cancel, {}, service_effects(cancel, "action_msgs/srv/CancelGoal", {}, 2), 2) is None


@pytest.mark.parametrize(
    "action_type",
    [
        "nav2_msgs/action/NavigateToPose",
        "nav2_msgs/NavigateToPoseAction",
        "nav2_msgs/action/DriveOnHeading",
        "move_base_msgs/MoveBaseAction",
        "control_msgs/action/FollowJointTrajectory",
        "control_msgs/GripperCommandAction",
        "opennav_docking_msgs/action/DockRobot",
    ],
)
def test_motion_action_types_in_either_spelling(action_type: str) -> None:
    assert motion_action_type(action_type)


@pytest.mark.parametrize(
    "action_type",
    [
        "nav2_msgs/action/ComputePathToPose",
        "nav2_msgs/action/Wait",
        "example_interfaces/action/Fibonacci",
        "junk",
    ],
)
def test_actions_that_move_nothing_are_not_motion(action_type: str) -> None:
    assert not motion_action_type(action_type)
