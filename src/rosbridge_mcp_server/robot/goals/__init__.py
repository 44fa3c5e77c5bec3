"""Action goals, what they mean: running, observing and cancelling them on ROS 2 (action ops) and ROS 1.

* :mod:`.record`: :class:`Goal`, the one record of a goal (running, then ended), and :class:`CancelReport`;
* :mod:`.registry`: :class:`GoalRegistry`, one per robot session (``robot/session.py`` makes it): the goals
  running now, and those a publish or a service call started (:mod:`.caused`), which the stops read;
* :mod:`.running`: one goal run to its end, in either dialect (its timeout, what its events mean);
* :mod:`.stopping`: what a stop cancels.

The client owns what is connection-level: each goal's :class:`GoalHandle` (its own lane on ROS 2, actionlib's
topics on ROS 1, its events as typed events), every cancel it sends and on which connections, and the goals a
drop cut off (cancelled once a connection is back). :func:`cancel_goals` is the one cancel of this layer.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Final

from rosbridge_mcp_server.errors import GoalTimeoutError, NotConnectedError, ServiceError
from rosbridge_mcp_server.robot.goals import running
from rosbridge_mcp_server.robot.goals.caused import uuid_hex
from rosbridge_mcp_server.robot.goals.record import (
    CANCEL_GRACE_SECONDS,
    UNCONFIRMED_STATUS,
    CanceledBy,
    CancelReport,
    Goal,
    GoalFeedback,
)
from rosbridge_mcp_server.robot.goals.registry import GoalRegistry
from rosbridge_mcp_server.robot.names import absolute

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import OthersCancel

__all__ = [
    "CANCEL_GRACE_SECONDS",
    "UNCONFIRMED_STATUS",
    "CancelReport",
    "CanceledBy",
    "Goal",
    "GoalFeedback",
    "GoalRegistry",
    "cancel_goals",
    "run_goal",
]

#: Longest wait for a bridge's refusal of a cancel (it comes before the answer to a call sent after it).
_REFUSAL_WAIT_SECONDS: Final = 3.0


async def run_goal(
    goals: GoalRegistry,
    action: str,
    action_type: str,
    goal: dict[str, Any],
    *,
    timeout: float,
    on_feedback: GoalFeedback | None = None,
    goal_id: str | None = None,
    before_send: Callable[[], None] | None = None,
) -> Goal:
    """Send a goal through the client of *goals* and wait (up to *timeout* seconds) for it to end; returns
    the goal, ended (*goals* tracks it while it runs).

    On timeout the goal is cancelled and it says ``canceled_by="timeout"``; if the task running this is
    cancelled, the goal is cancelled before the cancellation propagates. Raises :class:`ActionError` when the
    goal cannot be sent (no action server, refused by the bridge), and :class:`ConnectionLostError` when the
    connection drops: the goal keeps running on the robot, so it is cancelled as soon as a connection is back
    (``goal_cancel`` says whether that already happened).

    The goal is tracked before anything of it is sent. Right before the goal itself goes out,
    *before_send* (the send gate) is called, and a goal whose cancel or timeout came first is not sent:
    :class:`NotSentError` says which (see :func:`~.record.require_sendable`).
    """
    client = goals.client
    dialect = await client.dialect()
    action = absolute(action)
    gid = goal_id if goal_id is not None else client.new_goal_id(action)

    wire_type = dialect.action_type(action_type)
    with goals.tracking(Goal(gid, action, wire_type, dialect.version)) as record:
        try:
            return await running.run(
                goals, record, goal, timeout=timeout, on_feedback=on_feedback, before_send=before_send
            )
        except GoalTimeoutError as exc:
            if exc.status is None:
                return record if record.finished else record.end(0, None, timed_out=True, confirmed=False)
            return record.end(exc.status, exc.result, timed_out=True)


async def cancel_goals(
    goals: GoalRegistry, action: str, goal_id: str | None = None, *, by: CanceledBy = "cancel_action"
) -> CancelReport:
    """Cancel one goal (by id) or every goal of *action* (ours: those *goals* tracks, and others'); *by*
    names who asked.

    Our goals are cancelled through their handles (the client sends each on every connection the bridge may
    need). Others' (a goal id not ours, or every goal) through the client's cancel: ROS 2 a goal UUID or
    every goal through the action's own ``<action>/_action/cancel_goal`` service, which every bridge reaches
    (every goal: a zero goal id and zero stamp), a rosbridge id on the main connection with the bridge's
    refusal in the report if it sent one (rosbridge-server-rs lets only the starting connection cancel);
    ROS 1 a ``actionlib_msgs/GoalID`` on ``<ns>/cancel`` (an empty id cancels every goal).
    """
    client = goals.client
    version = (await client.ros_info()).version
    ns = absolute(action)
    ours = [g for g in goals.running(ns) if goal_id is None or g.goal_id == goal_id]
    for entry in ours:
        entry.cancel_requested = True
        entry.cancel_source = by
    report = CancelReport(ns, version, goal_id, [g.goal_id for g in ours], goal_id is not None and not ours)
    if version == 2 or (ours and goal_id is not None):
        for entry in ours:
            # A goal without a handle is not sent yet: its cancel_requested keeps it from being sent.
            handle = client.goals.handle(entry.goal_id)
            if handle is not None and not (await handle.cancel()).sent:
                raise NotConnectedError(client.url, f"could not send the cancel of goal {entry.goal_id}")
        if ours and goal_id is not None:
            return report
    wait = min(client.request_timeout, _REFUSAL_WAIT_SECONDS)
    try:
        _read_answer(report, await client.goals.cancel(ns, goal_id, timeout=wait))
    except ServiceError as exc:
        whose = "goals of other clients" if goal_id is None else f"goal {goal_id}"
        report.note = f"cancelling {whose} through {ns}/_action/cancel_goal failed: {exc.message}"
        report.no_server = exc.not_in_graph
        report.failed = not report.no_server
    return report


def _read_answer(report: CancelReport, answer: OthersCancel) -> None:
    """What the bridge or the action server answered a cancel of others' goals, into *report*."""
    report.refused = answer.refused
    if answer.goals_canceling is not None:
        report.goals_canceling = [h for h in (uuid_hex(info_) for info_ in answer.goals_canceling) if h]
    report.return_code = answer.return_code
    if answer.return_code not in (None, 0):
        # action_msgs/srv/CancelGoal: 1 rejected, 2 unknown goal id, 3 goal already ended.
        meaning = {1: "rejected", 2: "unknown goal id", 3: "goal already ended"}.get(answer.return_code, "")
        report.note = f"the action server answered the cancel with return_code {answer.return_code}" + (
            f" ({meaning})" if meaning else ""
        )
