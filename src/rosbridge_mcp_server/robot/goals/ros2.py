"""ROS 2 goals: rosbridge's action ops, each goal on a lane of its own, cancels on both connections.

A goal runs on its own lane so that a bridge that runs it inside the connection's thread (Humble, 2.1.0's
defaults) still hears its cancel on the main connection: rosbridge_suite keeps one goal table per process.
rosbridge-server-rs 0.1.6 lets only the connection that started a goal cancel it ("unknown active goal"
anywhere else) and never holds a connection up behind a goal. So every cancel of our goal goes on both: the
main connection and the goal's own lane. Each bridge acts on one of the two and ignores (rosbridge_suite: in
silence; rosbridge-server-rs: with a ``status``) the other.
"""

from __future__ import annotations

import asyncio
import functools
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import (
    ActionError,
    ConnectionLostError,
    GoalTimeoutError,
)
from rosbridge_mcp_server.robot.goals.record import (
    CANCEL_GRACE_SECONDS,
    Goal,
    GoalFeedback,
    require_sendable,
)
from rosbridge_mcp_server.robot.goals.registry import CANCEL_CONFIRM_SECONDS, GoalRegistry

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import GoalLane, RosbridgeClient

__all__ = ["cancel_on_both", "run", "send_action_goal"]


async def send_action_goal(
    registry: GoalRegistry,
    action: str,
    action_type: str,
    goal: dict[str, Any],
    *,
    timeout: float,
    on_feedback: GoalFeedback | None = None,
    goal_id: str | None = None,
) -> Goal:
    """Send a ROS 2 goal on a lane of its own and wait for its result; returns the goal, ended.

    Raises :class:`ActionError` when the bridge refuses the goal ("No action server available", ...),
    :class:`GoalTimeoutError` after *timeout* (a cancel was sent; the error carries the canceled result if
    it came within a short grace), :class:`ConnectionLostError` when the goal's lane drops (the goal keeps
    running on the robot, so it is cancelled on the main connection, or as soon as a connection is back).
    If the awaiting task is cancelled, the goal is cancelled too before the task ends.
    """
    gid = goal_id if goal_id is not None else registry.client.new_goal_id(action)
    with registry.tracking(Goal(gid, action, Dialect.action_names(action_type).ros2, 2)) as record:
        return await run(registry, record, goal, timeout=timeout, on_feedback=on_feedback)


