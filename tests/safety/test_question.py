"""The person sees what they approve (issue 35, finding 7): every value that moves the robot, whole, first;
strings capped with the cut said; control and direction characters escaped; no layout hides a value."""

from __future__ import annotations

from typing import Any

import pytest

from rosbridge_mcp_server.robot.approval import Act
from rosbridge_mcp_server.safety import question
from rosbridge_mcp_server.safety.question import LINES_SHOWN, TEXT_SHOWN, shown_text

GOAL = "nav2_msgs/action/NavigateToPose"


def goal(frame_id: str, *, x: float = 9.0, label: str = "") -> Act:
    pose = {
        "header": {"frame_id": frame_id, "stamp": {"sec": 0, "nanosec": 0}},
        "pose": {"position": {"x": x, "y": 1.5, "z": 0.0}, "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}},
    }
    return Act("publish_action", "action", "/navigate_to_pose", GOAL, {"pose": pose, "behavior_tree": label})


def values_of(text: str) -> list[str]:
    """The lines between the values heading and the text heading."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("Goal values"))
    end = next((i for i, line in enumerate(lines) if line.startswith("Goal text")), len(lines))
    return lines[start + 1 : end]


@pytest.mark.parametrize(
    ("frame_id", "label"),
    [(" " * 4000, ""), ("map", "x" * 100_000), ("map" + "\n" * 5000, "\u202e" * 3000)],
)
def test_no_string_pushes_the_goal_out_of_sight(frame_id: str, label: str) -> None:
    """A 4,000-space frame_id or a long label once pushed ``x: 9.0`` past the 4,000-character cut."""
    text = question(goal(frame_id, label=label))
    assert "  pose.pose.position.x: 9.0" in values_of(text)
    assert "  pose.pose.position.y: 1.5" in values_of(text)
    assert text.index("pose.pose.position.x: 9.0") < text.index("pose.header.frame_id")
    assert len(text) < 3000
    assert "not shown" in text or len(frame_id) + len(label) <= TEXT_SHOWN


def test_control_and_direction_characters_are_shown_escaped() -> None:
    """A right-to-left override would reverse what the person reads; a newline would start a line of ours."""
    text = question(goal("map\u202e0.0 :x\nAllow this?\x1b[2J\u2066\u200b\u2028"))
    for raw in ("\u202e", "\x1b", "\u2066", "\u200b", "\u2028"):
        assert raw not in text
    assert '"map\\u202e0.0 :x\\nAllow this?\\u001b[2J\\u2066\\u200b\\u2028"' in text
    assert text.count("\n") == len(text.splitlines()) - 1
    assert text.splitlines().count("Allow this?") == 1


def test_field_names_are_escaped_too() -> None:
    """A message of a type rosapi cannot describe has names the model chose."""
    act = Act("publish_topic", "topic", "/x", "my_msgs/msg/Thing", {"a\nAllow this?\u202e": 1.0})
    text = question(act)
    assert '"a\\nAllow this?\\u202e": 1.0' in text
    assert text.splitlines().count("Allow this?") == 1


def test_a_long_array_cannot_push_a_fixed_field_out() -> None:
    """Array contents (the model chooses their length) come after the type's fixed fields."""
    point = {"positions": [0.1] * 50, "velocities": [0.2], "effort": [1.0], "accelerations": [0.0]}
    points = [{**point, "time_from_start": {"sec": i}} for i in range(500)]
    message: dict[str, Any] = {"points": points, "header": {"frame_id": "base"}, "speed": 3.5}
    text = question(Act("publish_topic", "topic", "/arm", "my_msgs/msg/Traj", message))
    lines = text.splitlines()
    assert "  speed: 3.5" in lines
    assert lines.index("  speed: 3.5") < 12
    assert "more elements not shown" in text
    assert "more fields not shown" in text
    assert "(50 in all)" in text
    assert len(lines) < LINES_SHOWN + 20


def test_every_number_is_shown_whole() -> None:
    text = question(goal("map", x=1.0000000000000002))
    assert "pose.pose.position.x: 1.0000000000000002" in text


def test_shown_text_keeps_plain_text() -> None:
    assert shown_text("Hello, wörld — 地図") == '"Hello, wörld — 地図"'
    assert shown_text('say "hi"\\') == '"say \\"hi\\"\\\\"'


def test_a_name_from_the_robot_in_the_head_is_escaped_and_capped() -> None:
    """A ROS 2 parameter's name is kept as written (no whitespace, but any other character)."""
    name = "/turtlesim:\u202e" + "p" * 5000
    text = question(Act("set_parameter", "parameter", name, "", 9.0))
    assert "\u202e" not in text
    assert "/turtlesim:\\u202epppp" in text
    assert "  value: 9.0" in text
    assert len(text) < 2000
