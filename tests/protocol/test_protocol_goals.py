"""A goal's frames read as typed events (wire/goals.py), as each bridge line sends them."""

from __future__ import annotations

from typing import Any

import pytest

from rosbridge_mcp_server.wire.goals import (
    GoalEnded,
    GoalEvent,
    GoalFeedbackEvent,
    GoalNeverRan,
    GoalStatusRefusal,
    goal_event,
)


@pytest.mark.parametrize(
    ("op", "frame", "event"),
    [
        (
            "action_feedback",
            {"op": "action_feedback", "id": "g", "values": {"sequence": [0, 1]}},
            GoalFeedbackEvent({"sequence": [0, 1]}),
        ),
        (
            "action_result",
            {
                "op": "action_result",
                "id": "g",
                "status": 4,
                "values": {"sequence": [0, 1, 1]},
                "result": True,
            },
            GoalEnded(4, {"sequence": [0, 1, 1]}),
        ),
        # rosbridge_suite: a goal that never ran (no action server, rejected) says so with result false.
        (
            "action_result",
            {
                "op": "action_result",
                "id": "g",
                "status": 0,
                "values": "No action server available",
                "result": False,
            },
            GoalNeverRan("No action server available"),
        ),
        # rosbridge-server-rs 0.1.6: result false for a goal that ran and ended CANCELED, with its fields.
        (
            "action_result",
            {"op": "action_result", "id": "g", "status": 5, "values": {"sequence": [0]}, "result": False},
            GoalEnded(5, {"sequence": [0]}),
        ),
        # A false result whose values are not the result's fields never ran, whatever its status says.
        (
            "action_result",
            {"op": "action_result", "id": "g", "status": 6, "values": ["odd"], "result": False},
            GoalNeverRan("['odd']"),
        ),
        # A status that is not an int (or a bool) is no goal state.
        ("action_result", {"op": "action_result", "id": "g", "status": True, "values": {}}, GoalEnded(0, {})),
        (
            "status",
            {"op": "status", "level": "error", "id": "g", "msg": "unknown active goal"},
            GoalStatusRefusal("unknown active goal"),
        ),
    ],
)
def test_each_goal_frame_is_one_typed_event(op: str, frame: dict[str, Any], event: GoalEvent) -> None:
    """Feedback, an end (whatever ``result`` says of a goal that ran), a goal that never ran, a refusal."""
    assert goal_event(op, frame) == event
