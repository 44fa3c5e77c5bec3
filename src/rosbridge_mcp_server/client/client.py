"""``RosbridgeClient``: one shared WebSocket, background reconnects, lanes for in-order bridges."""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import logging
import ssl
from collections.abc import Callable, Coroutine, Sequence
from types import TracebackType
from typing import Any, Final, Protocol, Self

from rosbridge_mcp_server.client.calls import BridgeCalls
from rosbridge_mcp_server.client.capabilities import BridgeCapabilities
from rosbridge_mcp_server.client.connection import Connection, open_connection
from rosbridge_mcp_server.client.current import CurrentSession
from rosbridge_mcp_server.client.dialect import Dialect
from rosbridge_mcp_server.client.goal_lane import GoalLanes
from rosbridge_mcp_server.client.goals import ClientGoals, GoalHandle
from rosbridge_mcp_server.client.lanes import LanePool
from rosbridge_mcp_server.client.reconnect import Attempts, reconnect_cap
from rosbridge_mcp_server.client.session import BridgeSession, open_session
from rosbridge_mcp_server.client.topics import Topics
from rosbridge_mcp_server.client.transport import Dial, websocket_dial
from rosbridge_mcp_server.errors import ConnectionLostError, NotConnectedError
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.ros_versions import RosInfo

__all__ = ["RosbridgeClient", "SessionFacts", "SessionWatcher"]

logger = logging.getLogger("rosbridge_mcp_server.client")

#: How long :meth:`RosbridgeClient.close` waits for the bridge to handle what acted last.
_CLOSE_HANDLED_SECONDS: Final = 1.0


class SessionFacts(Protocol):
    """What a session watcher reads of a new connection (the connection itself stays inside ``client/``)."""

    @property
    def number(self) -> int:
        """1 for the first connection of a client, 2 after the first reconnect, ..."""
        ...

    @property
    def info(self) -> RosInfo: ...
    @property
    def dialect(self) -> Dialect: ...
    @property
    def capabilities(self) -> BridgeCapabilities: ...


class SessionWatcher(Protocol):
    """Told when a session starts and before the client closes (the log keeper, the service-type warm-up)."""

    def session_started(self, session: SessionFacts) -> None:
        """A new main connection is up (called in the connect loop: start tasks, do not wait)."""

    async def client_closing(self, session: SessionFacts | None) -> None:
        """``close()`` is about to close every socket; *session* is the open one, if any."""


