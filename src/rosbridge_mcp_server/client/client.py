"""``RosbridgeClient``: one shared WebSocket, background reconnects, lanes for in-order bridges."""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import logging
import ssl
from collections.abc import Callable, Coroutine, Sequence
from dataclasses import dataclass
from types import TracebackType
from typing import Any, Final, Literal, Protocol, Self

from rosbridge_mcp_server.client.capabilities import BridgeCapabilities
from rosbridge_mcp_server.client.connection import Connection, open_connection
from rosbridge_mcp_server.client.dialect import Dialect
from rosbridge_mcp_server.client.goal_lane import GoalLane, GoalLanes
from rosbridge_mcp_server.client.lanes import LanePool
from rosbridge_mcp_server.client.ordering import call_ordering
from rosbridge_mcp_server.client.reconnect import Attempts, reconnect_cap
from rosbridge_mcp_server.client.services import bridge_timeout, call_on, call_on_lane
from rosbridge_mcp_server.client.session import Session, open_session
from rosbridge_mcp_server.client.subscription import Subscription
from rosbridge_mcp_server.client.topics import Topics
from rosbridge_mcp_server.client.transport import Dial, websocket_dial
from rosbridge_mcp_server.errors import ConnectionLostError, NotConnectedError
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.dialect import RosInfo

__all__ = ["GoalCancel", "RosbridgeClient", "SessionWatcher"]

logger = logging.getLogger("rosbridge_mcp_server.client")

#: How long :meth:`RosbridgeClient.close` waits for the bridge to handle what acted last.
_CLOSE_HANDLED_SECONDS: Final = 1.0
#: How long the ordering probe's service holds its caller: above a slow rosapi call on 2.1.0 (85-100 ms).
_ORDERING_HOLD_SECONDS: Final = 0.5
#: The ordering probe gives up after this long (then every call keeps a connection of its own).
_ORDERING_LIMIT_SECONDS: Final = 5.0


class SessionWatcher(Protocol):
    """Told when a session starts and before the client closes (``robot/goals`` cancels goals then)."""

    def session_started(self, session: Session) -> None:
        """A new main connection is up (called in the connect loop: start tasks, do not wait)."""

    async def client_closing(self, session: Session | None) -> None:
        """``close()`` is about to close every socket; *session* is the open one, if any."""


