"""A ROS 1 goal over actionlib's topics, read as the same typed events as a ROS 2 goal (``wire/goals.py``).

ROS 1 rosbridge has no action ops, so a goal goes through five topics under the action's namespace: the client
publishes ``<ns>/goal`` and ``<ns>/cancel`` and listens on ``<ns>/status``, ``<ns>/feedback`` and
``<ns>/result``, matching its goal by ``goal_id.id``. Which connections a cancel goes on, and the goals a drop
cut off, are :mod:`.goals`'; what a goal means (its timeout, its record) is ``robot/goals``'.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable, Coroutine
from typing import Any, Final, Protocol

from rosbridge_mcp_server.client.dialect import Dialect
from rosbridge_mcp_server.client.session import BridgeSession
from rosbridge_mcp_server.client.subscription import Subscription
from rosbridge_mcp_server.errors import ActionError, RequestTimeoutError, RosbridgeError
from rosbridge_mcp_server.wire.goals import GoalEnded, GoalEvent, GoalFeedbackEvent

__all__ = [
    "ACTIONLIB_SERVER_WAIT",
    "CANCEL_TYPE",
    "RESULT_AFTER_STATUS_GRACE",
    "ActionlibGoal",
    "GoalsHost",
    "Progress",
    "cancel_message",
    "goal_id_of",
    "next_event",
]

#: How long a ROS 1 goal waits for a first message on ``<ns>/status`` (actionlib servers publish it
#: periodically; roslibpy waits 3 s too).
ACTIONLIB_SERVER_WAIT: Final = 3.0
#: A ROS 1 goal whose status says it finished, but whose result never came, ends after this long.
RESULT_AFTER_STATUS_GRACE: Final = 1.0
#: The message on ``<ns>/cancel``: a goal id and a stamp (both empty/zero: every goal).
CANCEL_TYPE: Final = "actionlib_msgs/GoalID"
#: actionlib's goal states (0..9).
_ROS1: Final = Dialect.for_version(1)


class GoalsHost(Protocol):
    """What a client's goals need of it (:class:`RosbridgeClient` is one): a ROS 1 goal, its topics."""

    url: str
    request_timeout: float
    unhandled_acts: bool

    @property
    def closed(self) -> bool: ...
    @property
    def session(self) -> BridgeSession | None: ...
    def require_session(self) -> BridgeSession: ...
    def new_goal_id(self, action: str) -> str: ...
    def run_in_background(self, coro: Coroutine[Any, Any, Any], name: str) -> asyncio.Task[Any]: ...
    async def wait_disconnected(self, timeout: float) -> None: ...
    async def advertise(self, topic: str, msg_type: str) -> None: ...
    async def publish(
        self, topic: str, msg_type: str, msg: dict[str, Any], *, session: BridgeSession | None = None
    ) -> None: ...
    def subscribe(
        self, topic: str, msg_type: str | None = None, *, max_queue: int = 1000
    ) -> Subscription: ...
    async def call_service(self, service: str, args: dict[str, Any]) -> Any: ...


def cancel_message(goal_id: str) -> dict[str, Any]:
    """The ``actionlib_msgs/GoalID`` that cancels *goal_id* (an empty id: every goal of the action)."""
    return {"stamp": {"sec": 0, "nanosec": 0}, "id": goal_id}


def goal_id_of(status: Any) -> str | None:
    """The ``goal_id.id`` of an ``actionlib_msgs/GoalStatus``, or None."""
    if isinstance(status, dict):
        goal_id = status.get("goal_id")
        if isinstance(goal_id, dict):
            gid = goal_id.get("id")
            return gid if isinstance(gid, str) else None
    return None


class Progress:
    """What the status topic has told us about our goal (kept across timeouts)."""

    __slots__ = ("code", "ended_at")

    def __init__(self) -> None:
        self.code = 0  # pending
        self.ended_at: float | None = None


