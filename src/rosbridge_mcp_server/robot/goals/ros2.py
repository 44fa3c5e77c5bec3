"""ROS 2 goals: rosbridge's action ops, each goal on a lane of its own, cancelled by the client.

A goal runs on its own lane so that a bridge that runs it inside the connection's thread (Humble, 2.1.0's
defaults) still hears its cancel on the main connection. Which connections a cancel goes on, and whether it
surely reaches the goal, is the client's (:meth:`RosbridgeClient.cancel_goal`); what the bridge says of the
goal arrives as typed events (feedback, its end, a goal that never ran, a refusal). This module decides what
a goal means: its timeout, its result, what a drop leaves running.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.client import (
    Dialect,
    GoalEnded,
    GoalFeedbackEvent,
    GoalNeverRan,
    GoalStatusRefusal,
)
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

__all__ = ["run", "send_action_goal"]


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
    if not session.capabilities.action_ops:
        raise ActionError(action, "this bridge runs ROS 1, which has no action ops; use actionlib topics")
    what = f"action goal {gid} on {action}"
    lane: GoalLane | None = None
    sent = False
    finished = False
    try:
        lane = await client.open_goal_lane(action, gid, what, max(deadline - loop.time(), 0.05))
        record.lane = lane
        require_sendable(record, deadline - loop.time(), timeout, before_send)
        await lane.send_goal(wire_type, goal)
        sent = True
        try:
            async with asyncio.timeout_at(deadline):
                ended = await _follow(lane, record, on_feedback)
        except TimeoutError:
            await asyncio.shield(_cancel_quietly(client, registry, record))
            late: GoalEnded | GoalNeverRan | None = None
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
            if isinstance(late, GoalNeverRan):
                raise ActionError(action, late.text) from None
            raise GoalTimeoutError(
                action, gid, timeout, status=late.status, result=late.values, feedback=last
            ) from None
        except ConnectionLostError:
            # The goal's lane dropped; the goal itself keeps running on the robot.
            finished = True  # the cancel is taken care of here, not in `finally`
            reached = await asyncio.shield(_cancel_after_drop(client, registry, record))
            raise ConnectionLostError(
                client.url, what, goal_cancel="sent" if reached else "pending"
            ) from None
        finished = True
        if isinstance(ended, GoalNeverRan):
            # rosbridge_suite: no action server, rejected, an unknown type; the goal never ran.
            raise ActionError(action, ended.text)
        return record.end(ended.status, ended.values)
    finally:
        try:
            if sent and not finished:
                await asyncio.shield(_cancel_quietly(client, registry, record))
        finally:
            # Even if we are cancelled again while the cancel is being sent.
            if lane is not None:
                lane.close()


async def _follow(lane: GoalLane, record: Goal, on_feedback: GoalFeedback | None) -> GoalEnded | GoalNeverRan:
    """Feedback until the bridge says how the goal ended (or that it never ran), which is returned."""
    while True:
        event = await lane.next()
        if isinstance(event, GoalEnded | GoalNeverRan):
            return event
        if isinstance(event, GoalFeedbackEvent):
            await record.take_feedback(event.values, on_feedback)
        elif isinstance(event, GoalStatusRefusal) and not record.cancel_requested:
            # A bridge that refuses a goal with an error status (others say so with an action_result).
            # After our own cancel, one may only say the goal was already over: its end still comes.
            raise ActionError(record.action, event.text)


async def _cancel_quietly(client: RosbridgeClient, registry: GoalRegistry, record: Goal) -> None:
    cancel = await client.cancel_goal(record.action, record.goal_id, record.lane)
    # close() has already sent cancels for every running goal.
    if client.closed:
        return
    if not cancel.reaches:
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
