"""Action goals, one owner: running, observing and cancelling them on ROS 2 (action ops) and ROS 1.

* :mod:`.record`: :class:`Goal`, the one record of a goal (running, then ended), and :class:`CancelReport`;
* :mod:`.registry`: :class:`GoalRegistry`, one per robot session (``robot/session.py`` makes it): the goals
  running now, and the ledger of goals a drop cut off, cancelled once as soon as the connection is back;
* :mod:`.ros2` and :mod:`.ros1`: the two strategies; :mod:`.actionlib`: ROS 1's topics and cancel message.

The client owns what is connection-level: a goal's own lane, the typed events the bridge sends of it, and
which connections a cancel goes on (what the bridge can do is the client's to know).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Final

from rosbridge_mcp_server.errors import GoalTimeoutError, NotConnectedError, ServiceError
from rosbridge_mcp_server.robot.goals import ros1, ros2
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
    from rosbridge_mcp_server.client import RosbridgeClient

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

_ZERO_UUID: Final = [0] * 16


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
        if dialect.version == 1:
            return await ros1.run(
                goals, record, goal, timeout=timeout, on_feedback=on_feedback, before_send=before_send
            )
        try:
            return await ros2.run(
                goals, record, goal, timeout=timeout, on_feedback=on_feedback, before_send=before_send
            )
        except GoalTimeoutError as exc:
            if exc.status is None:
                return record.end(0, None, timed_out=True, confirmed=False)
            return record.end(exc.status, exc.result, timed_out=True)


async def cancel_goals(
    goals: GoalRegistry, action: str, goal_id: str | None = None, *, by: CanceledBy = "cancel_action"
) -> CancelReport:
    """Cancel one goal (by id) or every goal of *action* (ours: those *goals* tracks, and others'); *by*
    names who asked.

    ROS 2: our goals are cancelled by the client on every connection the bridge may need
    (:meth:`RosbridgeClient.cancel_goal`). A goal of another client given by its goal UUID goes to the
    action's own ``<action>/_action/cancel_goal`` service, which every bridge reaches; given by its rosbridge
    id, it is
    cancelled on the main connection, and the report carries the bridge's refusal if it sent one
    (rosbridge-server-rs lets only the starting connection cancel). Every goal: our own cancels plus that
    service with a zero goal id and zero stamp. ROS 1: a ``actionlib_msgs/GoalID`` on ``<ns>/cancel`` (empty
    id and zero stamp cancels every goal).
    """
    client = goals.client
    info = await client.ros_info()
    ns = absolute(action)
    ours = [g for g in goals.running(ns) if goal_id is None or g.goal_id == goal_id]
    for entry in ours:
        entry.cancel_requested = True
        entry.cancel_source = by
    canceled_ours = [g.goal_id for g in ours]
    unknown = goal_id is not None and not ours
    if info.version == 1:
        if not await ros1.send_cancel(client, goals, ns, goal_id or ""):
            raise NotConnectedError(client.url, f"could not publish on {ns}/cancel")
        return CancelReport(ns, 1, goal_id, canceled_ours, unknown)
    for entry in ours:
        if not (await client.cancel_goal(entry.action, entry.goal_id, entry.lane)).sent:
            raise NotConnectedError(client.url, f"could not send the cancel of goal {entry.goal_id}")
    if goal_id is not None and ours:
        return CancelReport(ns, 2, goal_id, canceled_ours, False)
    if goal_id is not None:
        uuid = _uuid_bytes(goal_id)
        if uuid is None:
            refused = await client.cancel_goal_heard(
                ns, goal_id, min(client.request_timeout, _REFUSAL_WAIT_SECONDS)
            )
            return CancelReport(ns, 2, goal_id, [], True, refused=refused)
        report = CancelReport(ns, 2, goal_id, [], True)
        await _cancel_service(client, ns, uuid, report)
        return report
    report = CancelReport(ns, 2, None, canceled_ours, False)
    await _cancel_service(client, ns, _ZERO_UUID, report)
    return report


#: Longest wait for a bridge's refusal of a cancel (it comes before the answer to a call sent after it).
_REFUSAL_WAIT_SECONDS: Final = 3.0


async def _cancel_service(client: RosbridgeClient, ns: str, uuid: list[int], report: CancelReport) -> None:
    """Ask the action server itself (``action_msgs/srv/CancelGoal``): one goal by UUID, or all with zeros."""
    try:
        values = await client.call_service(
            f"{ns}/_action/cancel_goal",
            {"goal_info": {"goal_id": {"uuid": uuid}, "stamp": {"sec": 0, "nanosec": 0}}},
        )
    except ServiceError as exc:
        whose = "goals of other clients" if report.goal_id is None else f"goal {report.goal_id}"
        report.note = f"cancelling {whose} through {ns}/_action/cancel_goal failed: {exc.message}"
        report.no_server = exc.not_in_graph
        report.failed = not report.no_server
        return
    canceling = values.get("goals_canceling") if isinstance(values, dict) else None
    if isinstance(canceling, list):
        report.goals_canceling = [h for h in (uuid_hex(info_) for info_ in canceling) if h is not None]
    return_code = values.get("return_code") if isinstance(values, dict) else None
    report.return_code = return_code if isinstance(return_code, int) else None
    if return_code not in (None, 0):
        # action_msgs/srv/CancelGoal: 1 rejected, 2 unknown goal id, 3 goal terminated.
        meaning = {1: "rejected", 2: "unknown goal id", 3: "goal already ended"}.get(return_code, "")
        report.note = f"the action server answered the cancel with return_code {return_code}" + (
            f" ({meaning})" if meaning else ""
        )


def _uuid_bytes(goal_id: str) -> list[int] | None:
    """The 16 bytes of a goal UUID written as 32 hex digits (dashes allowed), else None (a rosbridge id)."""
    digits = goal_id.strip().replace("-", "")
    if len(digits) != 32:
        return None
    try:
        return list(bytes.fromhex(digits))
    except ValueError:
        return None