class ActionlibGoal:
    """One ROS 1 goal's topics: subscribed and the server heard from by :meth:`open`, the goal published by
    :meth:`send`, what the server says of it read by :meth:`next`."""

    def __init__(self, topics: GoalsHost, action: str, action_type: str, goal_id: str) -> None:
        self._topics = topics
        self.action = action
        self.goal_id = goal_id
        self.types = Dialect.action_names(action_type).ros1
        self.progress = Progress()
        self._queue: asyncio.Queue[tuple[str, Any]] = asyncio.Queue()
        self._stack = contextlib.AsyncExitStack()
        self._pumps: list[asyncio.Task[None]] = []

    async def open(self, timeout: float) -> None:
        """Advertise, subscribe, and wait (at most *timeout*, and :data:`ACTIONLIB_SERVER_WAIT`) for the
        server's status: :class:`ActionError` when none comes (no action server)."""
        ns, types = self.action, self.types
        # Advertised before we wait for the server, so the bridge's publishers have time to connect to
        # the action server: a message published right after a ROS 1 advertise is often lost.
        await self._topics.advertise(f"{ns}/goal", types.goal)
        await self._topics.advertise(f"{ns}/cancel", types.goal_id)
        subs = {}
        for kind, msg_type, queue in (
            ("status", types.status_array, 10),
            ("feedback", types.feedback, 100),
            ("result", types.result, 10),
        ):
            sub = self._topics.subscribe(f"{ns}/{kind}", msg_type, max_queue=queue)
            subs[kind] = await self._stack.enter_async_context(sub)
        wait = max(min(ACTIONLIB_SERVER_WAIT, timeout), 0.0)
        try:
            first_status = await subs["status"].get(wait)
        except RequestTimeoutError:
            raise ActionError(
                ns,
                f"no action server at {ns}: no status messages on {ns}/status within {round(wait, 1):g} s "
                f"(is the action server running, and is the type {types.action} right?)",
            ) from None
        self._pumps = [asyncio.create_task(_pump(kind, sub, self._queue)) for kind, sub in subs.items()]
        self._queue.put_nowait(("status", first_status))

    async def send(self, goal: dict[str, Any], check: Callable[[], None] | None) -> None:
        """Publish the goal on ``<ns>/goal`` (*check*, the send gate, right before)."""
        if check is not None:
            check()
        stamp = {"stamp": {"sec": 0, "nanosec": 0}, "id": self.goal_id}
        await self._topics.publish(
            f"{self.action}/goal", self.types.goal, {"header": {}, "goal_id": stamp, "goal": goal}
        )

    async def next(self) -> GoalEvent:
        """The next thing the server said of the goal (feedback or its end)."""
        return await next_event(self._queue, self.goal_id, self.progress)

    async def aclose(self) -> None:
        """Stop listening: the pumps and the three subscriptions."""
        for pump in self._pumps:
            pump.cancel()
        with contextlib.suppress(RosbridgeError):
            await self._stack.aclose()


async def _pump(kind: str, sub: Subscription, queue: asyncio.Queue[tuple[str, Any]]) -> None:
    try:
        while True:
            queue.put_nowait((kind, await sub.get()))
    except RosbridgeError as exc:
        queue.put_nowait(("error", exc))


async def next_event(queue: asyncio.Queue[tuple[str, Any]], goal_id: str, seen: Progress) -> GoalEvent:
    """The next feedback of goal *goal_id*, or its end (its result, else the status that said it ended once
    :data:`RESULT_AFTER_STATUS_GRACE` passed without one); *seen* keeps the last status across calls."""
    loop = asyncio.get_running_loop()
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
                return GoalEnded(seen.code, None)
        if kind == "error":
            raise msg
        if not isinstance(msg, dict):
            continue
        if kind == "result":
            status = msg.get("status")
            if goal_id_of(status) == goal_id:
                code = status.get("status") if isinstance(status, dict) else None
                seen.code = code if isinstance(code, int) else seen.code
                return GoalEnded(seen.code, msg.get("result"))
        elif kind == "feedback":
            if goal_id_of(msg.get("status")) == goal_id:
                return GoalFeedbackEvent(msg.get("feedback"))
        elif kind == "status":
            for status in msg.get("status_list") or []:
                if goal_id_of(status) == goal_id and isinstance(status.get("status"), int):
                    seen.code = status["status"]
                    if _ROS1.goal_ended(seen.code) and seen.ended_at is None:
                        seen.ended_at = loop.time()
