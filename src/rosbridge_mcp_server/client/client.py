"""``RosbridgeClient``: one shared WebSocket, background reconnects, lanes for in-order bridges."""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import itertools
import logging
import math
import random
import ssl
from collections.abc import Coroutine, Sequence
from types import TracebackType
from typing import Any, Final, Protocol, Self
from urllib.parse import urlsplit

from rosbridge_mcp_server.client.connection import Connection, open_connection
from rosbridge_mcp_server.client.detect import detect
from rosbridge_mcp_server.client.goal_lane import GoalLane
from rosbridge_mcp_server.client.lanes import LanePool
from rosbridge_mcp_server.client.services import bridge_timeout, call_on, call_on_lane
from rosbridge_mcp_server.client.session import Session
from rosbridge_mcp_server.client.subscription import Subscription
from rosbridge_mcp_server.client.topics import Topics
from rosbridge_mcp_server.errors import ConnectionLostError, NotConnectedError
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.dialect import RosInfo

__all__ = ["LOCAL_RECONNECT_MAX", "PROMPT_SPACING", "RosbridgeClient", "SessionWatcher", "reconnect_cap"]

logger = logging.getLogger("rosbridge_mcp_server.client")

#: Longest wait between connection attempts to a bridge on this machine or the local network. An attempt there
#: costs a refused connect (or a few packets), so retrying twice a second is cheap, and the robot is back in
#: use within about half a second of its bridge, however long it was gone.
LOCAL_RECONNECT_MAX: Final = 0.5
#: A call that finds no connection prompts an attempt at once, but not sooner than this after the last one
#: ended: a burst of calls against a dead bridge costs at most ten attempts a second.
PROMPT_SPACING: Final = 0.1
#: How long :meth:`RosbridgeClient.close` waits for the bridge to handle what acted last.
_CLOSE_HANDLED_SECONDS: Final = 1.0


