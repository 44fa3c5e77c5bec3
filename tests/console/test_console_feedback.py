"""What the console shows of a running goal's feedback: its numbers by name, not the raw JSON."""

from __future__ import annotations

from rosbridge_mcp_server.console.feedback import feedback_text

#: A Nav2 NavigateToPose feedback as rosbridge sends it (ROS 2).
NAV2_FEEDBACK = {
    "current_pose": {
        "header": {"stamp": {"sec": 1795900000, "nanosec": 5}, "frame_id": "map"},
        "pose": {"position": {"x": 1.0, "y": 2.0, "z": 0.0}, "orientation": {"w": 1.0}},
    },
    "navigation_time": {"sec": 12, "nanosec": 400_000_000},
    "estimated_time_remaining": {"sec": 5, "nanosec": 0},
    "number_of_recoveries": 0,
    "distance_remaining": 2.3141592,
}


def test_a_nav2_feedback_reads_as_named_numbers() -> None:
    text = feedback_text(NAV2_FEEDBACK)
    assert text == (
        "navigation_time 12 s, estimated_time_remaining 5 s, number_of_recoveries 0, distance_remaining 2.31"
    )
    assert "{" not in text


def test_a_fibonacci_feedback_without_named_numbers_is_shown_shortened() -> None:
    """A feedback of arrays only has nothing to name: it is shown as JSON, shortened."""
    assert feedback_text({"sequence": [0, 1, 1, 2, 3]}) == '{"sequence": [0, 1, 1, 2, 3]}'


def test_many_fields_are_cut_after_a_few() -> None:
    text = feedback_text({f"field_{i}": i for i in range(10)})
    assert text.endswith(", …")
    assert text.count(",") == 6
