"""ROS 1 vs ROS 2 rules: type names, action type forms, time fields, goal status, RosInfo."""

from __future__ import annotations

import pytest

from rosbridge_mcp_server.errors import UnknownTypeError
from rosbridge_mcp_server.wire import ros_versions
from rosbridge_mcp_server.wire.ros_versions import RosInfo


@pytest.mark.parametrize(
    ("given", "version", "expected"),
    [
        ("geometry_msgs/msg/Twist", 1, "geometry_msgs/Twist"),
        ("geometry_msgs/Twist", 1, "geometry_msgs/Twist"),
        ("geometry_msgs/Twist", 2, "geometry_msgs/msg/Twist"),
        ("geometry_msgs/msg/Twist", 2, "geometry_msgs/msg/Twist"),
        (" std_msgs/String ", 2, "std_msgs/msg/String"),
    ],
)
def test_message_types_are_spelled_for_the_dialect(given: str, version: int, expected: str) -> None:
    """ROS 1 gets pkg/Type (it rejects three parts); ROS 2 gets the full pkg/msg/Type."""
    assert ros_versions.normalize_type(given, version) == expected


def test_service_types_get_the_srv_category_on_ros2() -> None:
    """A short service type becomes pkg/srv/Type on ROS 2 and stays short on ROS 1."""
    assert ros_versions.normalize_type("std_srvs/Trigger", 2, "srv") == "std_srvs/srv/Trigger"
    assert ros_versions.normalize_type("std_srvs/srv/Trigger", 1, "srv") == "std_srvs/Trigger"


@pytest.mark.parametrize("bad", ["Twist", "a/b/c/d", "geometry_msgs/", "pkg/other/Type", "1pkg/Type", ""])
def test_malformed_type_names_are_rejected_with_an_example(bad: str) -> None:
    """Names that are not pkg/Type or pkg/category/Type raise UnknownTypeError with a hint."""
    with pytest.raises(UnknownTypeError, match="pkg/Type"):
        ros_versions.normalize_type(bad, 2)


@pytest.mark.parametrize(
    "given",
    [
        "action_tutorials_interfaces/Fibonacci",
        "action_tutorials_interfaces/action/Fibonacci",
        "action_tutorials_interfaces/FibonacciAction",
        "action_tutorials_interfaces/msg/FibonacciAction",
        "action_tutorials_interfaces/FibonacciActionGoal",
    ],
)
def test_every_action_type_form_names_the_same_action(given: str) -> None:
    """pkg/Fibonacci, pkg/action/Fibonacci and pkg/FibonacciAction map to both dialects' names."""
    names = ros_versions.action_type_names(given)
    assert names.ros2 == "action_tutorials_interfaces/action/Fibonacci"
    ros1 = names.ros1
    assert ros1.action == "action_tutorials_interfaces/FibonacciAction"
    assert ros1.goal == "action_tutorials_interfaces/FibonacciActionGoal"
    assert ros1.feedback == "action_tutorials_interfaces/FibonacciActionFeedback"
    assert ros1.result == "action_tutorials_interfaces/FibonacciActionResult"
    assert ros1.goal_id == "actionlib_msgs/GoalID"
    assert ros1.status_array == "actionlib_msgs/GoalStatusArray"
    assert names.for_version(1) == ros1.action
    assert names.for_version(2) == names.ros2


def test_a_service_type_is_not_an_action_type() -> None:
    """pkg/srv/X is refused as an action type."""
    with pytest.raises(UnknownTypeError, match="service type"):
        ros_versions.action_type_names("std_srvs/srv/Trigger")


def test_ros1_messages_get_secs_and_nsecs() -> None:
    """Every {sec, nanosec} object, nested or in arrays, becomes {secs, nsecs} for ROS 1."""
    msg = {
        "header": {"stamp": {"sec": 5, "nanosec": 7}, "frame_id": "map"},
        "poses": [{"stamp": {"sec": 1, "nanosec": 2}}],
        "duration": {"sec": 3},
        "data": 4,
    }
    converted = ros_versions.adapt_message(msg, 1)
    assert converted == {
        "header": {"stamp": {"secs": 5, "nsecs": 7}, "frame_id": "map"},
        "poses": [{"stamp": {"secs": 1, "nsecs": 2}}],
        "duration": {"secs": 3},
        "data": 4,
    }
    assert msg["header"]["stamp"] == {"sec": 5, "nanosec": 7}, "the caller's message is not modified"


def test_ros2_messages_go_out_untouched() -> None:
    """ROS 2 reads both spellings, so its messages are not rewritten."""
    msg = {"stamp": {"secs": 1, "nsecs": 2}}
    assert ros_versions.adapt_message(msg, 2) is msg
    assert ros_versions.adapt_message(msg, 1) == msg, "already ROS 1's spelling"


def test_objects_that_merely_contain_sec_are_not_time() -> None:
    """Only objects made of time keys (numbers) are converted; other fields are left alone."""
    msg = {"sec": "text", "other": {"sec": 1, "label": "x"}}
    assert ros_versions.to_ros1_time(msg) == msg


@pytest.mark.parametrize(
    ("code", "version", "word", "terminal", "success"),
    [
        (0, 2, "unknown", False, False),
        (2, 2, "executing", False, False),
        (3, 2, "canceling", False, False),
        (4, 2, "succeeded", True, True),
        (5, 2, "canceled", True, False),
        (6, 2, "aborted", True, False),
        (0, 1, "pending", False, False),
        (1, 1, "active", False, False),
        (2, 1, "preempted", True, False),
        (3, 1, "succeeded", True, True),
        (4, 1, "aborted", True, False),
        (5, 1, "rejected", True, False),
        (6, 1, "preempting", False, False),
        (7, 1, "recalling", False, False),
        (8, 1, "recalled", True, False),
        (9, 1, "lost", True, False),
    ],
)
def test_goal_status_numbers_mean_different_things_per_dialect(
    code: int, version: int, word: str, terminal: bool, success: bool
) -> None:
    """Status words, terminal states and success follow each dialect's own numbering."""
    assert ros_versions.goal_status_name(code, version) == word
    assert ros_versions.is_terminal_status(code, version) is terminal
    assert ros_versions.is_success_status(code, version) is success


def test_unknown_status_numbers_are_named_by_number() -> None:
    """A status outside the table reads as "status N"."""
    assert ros_versions.goal_status_name(42, 2) == "status 42"


@pytest.mark.parametrize(
    ("info", "in_order", "actions"),
    [
        (RosInfo(2, "humble"), True, True),
        (RosInfo(2, "jazzy"), True, True),
        (RosInfo(2, None), True, True),
        (RosInfo(2, "jazzy", calls_threaded=False, goals_threaded=False), True, True),
        (RosInfo(2, "jazzy", calls_threaded=True, goals_threaded=True), False, True),
        (RosInfo(2, "humble", calls_threaded=True, goals_threaded=True), False, True),
        (RosInfo(1, None), False, False),
    ],
)
def test_ros_info_takes_a_bridge_as_in_order_unless_it_says_it_threads(
    info: RosInfo, in_order: bool, actions: bool
) -> None:
    """The bridge's threading switches decide, never the distro; only ROS 2 has action ops and timeouts."""
    assert info.may_be_in_order is in_order
    assert info.goals_may_block is in_order
    assert info.has_action_ops is actions
    assert info.honours_service_timeout is (info.version == 2)


def test_ros_info_describes_itself() -> None:
    """describe() reads like "ROS 2 (jazzy)"."""
    assert RosInfo(2, "jazzy").describe() == "ROS 2 (jazzy)"
    assert RosInfo(1).describe() == "ROS 1"