class RosbridgeClient(BridgeCalls):
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
        # For wss:// with a private CA or a client certificate, and for a bridge behind an authenticating
        # proxy; every connection (main, lanes, the ordering probe's) opens with them. *transport* opens them
        # another way (the simulated robot's in memory): then the URL only names the bridge.
        dial = transport or websocket_dial(url, ssl_context=ssl_context, headers=headers)
        self.connect_timeout = connect_timeout
        self.reconnect_min = reconnect_min
        self.reconnect_max = max(reconnect_max, reconnect_min)
        #: The backoff's ceiling for this bridge (short on this machine and the local network).
        self.reconnect_cap = max(reconnect_cap(url, self.reconnect_max), reconnect_min)
        self._attempts = Attempts(reconnect_min, self.reconnect_cap)
        self._current = CurrentSession(url, self._attempts, connect_timeout)
        self._runner: asyncio.Task[None] | None = None
        self._closing = False
        self._connected_event = asyncio.Event()
        self._disconnected_event = asyncio.Event()
        self._disconnected_event.set()
        self._watchers: list[SessionWatcher] = []
        self._background: set[asyncio.Task[Any]] = set()
        self._measuring: asyncio.Task[Any] | None = None
        ids = protocol.IdMinter()
        super().__init__(
            url,
            self._current,
            transport=dial,
            ids=ids,
            lanes=LanePool(
                self._open_lane, self._close_in_background, cap=lane_cap, idle_seconds=lane_idle_seconds
            ),
            topics=Topics(url, ids, lambda: self._current.session, self._current.wait),
            request_timeout=request_timeout,
        )
        #: The goals sent through this client: open ones, and those a drop cut off (:mod:`.goals`).
        self.goals = ClientGoals(self, GoalLanes(url, self._open_lane, self._close_in_background))
        self.connections_made = 0
        self._lane_numbers = itertools.count(1)

    # --- lifecycle --------------------------------------------------------------------------------

    @property
    def connected(self) -> bool:
        """The main connection is open and the bridge's flavour is known."""
        return self._current.session is not None

    @property
    def session(self) -> BridgeSession | None:
        """The current session (main connection and what is known of its bridge), or None while down: for
        ``client/`` alone (the layers above read :attr:`session_facts`)."""
        return self._current.session

    @property
    def session_facts(self) -> SessionFacts | None:
        """What is known of the bridge behind the open connection (number, ``RosInfo``, dialect,
        capabilities), or None while down."""
        return self._current.session

    @property
    def closed(self) -> bool:
        """``close()`` was called."""
        return self._current.closed

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
        if self._current.closed:
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
        if self._current.closed:
            return
        self._current.closed = True
        self._closing = True
        self._attempts.stop()
        if self._measuring is not None:
            self._measuring.cancel()
        session = self.session
        await self.goals.closing()
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
        lanes = self._lanes.close_all() + self.goals.lanes.take_all()
        await asyncio.gather(*(lane.aclose() for lane in lanes), return_exceptions=True)
        held = self._current.held
        main = held.connection if held is not None else None
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
        if self._current.closed:
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
                self._started(session, attempt_done)
                failures = 0
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

    def _started(self, session: BridgeSession, attempt_done: asyncio.Event) -> None:
        """*session* is up: it is the client's now; the goals and the watchers are told."""
        self._current.held = session
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
        if not session.ordering_known.is_set():
            self._measuring = self.run_in_background(self._measure_ordering(session), "measure call ordering")
        self.goals.session_started(session)
        for watcher in self._watchers:
            watcher.session_started(session)

    def _set_disconnected(self, conn: Connection | None, reason: str) -> None:
        held = self._current.held
        if conn is not None and held is not None and held.connection is conn:
            self._current.held = None
            self._attempts.last_reason = reason
        self._connected_event.clear()
        self._disconnected_event.set()
        # Idle lanes belong to the old bridge session; busy ones fail on their own when it is gone.
        self._lanes.drop_idle()
        self.topics.fail_all(ConnectionLostError(self.url, "messages"))

    def require_session(self) -> BridgeSession:
        """The open session, or :class:`NotConnectedError` at once (for sends that must never wait)."""
        return self._current.require()

    async def _wait_session(self) -> BridgeSession:
        return await self._current.wait()

    async def ros_info(self) -> RosInfo:
        """What the bridge is: ROS version and distro, detected once per connection."""
        return (await self._wait_session()).info

    async def dialect(self) -> Dialect:
        """How the bridge spells types and time fields (one :class:`Dialect` per connection)."""
        return (await self._wait_session()).dialect

    async def capabilities(self) -> BridgeCapabilities:
        """What the bridge can do (decided once per connection, :mod:`.capabilities`)."""
        return (await self._wait_session()).capabilities

    # --- goals -------------------------------------------------------------------------------------------

    def new_goal_id(self, action: str) -> str:
        """A goal id unique across every client of the bridge (rosbridge's goal table is process-wide)."""
        return self._ids.goal_id(action)

    async def start_goal(
        self,
        action: str,
        action_type: str,
        goal: dict[str, Any],
        *,
        goal_id: str | None = None,
        timeout: float,
        check: Callable[[], None] | None = None,
    ) -> GoalHandle:
        """Send *goal* to action *action* and return its :class:`GoalHandle` (``aclose()`` it after).

        ROS 2: on a connection of its own, opened within *timeout*. ROS 1: over actionlib's topics, once the
        action server's status came (within *timeout* and 3 s; else :class:`ActionError`). *action_type* as
        the bridge spells it (``Dialect.action_type``). *check* (the send gate) is called right before the
        goal goes out; what it raises ends the start unsent. :class:`NotConnectedError` at once when there is
        no connection: a goal is never queued.
        """
        return await self.goals.start(
            action, action_type, goal, goal_id=goal_id, timeout=timeout, check=check
        )

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
        return await self._dial(f"lane {next(self._lane_numbers)}", min(timeout, self.connect_timeout))

    async def _dial(
        self, name: str, timeout: float, on_publish: Callable[[protocol.PublishEvent], None] | None = None
    ) -> Connection:
        return await open_connection(
            self._transport, self.url, name, timeout, on_publish=on_publish, send_timeout=self.request_timeout
        )
