"""``RosbridgeClient``: one shared WebSocket, background reconnects, lanes for in-order bridges."""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import logging
import random
import time
from collections.abc import Awaitable, Callable, Coroutine
from dataclasses import dataclass, field
from types import TracebackType
from typing import Any, Self

from rosbridge_mcp_server.client._connection import Connection, GoalStream, open_connection
from rosbridge_mcp_server.client._lanes import LanePool
from rosbridge_mcp_server.client._subscription import Subscription
from rosbridge_mcp_server.errors import (
    ActionError,
    ConnectionLostError,
    GoalTimeoutError,
    NotConnectedError,
    RequestTimeoutError,
    RosbridgeError,
    ServiceError,
)
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.dialect import (
    RosInfo,
    action_type_names,
    adapt_message,
    goal_status_name,
    normalize_type,
)

__all__ = ["ActionResult", "GoalHandle", "OrphanedGoal", "RosbridgeClient"]

logger = logging.getLogger("rosbridge_mcp_server.client")

#: After a goal's deadline we send a cancel and wait this long for the canceled result.
CANCEL_GRACE_SECONDS = 2.0
#: rosbridge's node name in rosbridge_websocket.launch (ROS 1 0.11); used to tell ROS 1 without rosapi.
ROS1_BRIDGE_NODE = "rosbridge_websocket"
#: The node name rosbridge's launch files (ROS 1 and 2) and `ros2 run` give the bridge.
BRIDGE_NODE = "rosbridge_websocket"
#: At most this many goals left running by a drop are remembered for a cancel (the oldest are forgotten).
ORPHAN_LIMIT = 100
#: A goal left running by a drop longer ago than this is not cancelled when the connection comes back: a
#: surprise cancel of something that old would stop whatever the robot is doing now.
ORPHAN_MAX_AGE_SECONDS = 300.0
#: ROS 1: the orphans' cancels are published again this long after the first time. A message published right
#: after a rospy publisher is (re)created is often lost before the action server's subscriber connects to it.
ROS1_CANCEL_REPEAT_SECONDS = 1.0
#: How long a cancel sent after a goal's lane dropped waits for the main connection to prove it is read.
CANCEL_CONFIRM_SECONDS = 1.0
ROS1_CANCEL_TYPE = "actionlib_msgs/GoalID"


@dataclass(frozen=True, slots=True)
class ActionResult:
    """The end of a ROS 2 goal: ROS 2 status number (4 succeeded, 5 canceled, 6 aborted) and result."""

    goal_id: str
    status: int
    values: Any

    @property
    def status_name(self) -> str:
        """``succeeded``, ``canceled``, ``aborted``, ..."""
        return goal_status_name(self.status, 2)

    @property
    def result(self) -> Any:
        """The Result message (the same as :attr:`values`)."""
        return self.values


@dataclass(slots=True)
class GoalHandle:
    """A goal this client has in flight."""

    goal_id: str
    action: str
    action_type: str
    started: float = field(default_factory=time.monotonic)
    feedback_count: int = 0
    last_feedback: Any = None
    cancel_requested: bool = False


@dataclass(frozen=True, slots=True)
class OrphanedGoal:
    """A goal left running on the robot by a drop, to be cancelled once the connection is back.

    ``ros_version`` is the dialect it was sent in: a ROS 2 goal is cancelled with ``cancel_action_goal``,
    a ROS 1 actionlib goal by publishing its id on ``<action>/cancel``.
    """

    action: str
    goal_id: str
    ros_version: int
    since: float = field(default_factory=time.monotonic)
    #: The main connection that was open when the goal was orphaned; it may be dying, so the cancel waits
    #: for another one.
    stale: Connection | None = field(default=None, compare=False)


@dataclass(slots=True)
class _Advert:
    id: str
    msg_type: str
    wire_type: str
    latch: bool
    queue_size: int