class RosbridgeClient:
    """An asyncio client for a rosbridge v2 server (ROS 1 0.11.x, ROS 2 Humble…Rolling).

    One main WebSocket is shared by every caller; a reader task routes frames and replies are
    matched by id. The connection is kept up in the background with exponential backoff, capped at
    :func:`reconnect_cap` (half a second for a bridge on this machine or the local network); a call
    that finds no connection prompts an attempt at once and waits for that one attempt only. While
    disconnected every call raises :class:`NotConnectedError`: nothing is queued and nothing is
    replayed (a stale velocity command is a safety bug); only subscriptions and advertisements still
    wanted are restored after a reconnect.
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
        ssl_context: ssl.SSLContext | None = None,
        headers: Sequence[tuple[str, str]] = (),
        transport: Dial | None = None,
    ) -> None:
        self.url = url
        # For wss:// with a private CA or a client certificate, and for a bridge behind an authenticating
        # proxy; every connection (main, lanes, the ordering probe's) opens with them. *transport* opens them
        # another way (the simulated robot's in memory): then the URL only names the bridge.
        self._transport = transport or websocket_dial(url, ssl_context=ssl_context, headers=headers)
        self.connect_timeout = connect_timeout
        self.request_timeout = request_timeout
        self.reconnect_min = reconnect_min
        self.reconnect_max = max(reconnect_max, reconnect_min)
        #: The backoff's ceiling for this bridge (short on this machine and the local network).
        self.reconnect_cap = max(reconnect_cap(url, self.reconnect_max), reconnect_min)
        self._ids = protocol.IdMinter()
        self._session: Session | None = None
        self._attempts = Attempts(reconnect_min, self.reconnect_cap)
        self._runner: asyncio.Task[None] | None = None
        self._closing = False
        self._closed = False
        #: Something that acts (a publish, a goal cancel) went out on the main connection, and the bridge may
        #: not have handled it yet: :meth:`close` waits for it first.
        self.unhandled_acts = False
        self._connected_event = asyncio.Event()
        self._disconnected_event = asyncio.Event()
        self._disconnected_event.set()
        self._watchers: list[SessionWatcher] = []
        self._background: set[asyncio.Task[Any]] = set()
        self._measuring: asyncio.Task[Any] | None = None
        self._lanes = LanePool(
            self._open_lane, self._close_in_background, cap=lane_cap, idle_seconds=lane_idle_seconds
        )
        self._goal_lanes = GoalLanes(url, self._open_lane, self._close_in_background)
        self.topics = Topics(url, self._ids, lambda: self.session, self._wait_session)
        self.connections_made = 0
        self._lane_numbers = itertools.count(1)

    # --- lifecycle --------------------------------------------------------------------------------

    @property
    def connected(self) -> bool:
        """The main connection is open and the bridge's flavour is known."""
        return self._session is not None and self._session.is_open

    @property
    def session(self) -> Session | None:
        """The current session (main connection and what is known of its bridge), or None while down."""
        session = self._session
        return session if session is not None and session.is_open else None

    @property
    def closed(self) -> bool:
        """``close()`` was called."""
        return self._closed

    @property
    def lanes(self) -> LanePool:
        """The pool of single-call lanes (for diagnostics)."""
        return self._lanes

    @property
    def watchers(self) -> tuple[SessionWatcher, ...]:
        """Who is told of new sessions and of ``close()`` (diagnostics and tests)."""
        return tuple(self._watchers)

    def watch(self, watcher: SessionWatcher) -> None:
        """Tell *watcher* of every new session and of ``close()``."""
        self._watchers.append(watcher)

    async def start(self) -> None:
        """Start the background connect/reconnect loop; returns at once."""
        if self._closed:
            raise RuntimeError("this RosbridgeClient is closed")
        if self._runner is not None:
            return
        self._attempts.start()
        self._runner = asyncio.create_task(self._run(), name=f"rosbridge connect loop ({self.url})")

    async def __aenter__(self) -> Self:
        await self.start()
        return self

    async def __aexit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.close()

    async def close(self) -> None:
        """Let watchers cancel what runs, unadvertise, close every socket. Idempotent."""
        if self._closed:
            return
        self._closed = True
        self._closing = True
        self._attempts.stop()
        if self._measuring is not None:
            self._measuring.cancel()
        session = self.session
        for watcher in self._watchers:
            await watcher.client_closing(session)
        if session is not None and self.unhandled_acts:
            # Both rosbridge lines drop the frames of a closing connection they have not handled yet: the
            # last zero velocity or goal cancel would never act.
            await session.handled(_CLOSE_HANDLED_SECONDS)
        if session is not None:
            await self.topics.unadvertise_all(session)
        if self._runner is not None:
            self._runner.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._runner
        lanes = self._lanes.close_all() + self._goal_lanes.take_all()
        await asyncio.gather(*(lane.aclose() for lane in lanes), return_exceptions=True)
        main = self._session.connection if self._session is not None else None
        if main is not None:
            await main.aclose()
        self._set_disconnected(main, "the client was closed")
        self.topics.close_all(NotConnectedError(self.url, "the client was closed"))
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
                self.url, f"no connection within {timeout:g} s; last error: {self._attempts.last_reason}"
            ) from None

    async def wait_disconnected(self, timeout: float) -> None:
        """Wait until the main connection is down (diagnostics and tests); raises TimeoutError."""
        async with asyncio.timeout(timeout):
            await self._disconnected_event.wait()

    # --- the connect loop ---------------------------------------------------------------------------

    async def _run(self) -> None:
        failures = 0
        while not self._closing:
            attempt_done = self._attempts.begin()
            served = False
            try:
                session = await open_session(
                    lambda: self._dial("main", self.connect_timeout, self.topics.deliver),
                    self._ids,
                    self.url,
                    number=self.connections_made + 1,
                    detect_timeout=min(self.connect_timeout, self.request_timeout),
                    prepare=self.topics.restore,
                )
            except NotConnectedError as exc:
                self._attempts.failed(exc.reason, timed_out=exc.timed_out)
                failures += 1
                if failures == 1:
                    logger.warning(
                        "Cannot reach rosbridge at %s (%s); retrying in the background", self.url, exc.reason
                    )
                else:
                    logger.debug("rosbridge at %s still unreachable (%s)", self.url, exc.reason)
            except Exception as exc:
                reason = f"{type(exc).__name__}: {exc}"
                self._attempts.failed(reason)
                failures += 1
                logger.warning("Setting up the connection to %s failed: %s", self.url, reason)
            else:
                self._session = session
                self._attempts.succeeded()
                self.connections_made += 1
                self._disconnected_event.clear()
                self._connected_event.set()
                attempt_done.set()
                logger.info(
                    "%s rosbridge at %s: %s",
                    "Reconnected to" if session.number > 1 else "Connected to",
                    self.url,
                    session.info.describe(),
                )
                failures = 0
                if not session.ordering_known.is_set():
                    self._measuring = self.run_in_background(
                        self._measure_ordering(session), "measure call ordering"
                    )
                for watcher in self._watchers:
                    watcher.session_started(session)
                served = True
                conn = session.connection
                await conn.closed.wait()
                reason = conn.close_reason or "the connection closed"
                self._set_disconnected(conn, reason)
                if not self._closing:
                    logger.warning(
                        "Lost the connection to rosbridge at %s (%s); reconnecting", self.url, reason
                    )
            finally:
                self._attempts.ended(attempt_done, served=served)
            await self._attempts.pause()

    def _set_disconnected(self, conn: Connection | None, reason: str) -> None:
        if conn is not None and self._session is not None and self._session.connection is conn:
            self._session = None
            self._attempts.last_reason = reason
        self._connected_event.clear()
        self._disconnected_event.set()
        # Idle lanes belong to the old bridge session; busy ones fail on their own when it is gone.
        self._lanes.drop_idle()
        self.topics.fail_all(ConnectionLostError(self.url, "messages"))

    async def _wait_session(self, deadline: float | None = None) -> Session:
        """The open session, waiting only for a connection attempt under way (or prompted now).

        Between attempts, a call prompts one at once rather than failing until the backoff runs out; it waits
        for that attempt (bounded by the connect timeout and *deadline*), never for a later one. Nothing is
        queued: the caller sends its request itself, now, or gets :class:`NotConnectedError`.
        """
        session = self.session
        if session is not None:
            return session
        if self._closed:
            raise NotConnectedError(self.url, "the client is closed")
        if self._attempts.timed_out:
            # Waiting out another handshake would cost every call the whole connect timeout: the attempt is
            # prompted, not awaited, so a later call finds the connection if the bridge answers again.
            self._attempts.prompt()
            raise NotConnectedError(self.url, self._attempts.last_reason)
        await self._attempts.wait_for_one(self.connect_timeout, deadline)
        session = self.session
        if session is not None:
            return session
        raise NotConnectedError(self.url, self._attempts.last_reason)

    def require_session(self) -> Session:
        """The open session, or :class:`NotConnectedError` at once (for sends that must never wait)."""
        session = self.session
        if session is None:
            raise NotConnectedError(self.url, self._attempts.last_reason)
        return session

    async def ros_info(self) -> RosInfo:
        """What the bridge is: ROS version and distro, detected once per connection."""
        return (await self._wait_session()).info

    async def dialect(self) -> Dialect:
        """How the bridge spells types and time fields (one :class:`Dialect` per connection)."""
        return (await self._wait_session()).dialect

    async def capabilities(self) -> BridgeCapabilities:
        """What the bridge can do (decided once per connection, :mod:`.capabilities`)."""
        return (await self._wait_session()).capabilities

    # --- background helpers -------------------------------------------------------------------------

    def run_in_background(self, coro: Coroutine[Any, Any, Any], name: str) -> asyncio.Task[Any]:
        """Run *coro* as a task the client keeps (and waits for on ``close()``)."""
        task = asyncio.get_running_loop().create_task(coro, name=name)
        self._background.add(task)
        task.add_done_callback(self._background.discard)
        return task

    async def _measure_ordering(self, session: Session) -> None:
        """Measure whether the bridge holds a connection's calls up behind each other; lanes stay until then.

        Only where the bridge's answers did not tell (see :mod:`.ordering`); a failed measurement keeps the
        safe assumption, in order.
        """
        try:
            queued = await call_ordering(
                self.url,
                session.info.version,
                min(max(self.request_timeout, 2.0), _ORDERING_LIMIT_SECONDS),
                hold=_ORDERING_HOLD_SECONDS,
                dial=self._transport,
            )
        except asyncio.CancelledError:
            raise
        except Exception as exc:
            logger.info(
                "Could not measure whether %s holds calls up behind each other (%s: %s); every call gets a "
                "connection of its own",
                self.url,
                type(exc).__name__,
                exc,
            )
        else:
            session.lanes_by_default = queued
            logger.info(
                "rosbridge at %s %s",
                self.url,
                "holds a connection's calls up behind a slow one: every call gets a connection of its own"
                if queued
                else "runs a connection's calls side by side (measured)",
            )
        finally:
            session.ordering_known.set()

    def _close_in_background(self, conn: Connection) -> None:
        self.run_in_background(conn.aclose(), f"close {conn.name}")

    async def _open_lane(self, timeout: float) -> Connection:
        return await self._dial(f"lane {next(self._lane_numbers)}", min(timeout, self.connect_timeout))

    async def _dial(
        self, name: str, timeout: float, on_publish: Callable[[protocol.PublishEvent], None] | None = None
    ) -> Connection:
        return await open_connection(
            self._transport, self.url, name, timeout, on_publish=on_publish, send_timeout=self.request_timeout
        )

    # --- services -----------------------------------------------------------------------------------

    async def call_service(
        self,
        service: str,
        args: dict[str, Any] | list[Any] | None = None,
        *,
        timeout: float | None = None,
        isolated: bool | None = None,
        check: Callable[[], None] | None = None,
    ) -> Any:
        """Call a ROS service and return its response fields (``values``).

        Time fields in *args* are respelled for ROS 1, which ignores ``sec``/``nanosec``. Runs on the shared
        connection, or on a lane of its own when the bridge may handle one
        connection in order, when another call is in flight on a ROS 1 connection (see
        :attr:`RosInfo.one_call_per_connection`), or when *isolated* is true. Raises :class:`ServiceError`
        with the bridge's text, :class:`RequestTimeoutError`, :class:`ConnectionLostError`,
        :class:`NotConnectedError`. *check* (the send gate) is called right before the call's frame is
        written, after a lane is opened for it; what it raises ends the call unsent.
        """
        t = self.request_timeout if timeout is None else timeout
        session = self._session
        if session is None or not session.is_open:
            session = await self._wait_session(asyncio.get_running_loop().time() + t)
        args = session.dialect.outgoing(args)
        if isolated or (
            isolated is None
            and (session.lanes_by_default or (session.spread_calls and session.connection.pending))
        ):
            return await call_on_lane(
                self._lanes,
                self._ids,
                service,
                args,
                t,
                send_timeout=session.send_service_timeout,
                check=check,
            )
        if check is not None:
            check()
        return await call_on(
            session.connection,
            self._ids,
            service,
            args,
            t,
            bridge_timeout=bridge_timeout(t) if session.send_service_timeout else None,
        )

    # --- topics -------------------------------------------------------------------------------------

    async def advertise(
        self, topic: str, msg_type: str, *, latch: bool = False, queue_size: int = 10
    ) -> None:
        """Advertise *topic* now (``publish`` does this on first use); restored after reconnects."""
        await self.topics.advertise(
            self.require_session(), topic, msg_type, latch=latch, queue_size=queue_size
        )

    async def publish(
        self,
        topic: str,
        msg_type: str,
        msg: dict[str, Any],
        *,
        latch: bool = False,
        queue_size: int = 10,
        session: Session | None = None,
    ) -> None:
        """Publish one message now, or raise :class:`NotConnectedError`. Never queued, never replayed.

        The topic is advertised once (per topic and type) and the advertisement reused; time
        fields are respelled for ROS 1, which ignores ``sec``/``nanosec``. With *session*, only on that
        session (:class:`NotConnectedError` if it is gone).
        """
        await self.topics.publish(
            session or self.require_session(), topic, msg_type, msg, latch=latch, queue_size=queue_size
        )
        self.unhandled_acts = True

    async def unadvertise(self, topic: str) -> None:
        """Stop advertising *topic* (our advertisement only)."""
        await self.topics.unadvertise(topic)

    def subscribe(
        self,
        topic: str,
        msg_type: str | None = None,
        *,
        throttle_rate: int = 0,
        queue_length: int = 0,
        max_queue: int = 1000,
        qos: dict[str, Any] | None = None,
        compression: Literal["cbor"] | None = None,
    ) -> Subscription:
        """A :class:`Subscription` (``async with client.subscribe("/chatter") as sub: ...``).

        ``qos`` is sent as the ROS 2 ``qos`` object (read by rosbridge 2.0.7 / 2.7.0 / 3.3.0 and later).
        ``compression="cbor"`` asks for binary CBOR frames: numeric arrays then arrive as ``array.array``
        and ``uint8[]`` as bytes (far faster for large maps); a bridge that ignores it sends JSON.
        """
        return self.topics.subscribe(
            topic,
            msg_type,
            throttle_rate=throttle_rate,
            queue_length=queue_length,
            max_queue=max_queue,
            qos=qos,
            compression=compression,
        )

    async def ping(self, timeout: float | None = None) -> float:
        """Round-trip a WebSocket ping on the main connection; returns the seconds it took.

        Proves the bridge reads the connection now: a frozen bridge, or a link that died without a close,
        still takes frames into the socket buffer and would act on them whenever it wakes up.
        :class:`RequestTimeoutError` if no pong within *timeout* (default ``request_timeout``),
        :class:`NotConnectedError` when there is no connection.
        """
        session = self.require_session()
        return await session.connection.ping(self.request_timeout if timeout is None else timeout)

    async def handled(self, timeout: float) -> bool:
        """Whether the bridge has handled everything sent so far on the main connection (one call's round
        trip, within *timeout*); ``False`` when there is no connection or no answer in time."""
        session = self.session
        return session is not None and await session.handled(timeout)

    # --- action goals: ids, lanes and cancels (what a goal means is robot/goals' job) ----------------

    def new_goal_id(self, action: str) -> str:
        """A goal id unique across every client of the bridge (rosbridge's goal table is process-wide)."""
        return self._ids.goal_id(action)

    async def open_goal_lane(self, action: str, goal_id: str, what: str, timeout: float) -> GoalLane:
        """A connection of its own for goal *goal_id* of *action*, opened within *timeout*; ``lane.close()``
        after. :class:`NotConnectedError` at once when there is no session (a goal is never queued)."""
        session = self.require_session()
        return await self._goal_lanes.open(action, goal_id, what, session.capabilities, timeout)

    async def cancel_goal(self, action: str, goal_id: str, lane: GoalLane | None = None) -> GoalCancel:
        """Send goal *goal_id*'s cancel on every connection a bridge may need it on; what reached it.

        The main connection first: on a bridge whose goals hold their connection up (2.1.0's and Humble's
        defaults) the goal's own *lane* reads its copy only after the goal ended. The lane's copy is for a
        bridge that lets only the starting connection cancel (rosbridge-server-rs, which refuses the main
        connection's copy with an error ``status``: expected here, so not logged). Each bridge acts on one of
        the two and ignores the other.
        """
        session = self.session
        if session is not None and session.capabilities.status_replies:
            conn = session.connection
            conn.expect(goal_id, f"the refusal of goal {goal_id}'s cancel", _REFUSAL_SECONDS)
            asyncio.get_running_loop().call_later(_REFUSAL_SECONDS, conn.forget, goal_id)
        on_main = session is not None and await session.try_cancel_goal(action, goal_id)
        if on_main:
            self.unhandled_acts = True
        on_lane = lane is not None and await lane.try_cancel()
        caps = (
            lane.capabilities if lane is not None else session.capabilities if session is not None else None
        )
        reaches = caps is not None and (
            (on_main and not caps.cancel_by_owner_only) or (on_lane and not caps.goals_hold_connection)
        )
        return GoalCancel(on_main, on_lane, reaches)

    async def cancel_goal_heard(self, action: str, goal_id: str, timeout: float) -> str | None:
        """Cancel goal *goal_id* (another client's, by its rosbridge id) on the main connection and tell
        whether the bridge refused it.

        Returns the bridge's refusal (an error ``status`` naming the goal: rosbridge-server-rs answers
        "unknown active goal" for a goal another connection started) if it came before the answer to a call
        sent after the cancel, else ``None``: rosbridge_suite cancels silently, and ignores an id it does
        not know just as silently. A refusal is also learnt: the session's capabilities then say
        ``cancel_by_owner_only``.
        """
        session = self.require_session()
        conn = session.connection
        heard = conn.expect(goal_id, f"a refusal of the cancel of goal {goal_id}", timeout)
        try:
            await session.cancel_goal(action, goal_id)
            self.unhandled_acts = True
            if not heard.done():
                await session.handled(timeout)
            if not heard.done() or heard.cancelled() or heard.exception() is not None:
                return None
            frame = heard.result()
        finally:
            conn.forget(goal_id)
        session.learn_cancel_by_owner_only()
        return str(frame.get("msg") or "the bridge refused the cancel")


@dataclass(frozen=True, slots=True)
class GoalCancel:
    """Where a goal's cancel went: on the main connection, on the goal's own lane, and whether one of them
    surely reaches the goal on this bridge (else the goal is cancelled again once a connection is back)."""

    on_main: bool
    on_lane: bool
    reaches: bool

    @property
    def sent(self) -> bool:
        """The cancel went out on at least one connection."""
        return self.on_main or self.on_lane


#: How long the main connection takes a refusal of our own goal's cancel as expected (not logged).
_REFUSAL_SECONDS: Final = 5.0
