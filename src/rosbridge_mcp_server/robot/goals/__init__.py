"""Action goals, one owner: running, observing and cancelling them on ROS 2 (action ops) and ROS 1.

* :mod:`.record`: :class:`Goal`, the one record of a goal (running, then ended), and :class:`CancelReport`;
* :mod:`.registry`: one :class:`GoalRegistry` per client: the goals running now, and the ledger of goals a
  drop cut off, cancelled once as soon as the connection is back;
* :mod:`.ros2` and :mod:`.ros1`: the two strategies; :mod:`.actionlib`: ROS 1's topics and cancel message.

The client only provides what is connection-level: a goal's own lane and the cancel op.
"""

from __future__ import annotations

import base64
import binascii
import contextlib
from typing import TYPE_CHECKING, Any, Final

from rosbridge_mcp_server.errors import GoalTimeoutError, NotConnectedError, ServiceError
from rosbridge_mcp_server.robot.goals import ros1, ros2
from rosbridge_mcp_server.robot.goals.record import (
    CANCEL_GRACE_SECONDS,
    UNCONFIRMED_STATUS,
    CanceledBy,
    CancelReport,
    Goal,
    GoalFeedback,
)
from rosbridge_mcp_server.robot.goals.registry import GoalRegistry, goals_of
from rosbridge_mcp_server.robot.names import absolute
from rosbridge_mcp_server.wire.dialect import action_type_names

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
    "goals_of",
    "run_goal",
    "running_goals",
]

_ZERO_UUID: Final = [0] * 16


def running_goals(client: RosbridgeClient, action: str | None = None) -> list[Goal]:
    """Goals *client* has running now (all, or those of *action*)."""
    return goals_of(client).running(action)


async def run_goal(
    client: RosbridgeClient,
    action: str,
    action_type: str,
    goal: dict[str, Any],
    *,
    timeout: float,
    on_feedback: GoalFeedback | None = None,
    goal_id: str | None = None,
) -> Goal:
    """Send a goal and wait (up to *timeout* seconds) for it to end; returns the goal, ended.

    On timeout the goal is cancelled and it says ``canceled_by="timeout"``; if the task running this is
    cancelled, the goal is cancelled before the cancellation propagates. Raises :class:`ActionError` when the
    goal cannot be sent (no action server, refused by the bridge), and :class:`ConnectionLostError` when the
    connection drops: the goal keeps running on the robot, so it is cancelled as soon as a connection is back
    (``goal_cancel`` says whether that already happened).
    """
    info = await client.ros_info()
    action = absolute(action)
    gid = goal_id if goal_id is not None else client.new_goal_id(action)

    wire_type = action_type_names(action_type).for_version(info.version)
    with goals_of(client).tracking(Goal(gid, action, wire_type, info.version)) as record:
        if info.version == 1:
            return await ros1.run(client, record, goal, timeout=timeout, on_feedback=on_feedback)
        try:
            return await ros2.run(client, record, goal, timeout=timeout, on_feedback=on_feedback)
        except GoalTimeoutError as exc:
            if exc.status is None:
                return record.end(0, None, timed_out=True, confirmed=False)
            return record.end(exc.status, exc.result, timed_out=True)


async def cancel_goals(client: RosbridgeClient, action: str, goal_id: str | None = None) -> CancelReport:
    """Cancel one goal (by our id) or every goal of *action* (ours and others').

    ROS 2: ``cancel_action_goal`` for our goals (on the main connection, so it reaches a goal
    running on its own lane), plus, to cancel every goal, the action's hidden
    ``<action>/_action/cancel_goal`` service with a zero goal id and zero stamp. ROS 1: a
    ``actionlib_msgs/GoalID`` on ``<ns>/cancel`` (empty id and zero stamp cancels every goal).
    """
    info = await client.ros_info()
    ns = absolute(action)
    registry = goals_of(client)
    ours = [g for g in registry.running(ns) if goal_id is None or g.goal_id == goal_id]
    for entry in ours:
        entry.cancel_requested = True
    canceled_ours = [g.goal_id for g in ours]
    unknown = goal_id is not None and not ours
    if info.version == 1:
        if not await ros1.send_cancel(client, registry, ns, goal_id or ""):
            raise NotConnectedError(client.url, f"could not publish on {ns}/cancel")
        return CancelReport(ns, 1, goal_id, canceled_ours, unknown)
    if goal_id is not None:
        await client.cancel_action_goal(ns, goal_id)
        return CancelReport(ns, 2, goal_id, canceled_ours, unknown)
    for entry in ours:
        await client.cancel_action_goal(ns, entry.goal_id)
    report = CancelReport(ns, 2, None, canceled_ours, False)
    try:
        values = await client.call_service(
            f"{ns}/_action/cancel_goal",
            {"goal_info": {"goal_id": {"uuid": _ZERO_UUID}, "stamp": {"sec": 0, "nanosec": 0}}},
        )
    except ServiceError as exc:
        report.note = f"cancelling goals of other clients failed: {exc.message}"
        return report
    canceling = values.get("goals_canceling") if isinstance(values, dict) else None
    if isinstance(canceling, list):
        report.goals_canceling = [h for h in (_uuid_hex(info_) for info_ in canceling) if h is not None]
    return_code = values.get("return_code") if isinstance(values, dict) else None
    if return_code not in (None, 0):
        # action_msgs/srv/CancelGoal: 1 rejected, 2 unknown goal id, 3 goal terminated.
        report.note = f"the action server answered the cancel with return_code {return_code}"
    return report


def _uuid_hex(goal_info: Any) -> str | None:
    if not isinstance(goal_info, dict):
        return None
    goal_id = goal_info.get("goal_id")
    uuid = goal_id.get("uuid") if isinstance(goal_id, dict) else None
    # uint8[16] arrives base64-encoded from rosbridge's JSON mode; accept a list of ints too.
    if isinstance(uuid, str):
        with contextlib.suppress(binascii.Error, ValueError):
            return base64.b64decode(uuid, validate=True).hex()
        return uuid
    if isinstance(uuid, list) and all(isinstance(b, int) and 0 <= b < 256 for b in uuid):
        return bytes(uuid).hex()
    return None