class RosbridgeClient:
    """An asyncio client for a rosbridge v2 server (ROS 1 0.11.x, ROS 2 Humble…Rolling).

    One main WebSocket is shared by every caller; a reader task routes frames and replies are
    matched by id. The connection is kept up in the background with exponential backoff. While
    disconnected every call raises :class:`NotConnectedError` at once: nothing is queued and
    nothing is replayed (a stale velocity command is a safety bug); only subscriptions and
    advertisements still wanted are restored after a reconnect.
    """

    def __init__(
        self,
        url: str,
        *,
        connect_timeout: float = 5.0,
        request_timeout: float = 10.0,
        reconnect_min: float = 0.2,
        reconnect_max: float = 5.0,
        lane_cap: int = 16,
        lane_idle_seconds: float = 30.0,
    ) -> None:
        self.url = url
        self.connect_timeout = connect_timeout
        self.request_timeout = request_timeout
        self.reconnect_min = reconnect_min
        self.reconnect_max = max(reconnect_max, reconnect_min)
        self._ids = protocol.IdMinter()
        self._main: Connection | None = None
        self._info: RosInfo | None = None
        # Derived from _info once per connection, so the hot path does not recompute them.
        self._lanes_by_default = False
        self._goals_block = False
        self._spread_calls = False
        self._send_service_timeout = False
        self._last_reason: str | None = "not started"
        self._runner: asyncio.Task[None] | None = None
        self._closing = False
        self._closed = False
        self._attempt_done: asyncio.Event | None = None
        self._connected_event = asyncio.Event()
        self._disconnected_event = asyncio.Event()
        self._disconnected_event.set()
        self._subs: dict[str, dict[str, Subscription]] = {}
        self._adverts: dict[str, _Advert] = {}
        self._goals: dict[str, GoalHandle] = {}
        self._goal_lanes: set[Connection] = set()
        self._orphans: dict[str, OrphanedGoal] = {}
        self._background: set[asyncio.Task[Any]] = set()
        self._lanes = LanePool(
            self._open_lane, self._close_in_background, cap=lane_cap, idle_seconds=lane_idle_seconds
        )
        self.connections_made = 0
        self._lane_numbers = itertools.count(1)

    # --- lifecycle --------------------------------------------------------------------------------

    @property
    def connected(self) -> bool:
        """The main connection is open and the bridge's flavour is known."""
        return self._main is not None and self._main.is_open

    @property
    def lanes(self) -> LanePool:
        """The pool of single-call lanes (for diagnostics)."""
        return self._lanes

    async def start(self) -> None:
        """Start the background connect/reconnect loop; returns at once."""
        if self._closed:
            raise RuntimeError("this RosbridgeClient is closed")
        if self._runner is not None:
            return
        # Marks an attempt as in progress before the loop runs, so a call right after start()
        # waits for the first attempt instead of failing.
        self._attempt_done = asyncio.Event()
        self._runner = asyncio.create_task(self._run(), name=f"rosbridge connect loop ({self.url})")

    async def __aenter__(self) -> Self:
        await self.start()
        return self

    async def __aexit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.close()

    async def close(self) -> None:
        """Cancel everything, cancel our goals, unadvertise, close every socket. Idempotent."""
        if self._closed:
            return
        self._closed = True
        self._closing = True
        main = self._main
        if main is not None and main.is_open:
            for goal in list(self._goals.values()):
                await self._send_quietly(main, protocol.cancel_action_goal(goal.action, id=goal.goal_id))
            for topic, advert in list(self._adverts.items()):
                if topic in main.advertised:
                    await self._send_quietly(main, protocol.unadvertise(topic, id=advert.id))
        if self._runner is not None:
            self._runner.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._runner
        lanes = self._lanes.close_all() + list(self._goal_lanes)
        self._goal_lanes.clear()
        await asyncio.gather(*(lane.aclose() for lane in lanes), return_exceptions=True)
        if main is not None:
            await main.aclose()
        self._set_disconnected(main, "the client was closed")
        for subs in list(self._subs.values()):
            for sub in list(subs.values()):
                sub.is_open = False
                sub.is_closed = True
                sub._interrupt(NotConnectedError(self.url, "the client was closed"))
        self._subs.clear()
        self._adverts.clear()
        for orphan in self._orphans.values():
            logger.warning(
                "The client is closing; goal %s on %s, left running by a drop, was not cancelled",
                orphan.goal_id,
                orphan.action,
            )
        self._orphans.clear()
        if self._background:
            await asyncio.gather(*list(self._background), return_exceptions=True)

    async def wait_connected(self, timeout: float) -> None:
        """Wait until connected; raises :class:`NotConnectedError` naming the URL and last reason."""
        if self.connected:
            return
        if self._closed:
            raise NotConnectedError(self.url, "the client is closed")
        try:
            async with asyncio.timeout(timeout):
                await self._connected_event.wait()
        except TimeoutError:
            raise NotConnectedError(
                self.url, f"no connection within {timeout:g} s; last error: {self._last_reason}"
            ) from None

    async def wait_disconnected(self, timeout: float) -> None:
        """Wait until the main connection is down (diagnostics and tests); raises TimeoutError."""
        async with asyncio.timeout(timeout):
            await self._disconnected_event.wait()

    # --- the connect loop ---------------------------------------------------------------------------

    async def _run(self) -> None:
        delay = self.reconnect_min
        failures = 0
        ever_connected = False
        while not self._closing:
            if self._attempt_done is None or self._attempt_done.is_set():
                self._attempt_done = asyncio.Event()
            attempt_done = self._attempt_done
            conn: Connection | None = None
            try:
                conn = await open_connection(
                    self.url, "main", self.connect_timeout, self._route_publish, self.request_timeout
                )
                info = await self._detect(conn)
                await self._restore(conn, info)
            except asyncio.CancelledError:
                # close() cancelled us mid-setup: the half-set-up socket is not self._main, so
                # nobody else would close it.
                if conn is not None:
                    await conn.aclose()
                raise
            except NotConnectedError as exc:
                self._last_reason = exc.reason
                if conn is not None:
                    await conn.aclose()
                failures += 1
                if failures == 1:
                    logger.warning(
                        "Cannot reach rosbridge at %s (%s); retrying in the background", self.url, exc.reason
                    )
                else:
                    logger.debug("rosbridge at %s still unreachable (%s)", self.url, exc.reason)
            except Exception as exc:
                self._last_reason = f"{type(exc).__name__}: {exc}"
                if conn is not None:
                    await conn.aclose()
                failures += 1
                logger.warning("Setting up the connection to %s failed: %s", self.url, self._last_reason)
            else:
                self._info = info
                self._lanes_by_default = info.may_be_in_order
                self._goals_block = info.goals_may_block
                self._spread_calls = info.one_call_per_connection
                self._send_service_timeout = info.honours_service_timeout
                self._main = conn
                self._last_reason = None
                self.connections_made += 1
                self._disconnected_event.clear()
                self._connected_event.set()
                attempt_done.set()
                logger.info(
                    "%s rosbridge at %s: %s",
                    "Reconnected to" if ever_connected else "Connected to",
                    self.url,
                    info.describe(),
                )
                ever_connected = True
                failures = 0
                if self._orphans:
                    self._spawn(self._cancel_orphans(conn, info), "cancel goals orphaned by a drop")
                delay = self.reconnect_min
                await conn.closed.wait()
                reason = conn.close_reason or "the connection closed"
                self._set_disconnected(conn, reason)
                if not self._closing:
                    logger.warning(
                        "Lost the connection to rosbridge at %s (%s); reconnecting", self.url, reason
                    )
            finally:
                attempt_done.set()
            sleep = random.uniform(delay / 2, delay)
            delay = min(delay * 2, self.reconnect_max)
            # No attempt is in progress while we sleep: calls fail at once instead of waiting.
            await asyncio.sleep(sleep)

    def _set_disconnected(self, conn: Connection | None, reason: str) -> None:
        if conn is not None and self._main is conn:
            self._main = None
            self._info = None
            self._last_reason = reason
        self._connected_event.clear()
        self._disconnected_event.set()
        # Idle lanes belong to the old bridge session; busy ones fail on their own when it is gone.
        self._lanes.drop_idle()
        lost = ConnectionLostError(self.url, "messages")
        for subs in self._subs.values():
            for sub in subs.values():
                sub._interrupt(lost)

    async def _detect(self, conn: Connection) -> RosInfo:
        """Ask the bridge what it is (once per connection)."""
        timeout = min(self.connect_timeout, self.request_timeout)
        try:
            values = await self._call_on(conn, "/rosapi/get_ros_version", None, timeout, send_timeout=False)
        except ServiceError:
            # ROS 1 (0.11.x) and ROS 2 before rosbridge 1.2.0 answer "Service /rosapi/get_ros_version
            # does not exist"; the type names tell them apart.
            pass
        except RequestTimeoutError:
            logger.warning("rosbridge at %s did not answer /rosapi/get_ros_version; assuming ROS 2", self.url)
            return RosInfo(2, None)
        else:
            version = values.get("version") if isinstance(values, dict) else None
            distro = values.get("distro") if isinstance(values, dict) else None
            if version == 1:
                return RosInfo(1, distro or None)
            calls, goals = await self._threading(conn, timeout)
            return RosInfo(2, str(distro) if distro else None, calls_threaded=calls, goals_threaded=goals)
        try:
            values = await self._call_on(conn, "/rosapi/topics", None, timeout, send_timeout=False)
        except ServiceError as exc:
            # No rosapi. Every rospy node offers <node>/get_loggers; ROS 2 nodes never do. Without this, a
            # real 0.11.17 bridge without rosapi was taken for ROS 2 and publish_action sent it action ops it
            # ignores, waiting out the whole timeout.
            if await self._answers(conn, f"/{ROS1_BRIDGE_NODE}/get_loggers", timeout):
                logger.warning("No rosapi at %s; its rosbridge node is a ROS 1 (rospy) node", self.url)
                return RosInfo(1, None)
            logger.warning("Cannot tell the ROS version of %s (no rosapi? %s); assuming ROS 2", self.url, exc)
            return RosInfo(2, None)
        except RequestTimeoutError as exc:
            logger.warning("Cannot tell the ROS version of %s (no rosapi? %s); assuming ROS 2", self.url, exc)
            return RosInfo(2, None)
        types = values.get("types", []) if isinstance(values, dict) else []
        if any(isinstance(t, str) and "/msg/" in t for t in types):
            return RosInfo(2, None)
        return RosInfo(1, None)

    async def _threading(self, conn: Connection, timeout: float) -> tuple[bool | None, bool | None]:
        """Whether a ROS 2 bridge runs each call and each goal in a thread of its own, as its node says.

        rosbridge 2.x reads ``call_services_in_new_thread`` and ``send_action_goals_in_new_thread``; 2.1.0's
        launch file sets both false, on Jazzy and Kilted alike. The node is found in ``/rosapi/nodes`` first:
        rosapi's ``get_param`` waits 5 s for a node that does not exist, serving nobody else meanwhile.
        ``None`` where the bridge did not tell (no such node, several, an older bridge without the parameter).
        """
        try:
            values = await self._call_on(conn, "/rosapi/nodes", None, timeout, send_timeout=False)
        except (ServiceError, RequestTimeoutError):
            return None, None
        listed = values.get("nodes") if isinstance(values, dict) else None
        nodes = [
            node
            for node in (listed if isinstance(listed, list) else [])
            if isinstance(node, str) and node.rsplit("/", 1)[-1] == BRIDGE_NODE
        ]
        if len(nodes) != 1:
            return None, None
        answers: list[bool | None] = []
        for parameter in ("call_services_in_new_thread", "send_action_goals_in_new_thread"):
            args = {"name": f"{nodes[0]}:{parameter}", "default_value": ""}
            try:
                found = await self._call_on(conn, "/rosapi/get_param", args, timeout, send_timeout=False)
            except (ServiceError, RequestTimeoutError):
                answers.append(None)
                continue
            text = found.get("value") if isinstance(found, dict) else None
            answers.append({"true": True, "false": False}.get(text) if isinstance(text, str) else None)
        return answers[0], answers[1]

    async def _answers(self, conn: Connection, service: str, timeout: float) -> bool:
        """Whether *service* answers a call with an empty request."""
        try:
            await self._call_on(conn, service, None, timeout, send_timeout=False)
        except (ServiceError, RequestTimeoutError):
            return False
        return True

    async def _restore(self, conn: Connection, info: RosInfo) -> None:
        """Re-advertise and re-subscribe what is still wanted. Never re-sends a publish.

        Type names are spelled again for this connection's bridge: the robot may have come back
        with another ROS version behind the same address.
        """
        for topic, advert in list(self._adverts.items()):
            advert.wire_type = normalize_type(advert.msg_type, info.version, "msg")
            await conn.send(
                protocol.advertise(
                    topic, advert.wire_type, id=advert.id, latch=advert.latch, queue_size=advert.queue_size
                )
            )
            conn.advertised.add(topic)
        for topic, subs in list(self._subs.items()):
            for sub in list(subs.values()):
                sub.wire_type = normalize_type(sub.msg_type, info.version, "msg") if sub.msg_type else None
                await conn.send(
                    protocol.subscribe(
                        topic,
                        sub.wire_type,
                        id=sub.id,
                        throttle_rate=sub.throttle_rate,
                        queue_length=sub.queue_length,
                    )
                )

    async def _main_connection(self, deadline: float | None = None) -> Connection:
        """The open main connection, waiting only for an attempt already in progress."""
        conn = self._main
        if conn is not None and conn.is_open:
            return conn
        if self._closed:
            raise NotConnectedError(self.url, "the client is closed")
        attempt = self._attempt_done
        if attempt is not None and not attempt.is_set():
            loop = asyncio.get_running_loop()
            until = loop.time() + self.connect_timeout
            if deadline is not None:
                until = min(until, deadline)
            try:
                async with asyncio.timeout_at(until):
                    await attempt.wait()
            except TimeoutError:
                pass
            conn = self._main
            if conn is not None and conn.is_open:
                return conn
        raise NotConnectedError(self.url, self._last_reason)

    def _require_main(self) -> tuple[Connection, RosInfo]:
        conn = self._main
        info = self._info
        if conn is None or info is None or not conn.is_open:
            raise NotConnectedError(self.url, self._last_reason)
        return conn, info

    async def ros_info(self) -> RosInfo:
        """What the bridge is: ROS version and distro, detected once per connection."""
        await self._main_connection()
        info = self._info
        if info is None:
            raise NotConnectedError(self.url, self._last_reason)
        return info

    # --- background helpers -------------------------------------------------------------------------

    def _spawn(self, coro: Coroutine[Any, Any, Any], name: str) -> asyncio.Task[Any]:
        task = asyncio.get_running_loop().create_task(coro, name=name)
        self._background.add(task)
        task.add_done_callback(self._background.discard)
        return task

    def _close_in_background(self, conn: Connection) -> None:
        self._spawn(conn.aclose(), f"close {conn.name}")

    async def _send_quietly(self, conn: Connection | None, op: dict[str, Any]) -> bool:
        if conn is None or not conn.is_open:
            return False
        try:
            await conn.send(op)
        except RosbridgeError:
            return False
        except Exception:
            logger.debug("sending %s failed", op.get("op"), exc_info=True)
            return False
        return True

    async def _open_lane(self, timeout: float) -> Connection:
        return await open_connection(
            self.url,
            f"lane {next(self._lane_numbers)}",
            min(timeout, self.connect_timeout),
            send_timeout=self.request_timeout,
        )

    # --- services -----------------------------------------------------------------------------------

    async def _call_on(
        self,
        conn: Connection,
        service: str,
        args: dict[str, Any] | list[Any] | None,
        timeout: float,
        *,
        send_timeout: bool,
    ) -> Any:
        rid = self._ids.mint("call_service", service)
        op = protocol.call_service(service, args, id=rid, timeout=timeout if send_timeout else None)
        reply = await conn.request(rid, op, f"service {service}", timeout)
        return _service_values(service, reply)

    async def call_service(
        self,
        service: str,
        args: dict[str, Any] | list[Any] | None = None,
        *,
        timeout: float | None = None,
        isolated: bool | None = None,
    ) -> Any:
        """Call a ROS service and return its response fields (``values``).

        Runs on the shared connection, or on a lane of its own when the bridge may handle one
        connection in order (Humble) or when *isolated* is true. Raises :class:`ServiceError`
        with the bridge's text, :class:`RequestTimeoutError`, :class:`ConnectionLostError`,
        :class:`NotConnectedError`.
        """
        t = self.request_timeout if timeout is None else timeout
        conn = self._main
        if conn is None or not conn.is_open:
            conn = await self._main_connection(asyncio.get_running_loop().time() + t)
        if isolated or (
            isolated is None and (self._lanes_by_default or (self._spread_calls and conn.pending))
        ):
            return await self._call_on_lane(service, args, t)
        # The hot path: kept flat (one coroutine frame below this one) because a benchmark holds
        # it to a raw websockets round trip.
        rid = self._ids.mint("call_service", service)
        op = protocol.call_service(
            service, args, id=rid, timeout=_bridge_timeout(t) if self._send_service_timeout else None
        )
        reply = await conn.request(rid, op, "service " + service, t)
        if reply.get("result") is False:
            raise _service_error(service, reply)
        return reply.get("values")

    async def _call_on_lane(self, service: str, args: dict[str, Any] | list[Any] | None, t: float) -> Any:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + t
        what = f"service {service}"
        lane = await self._lanes.acquire(deadline, what, t)
        reusable = False
        try:
            remaining = max(deadline - loop.time(), 0.001)
            rid = self._ids.mint("call_service", service)
            op = protocol.call_service(
                service,
                args,
                id=rid,
                timeout=_bridge_timeout(remaining) if self._send_service_timeout else None,
            )
            try:
                reply = await lane.request(rid, op, what, remaining)
            except RequestTimeoutError:
                raise RequestTimeoutError(what, t, "The bridge answers many errors with silence.") from None
            reusable = True
        finally:
            self._lanes.release(lane, reusable)
        if reply.get("result") is False:
            raise _service_error(service, reply)
        return reply.get("values")

    # --- topics -------------------------------------------------------------------------------------

    async def advertise(
        self, topic: str, msg_type: str, *, latch: bool = False, queue_size: int = 10
    ) -> None:
        """Advertise *topic* now (``publish`` does this on first use); restored after reconnects."""
        conn, info = self._require_main()
        await self._ensure_advertised(conn, info, topic, msg_type, latch=latch, queue_size=queue_size)

    async def _ensure_advertised(
        self, conn: Connection, info: RosInfo, topic: str, msg_type: str, *, latch: bool, queue_size: int
    ) -> None:
        wire_type = normalize_type(msg_type, info.version, "msg")
        advert = self._adverts.get(topic)
        if advert is not None and (advert.wire_type != wire_type or advert.latch != latch):
            conn.advertised.discard(topic)
            del self._adverts[topic]
            await conn.send(protocol.unadvertise(topic, id=advert.id))
            advert = None
        if advert is None:
            advert = _Advert(self._ids.mint("advertise", topic), msg_type, wire_type, latch, queue_size)
            self._adverts[topic] = advert
        if topic not in conn.advertised:
            conn.advertised.add(topic)
            try:
                await conn.send(
                    protocol.advertise(
                        topic, wire_type, id=advert.id, latch=latch, queue_size=advert.queue_size
                    )
                )
            except BaseException:
                conn.advertised.discard(topic)
                raise

    async def publish(
        self,
        topic: str,
        msg_type: str,
        msg: dict[str, Any],
        *,
        latch: bool = False,
        queue_size: int = 10,
    ) -> None:
        """Publish one message now, or raise :class:`NotConnectedError`. Never queued, never replayed.

        The topic is advertised once (per topic and type) and the advertisement reused; time
        fields are respelled for ROS 1, which ignores ``sec``/``nanosec``.
        """
        conn, info = self._require_main()
        advert = self._adverts.get(topic)
        if (
            advert is None
            or topic not in conn.advertised
            or advert.latch != latch
            or (
                advert.msg_type != msg_type
                and advert.wire_type != normalize_type(msg_type, info.version, "msg")
            )
        ):
            await self._ensure_advertised(conn, info, topic, msg_type, latch=latch, queue_size=queue_size)
        payload = adapt_message(msg, info.version) if info.version == 1 else msg
        await conn.send(protocol.publish(topic, payload))

    async def ping(self, timeout: float | None = None) -> float:
        """Round-trip a WebSocket ping on the main connection; returns the seconds it took.

        Proves the bridge reads the connection now: a frozen bridge, or a link that died without a close,
        still takes frames into the socket buffer and would act on them whenever it wakes up.
        :class:`RequestTimeoutError` if no pong within *timeout* (default ``request_timeout``),
        :class:`NotConnectedError` when there is no connection.
        """
        conn, _ = self._require_main()
        return await conn.ping(self.request_timeout if timeout is None else timeout)

    async def unadvertise(self, topic: str) -> None:
        """Stop advertising *topic* (our advertisement only)."""
        advert = self._adverts.pop(topic, None)
        conn = self._main
        if advert is not None and conn is not None and topic in conn.advertised:
            conn.advertised.discard(topic)
            await self._send_quietly(conn, protocol.unadvertise(topic, id=advert.id))

    def subscribe(
        self,
        topic: str,
        msg_type: str | None = None,
        *,
        throttle_rate: int = 0,
        queue_length: int = 0,
        max_queue: int = 1000,
    ) -> Subscription:
        """A :class:`Subscription` (``async with client.subscribe("/chatter") as sub: ...``)."""
        return Subscription(
            self,
            topic,
            msg_type,
            sub_id=self._ids.mint("subscribe", topic),
            throttle_rate=throttle_rate,
            queue_length=queue_length,
            max_queue=max_queue,
        )

    async def _open_subscription(self, sub: Subscription) -> None:
        conn = await self._main_connection()
        info = self._info
        if info is None:
            raise NotConnectedError(self.url, self._last_reason)
        sub.wire_type = normalize_type(sub.msg_type, info.version, "msg") if sub.msg_type else None
        self._subs.setdefault(sub.topic, {})[sub.id] = sub
        try:
            await conn.send(
                protocol.subscribe(
                    sub.topic,
                    sub.wire_type,
                    id=sub.id,
                    throttle_rate=sub.throttle_rate,
                    queue_length=sub.queue_length,
                )
            )
        except BaseException:
            self._forget_subscription(sub)
            raise

    def _forget_subscription(self, sub: Subscription) -> None:
        subs = self._subs.get(sub.topic)
        if subs is not None:
            subs.pop(sub.id, None)
            if not subs:
                del self._subs[sub.topic]

    async def _close_subscription(self, sub: Subscription) -> None:
        self._forget_subscription(sub)
        conn = self._main
        if conn is not None and conn.is_open:
            # Shielded: this runs in `finally`/`__aexit__`, often while the caller is being cancelled.
            await asyncio.shield(self._send_quietly(conn, protocol.unsubscribe(sub.topic, id=sub.id)))

    def _route_publish(self, event: protocol.PublishEvent) -> None:
        subs = self._subs.get(event.topic)
        if subs:
            for sub in subs.values():
                sub._push(event.msg)

    async def wait_for_message(self, topic: str, msg_type: str | None, timeout: float) -> dict[str, Any]:
        """The next message on *topic*, within *timeout* seconds."""
        async with self.subscribe(topic, msg_type, max_queue=1) as sub:
            return await sub.get(timeout)

    # --- ROS 2 actions ------------------------------------------------------------------------------

    def new_goal_id(self, action: str) -> str:
        """A goal id unique across every client of the bridge (rosbridge's goal table is process-wide)."""
        return self._ids.goal_id(action)

    def running_goals(self, action: str | None = None) -> list[GoalHandle]:
        """Goals this client has in flight (all, or those of *action*)."""
        return [g for g in self._goals.values() if action is None or g.action == action]

    # --- goals orphaned by a drop -------------------------------------------------------------------
    #
    # A goal keeps running on the robot when our connection drops: ROS 2 goals outlive the WebSocket that
    # sent them (the bridge's goal table is process-wide) and ROS 1 actionlib goals live in the action
    # server. Nobody supervises them any more, so each is cancelled once as soon as a connection is back.
    # This is not a replay: a cancel only stops motion, and nothing else asked for during the outage is sent.

    def orphaned_goals(self) -> list[OrphanedGoal]:
        """Goals left running by a drop, waiting for the connection to come back to be cancelled."""
        return list(self._orphans.values())

    def remember_orphaned_goal(
        self, action: str, goal_id: str, ros_version: int, *, stale: Connection | None = None
    ) -> None:
        """Remember a goal that may still be running but could not be cancelled: the connection is down.

        It is cancelled once as soon as a connection to the bridge is up again (at once if one already
        is, other than *stale*, a connection known to be dying), then forgotten. At most
        :data:`ORPHAN_LIMIT` are kept; one older than :data:`ORPHAN_MAX_AGE_SECONDS` is never cancelled.
        """
        if self._closed:
            return
        self._orphans.pop(goal_id, None)
        self._orphans[goal_id] = OrphanedGoal(action, goal_id, ros_version, stale=stale)
        logger.warning(
            "Goal %s on %s may still be running on the robot; it will be cancelled as soon as the "
            "connection to %s is back",
            goal_id,
            action,
            self.url,
        )
        while len(self._orphans) > ORPHAN_LIMIT:
            oldest = next(iter(self._orphans.values()))
            del self._orphans[oldest.goal_id]
            logger.warning(
                "More than %d goals are waiting to be cancelled; forgetting goal %s on %s without a cancel",
                ORPHAN_LIMIT,
                oldest.goal_id,
                oldest.action,
            )
        # The reconnect may already have happened (its own sweep ran before this goal was remembered).
        conn, info = self._main, self._info
        if conn is not None and conn.is_open and info is not None and conn is not stale:
            self._spawn(self._cancel_orphans(conn, info), "cancel goals orphaned by a drop")

    async def _cancel_orphans(self, conn: Connection, info: RosInfo) -> None:
        """Cancel, once, every remembered goal that *conn* may reach; forget them once the bridge read it."""
        now = time.monotonic()
        sent: list[OrphanedGoal] = []
        for orphan in list(self._orphans.values()):
            if orphan.stale is conn or self._orphans.get(orphan.goal_id) is not orphan:
                continue
            # Taken out before any await, so a second sweep running at the same time never sends it again.
            del self._orphans[orphan.goal_id]
            age = now - orphan.since
            if age > ORPHAN_MAX_AGE_SECONDS:
                logger.warning(
                    "Not cancelling goal %s on %s: it was left running by a drop %.0f s ago, "
                    "too long ago for a surprise cancel",
                    orphan.goal_id,
                    orphan.action,
                    age,
                )
                continue
            if orphan.ros_version != info.version:
                logger.warning(
                    "Not cancelling goal %s on %s: it was sent to a ROS %d bridge and %s came back "
                    "as ROS %d, so the goal is gone",
                    orphan.goal_id,
                    orphan.action,
                    orphan.ros_version,
                    self.url,
                    info.version,
                )
                continue
            try:
                await self._send_orphan_cancel(conn, info, orphan)
            except Exception as exc:
                # The connection went again: the next one tries.
                logger.debug("Could not cancel goal %s yet: %s", orphan.goal_id, exc)
                self._keep_orphans([orphan, *sent], conn)
                return
            sent.append(orphan)
        if not sent:
            return
        # A cancel written into a socket the bridge is closing is lost: only a pong proves it was read.
        if not await self._confirmed(conn):
            self._keep_orphans(sent, conn)
            return
        for orphan in sent:
            logger.warning(
                "Sent a cancel for goal %s on %s, left running on the robot when the connection dropped "
                "%.1f s ago (nothing else asked for during the outage is sent)",
                orphan.goal_id,
                orphan.action,
                time.monotonic() - orphan.since,
            )
        ros1 = [orphan for orphan in sent if orphan.ros_version == 1]
        if ros1:
            # Until the disconnect (close() too) or the repeat time, whichever comes first.
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(ROS1_CANCEL_REPEAT_SECONDS):
                    await self._disconnected_event.wait()
            if self._main is conn and conn.is_open:
                for orphan in ros1:
                    with contextlib.suppress(Exception):
                        await self._send_orphan_cancel(conn, info, orphan)

    def _keep_orphans(self, orphans: list[OrphanedGoal], conn: Connection) -> None:
        for orphan in orphans:
            if orphan.goal_id not in self._orphans:
                self._orphans[orphan.goal_id] = OrphanedGoal(
                    orphan.action, orphan.goal_id, orphan.ros_version, orphan.since, stale=conn
                )

    async def _send_orphan_cancel(self, conn: Connection, info: RosInfo, orphan: OrphanedGoal) -> None:
        if orphan.ros_version == 2:
            await conn.send(protocol.cancel_action_goal(orphan.action, id=orphan.goal_id))
            return
        topic = f"{orphan.action}/cancel"
        await self._ensure_advertised(conn, info, topic, ROS1_CANCEL_TYPE, latch=False, queue_size=10)
        msg = {"stamp": {"sec": 0, "nanosec": 0}, "id": orphan.goal_id}
        await conn.send(protocol.publish(topic, adapt_message(msg, info.version)))

    async def _confirmed(self, conn: Connection | None) -> bool:
        """Whether the bridge has read everything sent on *conn* so far (a pong came back in time)."""
        if conn is None or not conn.is_open:
            return False
        try:
            await conn.ping(min(CANCEL_CONFIRM_SECONDS, self.request_timeout))
        except RosbridgeError:
            return False
        except Exception:
            logger.debug("ping on %s failed", conn.name, exc_info=True)
            return False
        return True

    async def cancel_action_goal(self, action: str, goal_id: str) -> None:
        """Ask the bridge to cancel goal *goal_id*, on the main connection.

        rosbridge keeps one goal table per process, so this reaches a goal running on a lane (or
        on another client's connection) too. No reply comes; the goal's result says what happened.
        """
        conn, _info = self._require_main()
        handle = self._goals.get(goal_id)
        if handle is not None:
            handle.cancel_requested = True
        await conn.send(protocol.cancel_action_goal(action, id=goal_id))

    async def send_action_goal(
        self,
        action: str,
        action_type: str,
        goal: dict[str, Any],
        *,
        on_feedback: Callable[[dict[str, Any]], Awaitable[None] | None] | None = None,
        timeout: float,
        goal_id: str | None = None,
    ) -> ActionResult:
        """Send a ROS 2 goal on a lane of its own and wait for its result.

        Raises :class:`ActionError` when the bridge refuses the goal ("No action server
        available", ...), :class:`GoalTimeoutError` after *timeout* (a cancel was sent; the error
        carries the canceled result if it came within a short grace), :class:`ConnectionLostError`
        when the goal's lane drops (the goal keeps running on the robot, so it is cancelled on the main
        connection, or as soon as a connection is back: see :meth:`remember_orphaned_goal`).
        If the awaiting task is cancelled, the goal is cancelled too before the task ends.
        """
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        _conn, info = self._require_main()
        if not info.has_action_ops:
            raise ActionError(action, "this bridge runs ROS 1, which has no action ops; use actionlib topics")
        wire_type = action_type_names(action_type).ros2
        gid = goal_id if goal_id is not None else self._ids.goal_id(action)
        if gid in self._goals:
            raise ActionError(action, f"goal id {gid!r} is already in use by a running goal")
        handle = GoalHandle(gid, action, wire_type)
        what = f"action goal {gid} on {action}"
        stream = GoalStream(what)
        lane: Connection | None = None
        sent = False
        finished = False
        self._goals[gid] = handle
        try:
            try:
                lane = await self._open_lane(max(deadline - loop.time(), 0.05))
            except NotConnectedError as exc:
                raise NotConnectedError(
                    self.url, f"could not open a lane for the goal: {exc.reason}"
                ) from None
            self._goal_lanes.add(lane)
            lane.pending[gid] = stream
            await lane.send(protocol.send_action_goal(action, wire_type, goal, id=gid, feedback=True))
            sent = True
            try:
                async with asyncio.timeout_at(deadline):
                    frame = await self._follow_goal(stream, handle, on_feedback)
            except TimeoutError:
                await asyncio.shield(self._cancel_quietly(action, gid, lane))
                late: dict[str, Any] | None = None
                try:
                    async with asyncio.timeout(CANCEL_GRACE_SECONDS):
                        late = await self._follow_goal(stream, handle, None)
                except (TimeoutError, ConnectionLostError):
                    pass
                if late is None:
                    raise GoalTimeoutError(action, gid, timeout, feedback=handle.last_feedback) from None
                finished = True
                status, values = _goal_result(action, late)
                raise GoalTimeoutError(
                    action, gid, timeout, status=status, result=values, feedback=handle.last_feedback
                ) from None
            except ConnectionLostError:
                # The goal's lane dropped; the goal itself keeps running on the robot.
                finished = True  # the cancel is taken care of here, not in `finally`
                reached = await asyncio.shield(self._cancel_after_drop(action, gid))
                raise ConnectionLostError(
                    self.url, what, goal_cancel="sent" if reached else "pending"
                ) from None
            finished = True
            status, values = _goal_result(action, frame)
            return ActionResult(gid, status, values)
        finally:
            self._goals.pop(gid, None)
            try:
                if sent and not finished:
                    await asyncio.shield(self._cancel_quietly(action, gid, lane))
            finally:
                # Even if we are cancelled again while the cancel is being sent.
                if lane is not None:
                    lane.pending.pop(gid, None)
                    self._goal_lanes.discard(lane)
                    self._close_in_background(lane)

    async def _follow_goal(
        self,
        stream: GoalStream,
        handle: GoalHandle,
        on_feedback: Callable[[dict[str, Any]], Awaitable[None] | None] | None,
    ) -> dict[str, Any]:
        while True:
            item = await stream.queue.get()
            if isinstance(item, BaseException):
                raise item
            op, frame = item
            if op == "action_result":
                return frame
            if op == "action_feedback":
                values = frame.get("values")
                handle.feedback_count += 1
                handle.last_feedback = values
                if on_feedback is not None and isinstance(values, dict):
                    maybe = on_feedback(values)
                    if maybe is not None:
                        await maybe

    async def _cancel_quietly(self, action: str, goal_id: str, lane: Connection | None) -> None:
        op = protocol.cancel_action_goal(action, id=goal_id)
        # The main connection first: on an in-order bridge the goal's own lane is blocked by the goal.
        if await self._send_quietly(self._main, op):
            return
        on_lane = await self._send_quietly(lane, op)
        # close() has already sent cancels for every running goal on the main connection.
        if self._closed:
            return
        # An in-order bridge (2.1.0's and Humble's defaults) reads a lane's cancel only after the goal ended.
        if not on_lane or self._goals_block:
            self.remember_orphaned_goal(action, goal_id, 2)

    async def _cancel_after_drop(self, action: str, goal_id: str) -> bool:
        """Cancel a goal whose lane dropped on the main connection; True if the bridge surely read it.

        A drop of the whole bridge closes the main connection too, but its reader may not have noticed
        yet: a cancel written then is lost, so it counts only once a ping on the same connection is answered.
        Otherwise the goal is remembered and cancelled on the next connection.
        """
        main = self._main
        op = protocol.cancel_action_goal(action, id=goal_id)
        if await self._send_quietly(main, op) and await self._confirmed(main):
            return True
        if not self._closed:
            self.remember_orphaned_goal(action, goal_id, 2, stale=main)
        return False


def _bridge_timeout(deadline_in: float) -> float:
    """The ``timeout`` field for a call we give up on after *deadline_in* seconds.

    Slightly shorter than our own deadline, so a ROS 2 bridge (Humble 2.0.1+, Jazzy 2.2.0+) gives up
    first and its own text ("Timeout exceeded while waiting for service response") reaches the
    user, telling them the bridge is alive and the service is what is slow.
    """
    return max(deadline_in - min(0.25, deadline_in * 0.1), 0.001)


def _service_error(service: str, reply: dict[str, Any]) -> ServiceError:
    values = reply.get("values")
    return ServiceError(service, values if isinstance(values, str) else repr(values))


def _service_values(service: str, reply: dict[str, Any]) -> Any:
    if reply.get("result") is False:
        raise _service_error(service, reply)
    return reply.get("values")


def _goal_result(action: str, frame: dict[str, Any]) -> tuple[int, Any]:
    values = frame.get("values")
    if frame.get("result") is False:
        raise ActionError(action, values if isinstance(values, str) else repr(values))
    status = frame.get("status")
    return (status if isinstance(status, int) and not isinstance(status, bool) else 0), values
