"""What a goal is while it runs and after it ended: one record for both, in either dialect."""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any, Final, Literal

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import NotSentError

__all__ = [
    "CANCEL_GRACE_SECONDS",
    "LAST_FEEDBACK",
    "UNCONFIRMED_STATUS",
    "CancelReport",
    "CanceledBy",
    "Goal",
    "GoalFeedback",
    "require_sendable",
]

CanceledBy = Literal["timeout", "request_cancelled", "cancel_action", "stop_robot", "estop"]
#: ``Goal.status`` of a goal that timed out and whose end the server never confirmed after the cancel.
UNCONFIRMED_STATUS: Final = "timed out"
#: After a timeout's cancel, how long we wait for the goal's final result.
CANCEL_GRACE_SECONDS: Final = 2.0
#: How many of the last feedback messages a goal keeps.
LAST_FEEDBACK: Final = 5


@dataclass
class Goal:
    """One goal we sent: its identity, its feedback so far, and (once it ended) how it ended.

    Status numbers are kept as the dialect sends them (ROS 2 0..6, ROS 1 0..9); the words differ too
    (a canceled ROS 1 goal ends "preempted" or "recalled").
    """

    goal_id: str
    action: str
    action_type: str
    """As the bridge was given it (the dialect's spelling)."""
    dialect: int
    started: float = field(default_factory=time.monotonic)
    feedback_count: int = 0
    last_feedback: deque[dict[str, Any]] = field(default_factory=lambda: deque(maxlen=LAST_FEEDBACK))
    cancel_requested: bool = False
    #: Who asked for the cancel (cancel_action, or stop_robot's e-stop), for the answer.
    cancel_source: CanceledBy = "cancel_action"
    # How it ended; set by end(). `status` stays "running" until then.
    finished: bool = False
    status_code: int = 0
    status: str = "running"
    succeeded: bool = False
    result: dict[str, Any] | None = None
    canceled_by: CanceledBy | None = None

    async def take_feedback(self, values: Any, listener: GoalFeedback | None) -> None:
        """Count a feedback message (anything but an object counts as ``{}``), keep it, tell *listener*."""
        feedback = values if isinstance(values, dict) else {}
        self.feedback_count += 1
        self.last_feedback.append(feedback)
        if listener is not None:
            maybe = listener(self, feedback)
            if maybe is not None:
                await maybe

    def end(self, code: int, result: Any, *, timed_out: bool = False, confirmed: bool = True) -> Goal:
        """Record how the goal ended (*confirmed*: the robot said so, not only our timeout); returns self."""
        self.finished = True
        self.status_code = code
        dialect = Dialect.for_version(self.dialect)
        self.succeeded = confirmed and dialect.goal_succeeded(code)
        self.status = dialect.goal_status(code) if confirmed else UNCONFIRMED_STATUS
        self.result = result if isinstance(result, dict) else None
        if not self.succeeded:
            if timed_out:
                self.canceled_by = "timeout"
            elif self.cancel_requested:
                self.canceled_by = self.cancel_source
        return self


@dataclass
class CancelReport:
    """What a cancel did."""

    action: str
    dialect: int
    goal_id: str | None
    """The goal asked for, or None for every goal of the action."""
    canceled_ours: list[str]
    """Ids of our running goals a cancel was sent for."""
    unknown_goal_id: bool
    """A goal id was given that is not one of our running goals (a cancel was still sent for it)."""
    goals_canceling: list[str] | None = None
    """ROS 2, cancel-all or a goal given by UUID: goal UUIDs (hex) the action server said it is canceling."""
    refused: str | None = None
    """The bridge's refusal of the cancel (rosbridge-server-rs: "unknown active goal"), if it sent one."""
    note: str | None = None
    return_code: int | None = None
    """ROS 2, a cancel through ``<action>/_action/cancel_goal``: the server's ``return_code`` (0 accepted, 1
    rejected, 2 unknown goal id, 3 goal already ended)."""
    failed: bool = False
    """That service call failed (``note`` says how): the cancel did not reach the action server."""
    no_server: bool = False
    """That service is not on the graph: no action server runs there, so no goal of it runs."""


#: Told of each feedback message of a goal, after the goal counted it (``goal.feedback_count`` is its number).
GoalFeedback = Callable[[Goal, dict[str, Any]], Awaitable[None] | None]


def require_sendable(
    record: Goal, remaining: float, timeout: float, before_send: Callable[[], None] | None
) -> None:
    """Right before *record*'s goal is sent: the send gate (*before_send*) first, then raise
    :class:`NotSentError` if its cancel (cancel_action, stop_robot) came first or its timeout already ran out
    (*remaining* seconds left of *timeout*). A goal refused here was never sent, so nothing needs cancelling.
    """
    if before_send is not None:
        before_send()
    if record.cancel_requested:
        who = "E-STOP on the operator console" if record.cancel_source == "estop" else record.cancel_source
        raise NotSentError(
            f"Goal {record.goal_id} on {record.action} was cancelled by {who} before it was sent, so no goal "
            "was sent."
        )
    if remaining <= 0:
        raise NotSentError(
            f"The timeout of {timeout:g} s for the goal on {record.action} ran out before the goal could be "
            "sent (waiting for the action server), so no goal was sent. Check that the action server runs, "
            "then try again with a longer timeout."
        )