async def run(
    registry: GoalRegistry,
    record: Goal,
    goal: dict[str, Any],
    *,
    timeout: float,
    on_feedback: GoalFeedback | None,
    before_send: Callable[[], None] | None = None,
) -> Goal:
    """Run *record* (a goal the registry tracks); see :func:`send_action_goal`. Right before the goal is sent
    on its lane, :func:`require_sendable` (with *before_send*) may refuse it."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    action, gid, wire_type = record.action, record.goal_id, record.action_type
    client = registry.client
    session = client.require_session()
    if not session.info.has_action_ops:
        raise ActionError(action, "this bridge runs ROS 1, which has no action ops; use actionlib topics")
    # Whether a cancel on the goal's own lane is read in time depends on the bridge the goal went to.
    in_order = session.goals_block
    owner_only = bool(session.cancel_owner_only or session.info.status_replies)
    what = f"action goal {gid} on {action}"
    lane: GoalLane | None = None
    sent = False
    finished = False
    try:
        lane = await client.open_goal_lane(gid, what, max(deadline - loop.time(), 0.05))
        record.cancel_on_owner = functools.partial(lane.try_cancel, action)
        require_sendable(record, deadline - loop.time(), timeout, before_send)
        await lane.send_goal(action, wire_type, goal)
        sent = True
        try:
            async with asyncio.timeout_at(deadline):
                frame = await _follow(lane, record, on_feedback)
        except TimeoutError:
            await asyncio.shield(_cancel_quietly(client, registry, record, in_order, owner_only))
            late: dict[str, Any] | None = None
            try:
                async with asyncio.timeout(CANCEL_GRACE_SECONDS):
                    late = await _follow(lane, record, None)
            except (TimeoutError, ConnectionLostError, ActionError):
                pass
            last = record.last_feedback[-1] if record.last_feedback else None
            if late is None:
                raise GoalTimeoutError(action, gid, timeout, feedback=last) from None
            finished = True
            # The cancel reached it after all (a lane's cancel on a bridge that handles goals apart).
            registry.ended(gid)
            status, values = _result(action, late)
            raise GoalTimeoutError(
                action, gid, timeout, status=status, result=values, feedback=last
            ) from None
        except ConnectionLostError:
            # The goal's lane dropped; the goal itself keeps running on the robot.
            finished = True  # the cancel is taken care of here, not in `finally`
            reached = await asyncio.shield(_cancel_after_drop(client, registry, record))
            raise ConnectionLostError(
                client.url, what, goal_cancel="sent" if reached else "pending"
            ) from None
        finished = True
        status, values = _result(action, frame)
        return record.end(status, values)
    finally:
        try:
            if sent and not finished:
                await asyncio.shield(_cancel_quietly(client, registry, record, in_order, owner_only))
        finally:
            # Even if we are cancelled again while the cancel is being sent.
            if lane is not None:
                lane.close()


async def _follow(lane: GoalLane, record: Goal, on_feedback: GoalFeedback | None) -> dict[str, Any]:
    """Feedback until the result frame, which is returned."""
    while True:
        op, frame = await lane.next()
        if op == "action_result":
            return frame
        if op == "action_feedback":
            await record.take_feedback(frame.get("values"), on_feedback)
        elif op == "status" and not record.cancel_requested:
            # rosbridge-server-rs refuses a goal with an error status (rosbridge_suite with an action_result).
            # After our own cancel, one may only say the goal was already over: its result still comes.
            raise ActionError(record.action, str(frame.get("msg")))


async def cancel_on_both(client: RosbridgeClient, record: Goal) -> tuple[bool, bool]:
    """Send *record*'s cancel on the main connection and on the goal's own lane; whether each was sent.

    The main connection first: on an in-order bridge the goal's own lane is blocked by the goal. The lane's
    copy is for bridges that let only the starting connection cancel (rosbridge-server-rs).
    """
    session = client.session
    if session is not None and session.info.status_replies:
        # Such a bridge refuses the main connection's copy with an error status: expected, so not logged.
        conn = session.connection
        conn.expect(record.goal_id, f"the refusal of goal {record.goal_id}'s cancel", _REFUSAL_SECONDS)
        asyncio.get_running_loop().call_later(_REFUSAL_SECONDS, conn.forget, record.goal_id)
    on_main = session is not None and await session.try_cancel_goal(record.action, record.goal_id)
    if on_main:
        client.unhandled_acts = True
    on_lane = record.cancel_on_owner is not None and await record.cancel_on_owner()
    return on_main, on_lane


#: How long the main connection takes a refusal of our own goal's cancel as expected (not logged).
_REFUSAL_SECONDS = 5.0


async def _cancel_quietly(
    client: RosbridgeClient, registry: GoalRegistry, record: Goal, in_order: bool, owner_only: bool
) -> None:
    on_main, on_lane = await cancel_on_both(client, record)
    # close() has already sent cancels for every running goal.
    if client.closed:
        return
    # An in-order bridge (2.1.0's and Humble's defaults) reads a lane's cancel only after the goal ended;
    # an owner-only bridge (rosbridge-server-rs) acts only on the lane's.
    if not ((on_main and not owner_only) or (on_lane and not in_order)):
        registry.remember_cut_off(record.action, record.goal_id, 2)


async def _cancel_after_drop(client: RosbridgeClient, registry: GoalRegistry, record: Goal) -> bool:
    """Cancel a goal whose lane dropped on the main connection; True if the bridge surely read it.

    A drop of the whole bridge closes the main connection too, but its reader may not have noticed
    yet: a cancel written then is lost, so it counts only once a ping on the same connection is answered.
    Otherwise the goal is remembered and cancelled on the next connection.
    """
    session = client.session
    if (
        session is not None
        and await session.try_cancel_goal(record.action, record.goal_id)
        and await session.confirm(min(CANCEL_CONFIRM_SECONDS, client.request_timeout))
    ):
        return True
    if not client.closed:
        registry.remember_cut_off(record.action, record.goal_id, 2, stale=session)
    return False


#: ``action_msgs/GoalStatus`` codes a goal ends with: SUCCEEDED, CANCELED, ABORTED.
_TERMINAL = frozenset({4, 5, 6})


def _result(action: str, frame: dict[str, Any]) -> tuple[int, Any]:
    values = frame.get("values")
    status = frame.get("status")
    code = status if isinstance(status, int) and not isinstance(status, bool) else 0
    if frame.get("result") is False and not (code in _TERMINAL and isinstance(values, dict)):
        # rosbridge_suite: result false means the goal never ran (values is its error text).
        # rosbridge-server-rs 0.1.6 also says false for a goal that ended CANCELED or ABORTED, with its
        # status and result fields: that goal ran and ended, and is reported as such.
        raise ActionError(action, values if isinstance(values, str) else repr(values))
    return code, values
