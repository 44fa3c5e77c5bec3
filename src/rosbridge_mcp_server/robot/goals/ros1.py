"""ROS 1 goals: actionlib's topics (``<ns>/goal``, ``<ns>/cancel``, ``<ns>/status``, ``<ns>/feedback``,
``<ns>/result``), our goal matched by ``goal_id.id``."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Final

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import ActionError, ConnectionLostError, RequestTimeoutError, RosbridgeError
from rosbridge_mcp_server.robot.goals.actionlib import goal_id_of, publish_cancel
from rosbridge_mcp_server.robot.goals.record import (
    CANCEL_GRACE_SECONDS,
    Goal,
    GoalFeedback,
    require_sendable,
)
from rosbridge_mcp_server.robot.goals.registry import GoalRegistry

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient, Subscription

__all__ = ["ACTIONLIB_SERVER_WAIT", "RESULT_AFTER_STATUS_GRACE", "Progress", "follow", "run", "send_cancel"]

logger = logging.getLogger("rosbridge_mcp_server.robot.goals")

#: How long a ROS 1 goal waits for a first message on ``<ns>/status`` (actionlib servers publish it
#: periodically; roslibpy waits 3 s too).
ACTIONLIB_SERVER_WAIT: Final = 3.0
#: A ROS 1 goal whose status says it finished, but whose result never came, ends after this long.
RESULT_AFTER_STATUS_GRACE: Final = 1.0
#: actionlib's goal states (0..9).
_ROS1: Final = Dialect.for_version(1)


async def run(
    registry: GoalRegistry,
    record: Goal,
    goal: dict[str, Any],
    *,
    timeout: float,
    on_feedback: GoalFeedback | None,
    before_send: Callable[[], None] | None = None,
) -> Goal:
    """Send *goal* on ``<ns>/goal``, follow it until it ends (at *timeout*: cancel it); returns *record*.

    Right before the goal is published, :func:`require_sendable` (with *before_send*) may refuse it."""
    client = registry.client
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    ns = record.action
    types = Dialect.action_names(record.action_type).ros1
    gid = record.goal_id
    # Advertised before we wait for the server, so the bridge's publishers have time to connect to
    # the action server: a message published right after a ROS 1 advertise is often lost.
    await client.advertise(f"{ns}/goal", types.goal)
    await client.advertise(f"{ns}/cancel", types.goal_id)
    queue: asyncio.Queue[tuple[str, Any]] = asyncio.Queue()
    sent = False
    finished = False
    async with (
        client.subscribe(f"{ns}/status", types.status_array, max_queue=10) as status_sub,
        client.subscribe(f"{ns}/feedback", types.feedback, max_queue=100) as feedback_sub,
        client.subscribe(f"{ns}/result", types.result, max_queue=10) as result_sub,
    ):
        wait = max(min(ACTIONLIB_SERVER_WAIT, deadline - loop.time()), 0.0)
        try:
            first_status = await status_sub.get(wait)
        except RequestTimeoutError:
            raise ActionError(
                ns,
                f"no action server at {ns}: no status messages on {ns}/status within {round(wait, 1):g} s "
                f"(is the action server running, and is the type {types.action} right?)",
            ) from None
        pumps = [
            asyncio.create_task(_pump("status", status_sub, queue)),
            asyncio.create_task(_pump("feedback", feedback_sub, queue)),
            asyncio.create_task(_pump("result", result_sub, queue)),
        ]
        queue.put_nowait(("status", first_status))
        seen = Progress()
        try:
            require_sendable(record, deadline - loop.time(), timeout, before_send)
            await client.publish(
                f"{ns}/goal",
                types.goal,
                {"header": {}, "goal_id": {"stamp": {"sec": 0, "nanosec": 0}, "id": gid}, "goal": goal},
            )
            sent = True
            try:
                async with asyncio.timeout_at(deadline):
                    code, result = await follow(queue, record, on_feedback, seen)
                finished = True
                return record.end(code, result)
            except TimeoutError:
                pass
            except ConnectionLostError:
                # The action server keeps running the goal after our connection dropped.
                finished = True  # the cancel is taken care of here, not in `finally`
                reached = await asyncio.shield(send_cancel(client, registry, ns, gid, remember=True))
                raise ConnectionLostError(
                    client.url, f"action goal {gid} on {ns}", goal_cancel="sent" if reached else "pending"
                ) from None
            await asyncio.shield(send_cancel(client, registry, ns, gid))
            try:
                async with asyncio.timeout(CANCEL_GRACE_SECONDS):
                    code, result = await follow(queue, record, on_feedback, seen)
                finished = True
                return record.end(code, result, timed_out=True)
            except (TimeoutError, ConnectionLostError):
                finished = True
                return record.end(seen.code, None, timed_out=True, confirmed=False)
        finally:
            for pump in pumps:
                pump.cancel()
            if sent and not finished:
                await asyncio.shield(send_cancel(client, registry, ns, gid, remember=True))


async def _pump(kind: str, sub: Subscription, queue: asyncio.Queue[tuple[str, Any]]) -> None:
    try:
        while True:
            queue.put_nowait((kind, await sub.get()))
    except RosbridgeError as exc:
        queue.put_nowait(("error", exc))


class Progress:
    """What the status topic has told us about our goal (kept across timeouts)."""

    __slots__ = ("code", "ended_at")

    def __init__(self) -> None:
        self.code = 0  # pending
        self.ended_at: float | None = None


async def follow(
    queue: asyncio.Queue[tuple[str, Any]], record: Goal, on_feedback: GoalFeedback | None, seen: Progress
) -> tuple[int, Any]:
    """Wait for our goal's result, counting its feedback on *record*; returns (status, result)."""
    loop = asyncio.get_running_loop()
    gid = record.goal_id
    while True:
        if seen.ended_at is None:
            kind, msg = await queue.get()
        else:
            try:
                async with asyncio.timeout_at(seen.ended_at + RESULT_AFTER_STATUS_GRACE):
                    kind, msg = await queue.get()
            except TimeoutError:
                # The status array says the goal ended but its result never came (published
                # before our subscription was set up, or lost): end with what we know.
                return seen.code, None
        if kind == "error":
            raise msg
        if not isinstance(msg, dict):
            continue
        if kind == "result":
            status = msg.get("status")
            if goal_id_of(status) == gid:
                code = status.get("status") if isinstance(status, dict) else None
                seen.code = code if isinstance(code, int) else seen.code
                return seen.code, msg.get("result")
        elif kind == "feedback":
            if goal_id_of(msg.get("status")) == gid:
                await record.take_feedback(msg.get("feedback"), on_feedback)
        elif kind == "status":
            for status in msg.get("status_list") or []:
                if goal_id_of(status) == gid and isinstance(status.get("status"), int):
                    seen.code = status["status"]
                    if _ROS1.goal_ended(seen.code) and seen.ended_at is None:
                        seen.ended_at = loop.time()


async def send_cancel(
    client: RosbridgeClient, registry: GoalRegistry, ns: str, goal_id: str, *, remember: bool = False
) -> bool:
    """Publish a cancel on ``<ns>/cancel`` (empty id = every goal); False if it could not be sent.

    With *remember*, a goal whose cancel could not be sent goes to the registry's ledger, which cancels it
    as soon as the connection is back.
    """
    try:
        await publish_cancel(client, ns, goal_id)
    except RosbridgeError as exc:
        if remember and goal_id:
            # Right after the failed send, with no await between: the registry sees the same connection state.
            registry.remember_cut_off(ns, goal_id, 1)
        else:
            logger.warning("Could not send a cancel for goal %r on %s: %s", goal_id, ns, exc)
        return False
    return True