def reconnect_cap(url: str, reconnect_max: float) -> float:
    """The longest wait between connection attempts for the bridge at *url*.

    Loopback and local-network hosts (private, link-local and unique-local addresses, ``localhost``, names
    ending in ``.local`` or without a dot) get :data:`LOCAL_RECONNECT_MAX`; other hosts *reconnect_max*, so
    a remote bridge is not tried more than every few seconds, while a tool call still prompts an attempt at
    once. Decided from the URL alone (no name lookup).
    """
    host = (urlsplit(url).hostname or "").rstrip(".").lower()
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        local = host == "localhost" or host.endswith((".localhost", ".local")) or "." not in host
    else:
        local = address.is_loopback or address.is_private or address.is_link_local
    return min(reconnect_max, LOCAL_RECONNECT_MAX) if local else reconnect_max


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
    ) -> None:
        self.url = url
        # For wss:// with a private CA or a client certificate, and for a bridge behind an authenticating
        # proxy; every connection (main and lanes) opens with them.
        self._ssl = ssl_context
        self._headers = tuple(headers)
        self.connect_timeout = connect_timeout
        self.request_timeout = request_timeout
        self.reconnect_min = reconnect_min
        self.reconnect_max = max(reconnect_max, reconnect_min)
        #: The backoff's ceiling for this bridge (short on this machine and the local network).
        self.reconnect_cap = max(reconnect_cap(url, self.reconnect_max), reconnect_min)
        self._ids = protocol.IdMinter()
        self._session: Session | None = None
        self._last_reason: str | None = "not started"
        self._runner: asyncio.Task[None] | None = None
        self._closing = False
        self._closed = False
        #: Something that acts (a publish, a goal cancel) went out on the main connection, and the bridge may
        #: not have handled it yet: :meth:`close` waits for it first.
        self.unhandled_acts = False
        self._attempt_done: asyncio.Event | None = None
        # Set by a call that finds no connection: the connect loop stops waiting and tries at once.
        self._wake = asyncio.Event()
        self._last_attempt_end = -math.inf
        # The last attempt got no WebSocket answer in time (a port that accepts but never completes the
        # handshake, a host that drops packets): calls then fail at once instead of each waiting out the
        # connect timeout again, while the loop keeps trying.
        self._last_attempt_timed_out = False
        self._connected_event = asyncio.Event()
        self._disconnected_event = asyncio.Event()
        self._disconnected_event.set()
        self._watchers: list[SessionWatcher] = []
        self._goal_lanes: set[GoalLane] = set()
        self._background: set[asyncio.Task[Any]] = set()
        self._lanes = LanePool(
            self._open_lane, self._close_in_background, cap=lane_cap, idle_seconds=lane_idle_seconds
        )
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

    def watch(self, watcher: SessionWatcher) -> None:
        """Tell *watcher* of every new session and of ``close()``."""
        self._watchers.append(watcher)

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
        """Let watchers cancel what runs, unadvertise, close every socket. Idempotent."""
        if self._closed:
            return
        self._closed = True
        self._closing = True
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
        lanes = self._lanes.close_all() + [lane.connection for lane in self._goal_lanes]
        self._goal_lanes.clear()
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
        loop = asyncio.get_running_loop()
        while not self._closing:
            self._wake.clear()
            if self._attempt_done is None or self._attempt_done.is_set():
                self._attempt_done = asyncio.Event()
            attempt_done = self._attempt_done
            conn: Connection | None = None
            served = False
            try:
                conn = await open_connection(
                    self.url,
                    "main",
                    self.connect_timeout,
                    self.topics.deliver,
                    self.request_timeout,
                    ssl_context=self._ssl,
                    headers=self._headers,
                )
                info = await detect(
                    conn, self._ids, self.url, min(self.connect_timeout, self.request_timeout)
                )
                session = Session(conn, info, self.connections_made + 1)
                await self.topics.restore(session)
            except asyncio.CancelledError:
                # close() cancelled us mid-setup: the half-set-up socket is not the session's, so
                # nobody else would close it.
                if conn is not None:
                    await conn.aclose()
                raise
            except NotConnectedError as exc:
                self._last_reason = exc.reason
                self._last_attempt_timed_out = exc.timed_out
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
                self._session = session
                self._last_reason = None
                self._last_attempt_timed_out = False
                self.connections_made += 1
                self._disconnected_event.clear()
                self._connected_event.set()
                attempt_done.set()
                logger.info(
                    "%s rosbridge at %s: %s",
                    "Reconnected to" if session.number > 1 else "Connected to",
                    self.url,
                    info.describe(),
                )
                failures = 0
                for watcher in self._watchers:
                    watcher.session_started(session)
                delay = self.reconnect_min
                served = True
                await conn.closed.wait()
                reason = conn.close_reason or "the connection closed"
                self._set_disconnected(conn, reason)
                if not self._closing:
                    logger.warning(
                        "Lost the connection to rosbridge at %s (%s); reconnecting", self.url, reason
                    )
            finally:
                if not served:
                    # A failed attempt (not the end of a session): prompts wait a moment before the next.
                    self._last_attempt_end = loop.time()
                attempt_done.set()
            sleep = random.uniform(delay / 2, delay)
            delay = min(delay * 2, self.reconnect_cap)
            # No attempt is in progress while we wait; a call that needs the connection wakes us (see
            # _prompt_attempt) instead of failing until the backoff runs out.
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(sleep):
                    await self._wake.wait()

    def _set_disconnected(self, conn: Connection | None, reason: str) -> None:
        if conn is not None and self._session is not None and self._session.connection is conn:
            self._session = None
            self._last_reason = reason
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
        if self._last_attempt_timed_out:
            # Waiting out another handshake would cost every call the whole connect timeout: the attempt is
            # prompted, not awaited, so a later call finds the connection if the bridge answers again.
            self._prompt_attempt()
            raise NotConnectedError(self.url, self._last_reason)
        attempt = self._attempt_done
        if attempt is None or attempt.is_set():
            attempt = self._prompt_attempt()
        if attempt is not None and not attempt.is_set():
            loop = asyncio.get_running_loop()
            # The attempt is bounded by the connect timeout itself; the margin lets it report why it failed.
            until = loop.time() + self.connect_timeout + 1.0
            if deadline is not None:
                until = min(until, deadline)
            try:
                async with asyncio.timeout_at(until):
                    await attempt.wait()
            except TimeoutError:
                pass
            session = self.session
            if session is not None:
                return session
        raise NotConnectedError(self.url, self._last_reason)

    def _prompt_attempt(self) -> asyncio.Event | None:
        """Wake the connect loop for an attempt now; the event set when it is done (None: not now)."""
        if self._runner is None or self._closing:
            return None
        if asyncio.get_running_loop().time() - self._last_attempt_end < PROMPT_SPACING:
            return None
        if self._attempt_done is None or self._attempt_done.is_set():
            self._attempt_done = asyncio.Event()
        self._wake.set()
        return self._attempt_done

    def require_session(self) -> Session:
        """The open session, or :class:`NotConnectedError` at once (for sends that must never wait)."""
        session = self.session
        if session is None:
            raise NotConnectedError(self.url, self._last_reason)
        return session

    async def ros_info(self) -> RosInfo:
        """What the bridge is: ROS version and distro, detected once per connection."""
        return (await self._wait_session()).info

    # --- background helpers -------------------------------------------------------------------------

    def run_in_background(self, coro: Coroutine[Any, Any, Any], name: str) -> asyncio.Task[Any]:
        """Run *coro* as a task the client keeps (and waits for on ``close()``)."""
        task = asyncio.get_running_loop().create_task(coro, name=name)
        self._background.add(task)
        task.add_done_callback(self._background.discard)
        return task

    def _close_in_background(self, conn: Connection) -> None:
        self.run_in_background(conn.aclose(), f"close {conn.name}")

    async def _open_lane(self, timeout: float) -> Connection:
        return await open_connection(
            self.url,
            f"lane {next(self._lane_numbers)}",
            min(timeout, self.connect_timeout),
            send_timeout=self.request_timeout,
            ssl_context=self._ssl,
            headers=self._headers,
        )

    # --- services -----------------------------------------------------------------------------------

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
        connection in order, when another call is in flight on a ROS 1 connection (see
        :attr:`RosInfo.one_call_per_connection`), or when *isolated* is true. Raises :class:`ServiceError`
        with the bridge's text, :class:`RequestTimeoutError`, :class:`ConnectionLostError`,
        :class:`NotConnectedError`.
        """
        t = self.request_timeout if timeout is None else timeout
        session = self._session
        if session is None or not session.is_open:
            session = await self._wait_session(asyncio.get_running_loop().time() + t)
        if isolated or (
            isolated is None
            and (session.lanes_by_default or (session.spread_calls and session.connection.pending))
        ):
            return await call_on_lane(
                self._lanes, self._ids, service, args, t, send_timeout=session.send_service_timeout
            )
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
    ) -> Subscription:
        """A :class:`Subscription` (``async with client.subscribe("/chatter") as sub: ...``).

        ``qos`` is sent as the ROS 2 ``qos`` object (read by rosbridge 2.0.7 / 2.7.0 / 3.3.0 and later).
        """
        return self.topics.subscribe(
            topic,
            msg_type,
            throttle_rate=throttle_rate,
            queue_length=queue_length,
            max_queue=max_queue,
            qos=qos,
        )

    async def wait_for_message(self, topic: str, msg_type: str | None, timeout: float) -> dict[str, Any]:
        """The next message on *topic*, within *timeout* seconds."""
        async with self.subscribe(topic, msg_type, max_queue=1) as sub:
            return await sub.get(timeout)

    async def ping(self, timeout: float | None = None) -> float:
        """Round-trip a WebSocket ping on the main connection; returns the seconds it took.

        Proves the bridge reads the connection now: a frozen bridge, or a link that died without a close,
        still takes frames into the socket buffer and would act on them whenever it wakes up.
        :class:`RequestTimeoutError` if no pong within *timeout* (default ``request_timeout``),
        :class:`NotConnectedError` when there is no connection.
        """
        session = self.require_session()
        return await session.connection.ping(self.request_timeout if timeout is None else timeout)

    # --- action goals: ids, lanes and the cancel op (what a goal means is robot/goals' job) ---------

    def new_goal_id(self, action: str) -> str:
        """A goal id unique across every client of the bridge (rosbridge's goal table is process-wide)."""
        return self._ids.goal_id(action)

    async def open_goal_lane(self, goal_id: str, what: str, timeout: float) -> GoalLane:
        """A connection of its own for goal *goal_id*, opened within *timeout*; ``lane.close()`` after."""
        try:
            conn = await self._open_lane(timeout)
        except NotConnectedError as exc:
            raise NotConnectedError(self.url, f"could not open a lane for the goal: {exc.reason}") from None
        lane = GoalLane(conn, goal_id, what, self._forget_goal_lane)
        self._goal_lanes.add(lane)
        return lane

    def _forget_goal_lane(self, lane: GoalLane) -> None:
        self._goal_lanes.discard(lane)
        self._close_in_background(lane.connection)

    async def cancel_action_goal(self, action: str, goal_id: str) -> None:
        """Ask the bridge to cancel goal *goal_id*, on the main connection.

        rosbridge keeps one goal table per process, so this reaches a goal running on a lane (or
        on another client's connection) too. No reply comes; the goal's result says what happened.
        """
        await self.require_session().send(protocol.cancel_action_goal(action, id=goal_id))
        self.unhandled_acts = True
