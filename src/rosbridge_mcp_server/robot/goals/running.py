"""Running one goal, in either dialect: what it means (its timeout, its record, what a drop leaves running).

The client sends the goal and hands out its :class:`GoalHandle` (``client.start_goal``): what the bridge says
of the goal as typed events (feedback, its end, a goal that never ran, a refusal), and its cancel, which goes
on every connection the bridge may need and is kept for the next connection when none surely reaches it. This
module decides what those events mean for the goal's record, and when to cancel.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any, NoReturn

from rosbridge_mcp_server.client import (
    Dialect,
    GoalEnded,
    GoalFeedbackEvent,
    GoalHandle,
    GoalNeverRan,
    GoalStatusRefusal,
)
from rosbridge_mcp_server.errors import ActionError, ConnectionLostError, GoalTimeoutError
from rosbridge_mcp_server.robot.goals.record import (
    CANCEL_GRACE_SECONDS,
    Goal,
    GoalFeedback,
    require_sendable,
)
from rosbridge_mcp_server.robot.goals.registry import GoalRegistry

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
    """Send a ROS 2 goal (on a lane of its own) and wait for its result; returns the goal, ended.

    Raises :class:`ActionError` when the bridge refuses the goal ("No action server available", ...),
    :class:`GoalTimeoutError` after *timeout* (a cancel was sent; the error carries the canceled result if
    it came within a short grace), :class:`ConnectionLostError` when the goal's lane drops (the goal keeps
    running on the robot, so it is cancelled on the main connection, or as soon as a connection is back).
    If the awaiting task is cancelled, the goal is cancelled too before the task ends.
    """
    client = registry.client
    if not (await client.capabilities()).action_ops:
        raise ActionError(action, "this bridge runs ROS 1, which has no action ops; use actionlib topics")
    gid = goal_id if goal_id is not None else client.new_goal_id(action)
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
    """Run *record* (a goal the registry tracks) until it ends; see :func:`send_action_goal`. Right before
    the goal is sent, :func:`require_sendable` (with *before_send*) may refuse it.

    At *timeout* the goal is cancelled; a goal whose end did not come within a short grace after is ended
    unconfirmed (with its last status) and :class:`GoalTimeoutError` says so.
    """
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    client = registry.client
    handle = await client.start_goal(
        record.action,
        record.action_type,
        goal,
        goal_id=record.goal_id,
        timeout=max(deadline - loop.time(), 0.05),
        check=lambda: require_sendable(record, deadline - loop.time(), timeout, before_send),
    )
    finished = False
    try:
        try:
            async with asyncio.timeout_at(deadline):
                ended = await _follow(handle, record, on_feedback)
        except TimeoutError:
            finished = True  # the cancel is taken care of here, not in `finally`
            await _after_timeout(handle, record, timeout)
        except ConnectionLostError:
            # The goal's connection dropped; the goal itself keeps running on the robot.
            finished = True
            cancel = await asyncio.shield(handle.cancel())
            what = f"action goal {record.goal_id} on {record.action}"
            raise ConnectionLostError(
                client.url, what, goal_cancel="sent" if cancel.reaches else "pending"
            ) from None
        finished = True
        if isinstance(ended, GoalNeverRan):
            # rosbridge_suite: no action server, rejected, an unknown type; the goal never ran.
            raise ActionError(record.action, ended.text)
        return record.end(ended.status, ended.values)
    finally:
        try:
            if not finished:
                await asyncio.shield(handle.cancel())
        finally:
            # Even if we are cancelled again while the cancel is being sent.
            await asyncio.shield(handle.aclose())


async def _after_timeout(handle: GoalHandle, record: Goal, timeout: float) -> NoReturn:
    """Cancel a goal that ran out of time and wait a short grace for its end: :class:`GoalTimeoutError` with
    it, or (none came) with the record ended unconfirmed."""
    await asyncio.shield(handle.cancel())
    late: GoalEnded | GoalNeverRan | None = None
    try:
        async with asyncio.timeout(CANCEL_GRACE_SECONDS):
            late = await _follow(handle, record, None)
    except (TimeoutError, ConnectionLostError, ActionError):
        pass
    last = record.last_feedback[-1] if record.last_feedback else None
    if late is None:
        record.end(handle.last_status, None, timed_out=True, confirmed=False)
        raise GoalTimeoutError(record.action, record.goal_id, timeout, feedback=last) from None
    if isinstance(late, GoalNeverRan):
        raise ActionError(record.action, late.text) from None
    raise GoalTimeoutError(
        record.action, record.goal_id, timeout, status=late.status, result=late.values, feedback=last
    ) from None


async def _follow(
    handle: GoalHandle, record: Goal, on_feedback: GoalFeedback | None
) -> GoalEnded | GoalNeverRan:
    """Feedback until the bridge says how the goal ended (or that it never ran), which is returned."""
    while True:
        event = await handle.next()
        if isinstance(event, GoalEnded | GoalNeverRan):
            return event
        if isinstance(event, GoalFeedbackEvent):
            await record.take_feedback(event.values, on_feedback)
        elif isinstance(event, GoalStatusRefusal) and not record.cancel_requested:
            # A bridge that refuses a goal with an error status (others say so with an action_result).
            # After our own cancel, one may only say the goal was already over: its end still comes.
            raise ActionError(record.action, event.text)
