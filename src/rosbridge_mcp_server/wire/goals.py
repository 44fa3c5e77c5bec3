"""A ROS 2 goal's frames as typed events, without I/O.

A goal sent with ``send_action_goal`` is answered by ``action_feedback`` frames and one ``action_result``;
a bridge that answers refused ops with ``status`` (rosbridge-server-rs 0.1.6) may refuse the goal, or a
cancel naming it, with an error ``status`` carrying the goal's id. :func:`goal_event` reads one such frame;
nothing above the client reads the frame itself.

How the two bridge lines say a goal failed (see ``docs/rosbridge-behaviour.md``):

* rosbridge_suite (2.0.5 / 2.5.0 / 3.1.0 / 4.0.0 on): ``action_result`` with ``result: false``, ``status`` 0
  and ``values`` an error text ("No action server available", "Action goal was rejected"): the goal never ran.
* rosbridge-server-rs 0.1.6: an error ``status`` for a goal it refuses; and ``result: false`` also for a goal
  that ran and ended CANCELED or ABORTED, with that status and the result's fields: that goal ended.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final

__all__ = [
    "GoalEnded",
    "GoalEvent",
    "GoalFeedbackEvent",
    "GoalNeverRan",
    "GoalStatusRefusal",
    "goal_event",
]

#: ``action_msgs/GoalStatus`` codes a goal ends with: SUCCEEDED, CANCELED, ABORTED.
_TERMINAL: Final = frozenset({4, 5, 6})


@dataclass(frozen=True, slots=True)
class GoalFeedbackEvent:
    """One ``action_feedback``: the feedback message's fields."""

    values: Any


@dataclass(frozen=True, slots=True)
class GoalEnded:
    """The goal's ``action_result``: its final ``action_msgs/GoalStatus`` code and the result's fields."""

    status: int
    values: Any


@dataclass(frozen=True, slots=True)
class GoalNeverRan:
    """An ``action_result`` saying the goal never ran (no action server, rejected, unknown type): the bridge's
    text."""

    text: str


@dataclass(frozen=True, slots=True)
class GoalStatusRefusal:
    """An error ``status`` naming the goal: the bridge refused the goal, or a cancel of it (its text)."""

    text: str


GoalEvent = GoalFeedbackEvent | GoalEnded | GoalNeverRan | GoalStatusRefusal


def goal_event(op: str, frame: dict[str, Any]) -> GoalEvent:
    """The event one frame routed to a goal's id stands for (*op* is ``action_feedback``, ``action_result``
    or ``status``)."""
    if op == "action_feedback":
        return GoalFeedbackEvent(frame.get("values"))
    if op == "status":
        return GoalStatusRefusal(str(frame.get("msg")))
    values = frame.get("values")
    status = frame.get("status")
    code = status if isinstance(status, int) and not isinstance(status, bool) else 0
    if frame.get("result") is False and not (code in _TERMINAL and isinstance(values, dict)):
        return GoalNeverRan(values if isinstance(values, str) else repr(values))
    return GoalEnded(code, values)
