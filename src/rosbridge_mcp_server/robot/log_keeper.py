"""What a robot session keeps watching from the moment the server connects: the robot's log, and the graph
as it was then.

:class:`LogKeeper` is a session watcher (``client.watch``): on every (re)connect it makes sure one
subscription to the robot's log is open, in the background, so nothing a tool does waits for it. The log is
``/rosout`` (ROS 2: ``rcl_interfaces/msg/Log``), or on ROS 1 ``/rosout_agg`` when the graph has it (the
``rosout`` node passes every node's line on there: one publisher for rosbridge to follow instead of one per
node), else ``/rosout``. The subscription is the client's, so a reconnect restores it; its lines go into a
:class:`~rosbridge_mcp_server.robot.logs.LogRing`. ``/diagnostics`` (and ``/diagnostics_agg``) the same way,
into a :class:`~rosbridge_mcp_server.robot.diagnostics.StatusBoard`: drivers report about once a second, too
slowly to catch every one in a short look.

It also keeps what ``diagnose`` compares with: the node names at connect (and at its last look), and the
rates it last measured.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import NotConnectedError, RosbridgeError
from rosbridge_mcp_server.robot.diagnostics import StatusBoard
from rosbridge_mcp_server.robot.logs import LogRing, line_of
from rosbridge_mcp_server.robot.nodes import node_names

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient, SessionFacts, Subscription
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["DIAGNOSTICS_TOPICS", "LOG_QUEUE", "LogKeeper"]

_log = logging.getLogger(__name__)
#: Log messages the subscription holds before the keeper takes them (a burst beyond it drops the oldest).
LOG_QUEUE = 20_000
#: The diagnostics topics followed when the graph has them.
DIAGNOSTICS_TOPICS = ("/diagnostics", "/diagnostics_agg")
#: Seconds before the topics are asked again after a failure, doubling up to RETRY_MOST.
RETRY_FIRST = 1.0
RETRY_MOST = 30.0


class LogKeeper:
    """The robot's log since the server connected, and the graph as the server first (and last) saw it."""

    def __init__(self, client: RosbridgeClient, graph: RosGraph) -> None:
        self._client = client
        self._graph = graph
        self.ring = LogRing()
        #: When the server first connected (``time.time()``), and when the log subscription opened.
        self.connected_at: float | None = None
        self.listening_since: float | None = None
        #: The topic read (``/rosout`` or ``/rosout_agg``); ``None`` while unknown or absent.
        self.source: str | None = None
        #: True when the robot's graph has no log topic (checked again on every reconnect).
        self.absent = False
        #: Set once the keeper knows: subscribed, or the robot has no log topic (or the subscribe failed).
        self.ready = asyncio.Event()
        #: Set once the first look at the graph (topics, nodes) has ended, however it ended.
        self.looked = asyncio.Event()
        #: The node names at connect, then at diagnose's last look.
        self.nodes_seen: set[str] | None = None
        self.nodes_seen_at: float | None = None
        #: Rates (Hz) diagnose measured last, by topic.
        self.rates: dict[str, float] = {}
        #: The latest /diagnostics (and /diagnostics_agg) status per name and hardware id.
        self.board = StatusBoard()
        #: True when the robot's graph has neither topic.
        self.diagnostics_absent = False
        self._subs: dict[str, Subscription] = {}
        self._task: asyncio.Task[None] | None = None

    # --- the session watcher ------------------------------------------------------------------------------

    def session_started(self, session: SessionFacts) -> None:
        """Open the log subscription if it is not open yet (a reconnect restores an open one)."""
        if self.connected_at is None:
            self.connected_at = time.time()
        if self._task is None or self._task.done():
            self._task = self._client.run_in_background(self._follow(session), "keep the robot's log")

    async def client_closing(self, session: SessionFacts | None) -> None:
        if self._task is not None:
            self._task.cancel()

    # --- reading ---------------------------------------------------------------------------------------

    async def _follow(self, session: SessionFacts) -> None:
        topics = await self._topics(session)
        if topics is None:
            return
        await self._look(session)
        self.looked.set()
        source = "/rosout"
        if session.dialect.version == 1 and topics.get("/rosout_agg"):
            source = "/rosout_agg"
        log_type = topics.get(source)
        self.absent = not log_type
        readers = []
        if log_type:
            readers.append(self._read(source, log_type, self._log_line))
        for topic in DIAGNOSTICS_TOPICS:
            if topics.get(topic):
                readers.append(self._read(topic, topics[topic], self._status))
        self.diagnostics_absent = not any(topics.get(topic) for topic in DIAGNOSTICS_TOPICS)
        if not readers:
            self.ready.set()
            return
        await asyncio.gather(*readers)

    async def _topics(self, session: SessionFacts) -> dict[str, str] | None:
        """The graph's topics and types, asked again after a failure (a busy bridge may not answer rosapi in
        time) until the connection ends: then None, and the next connection starts a new follow."""
        delay = RETRY_FIRST
        while True:
            try:
                return {entry.name: entry.type for entry in await self._graph.topics()}
            except NotConnectedError as exc:
                _log.debug("no log kept on connection %d: %s", session.number, exc)
                self.looked.set()
                return None
            except RosbridgeError as exc:
                _log.debug(
                    "could not list the topics to find the log on connection %d (%s); again in %g s",
                    session.number,
                    exc,
                    delay,
                )
                self.looked.set()
                await asyncio.sleep(delay)
                delay = min(delay * 2, RETRY_MOST)

    def _log_line(self, topic: str, msg: dict[str, Any], now: float) -> None:
        self.ring.add(line_of(msg, now))

    def _status(self, topic: str, msg: dict[str, Any], now: float) -> None:
        self.board.add_message(msg, topic, now)

    async def _read(
        self, topic: str, msg_type: str, handle: Callable[[str, dict[str, Any], float], None]
    ) -> None:
        sub = self._client.subscribe(topic, msg_type, max_queue=LOG_QUEUE)
        try:
            await sub.open()
        except RosbridgeError as exc:
            _log.debug("could not subscribe to %s: %s", topic, exc)
            self.ready.set()
            return
        self._subs[topic] = sub
        if handle == self._log_line:
            self.source, self.listening_since = topic, time.time()
            self.ready.set()
        try:
            while True:
                try:
                    msg = await sub.get()
                except NotConnectedError:
                    if sub.is_closed:
                        return
                    continue
                except RosbridgeError:
                    # The connection dropped; the client restores the subscription on the next one.
                    continue
                now = time.time()
                handle(topic, msg, now)
                while (more := sub.get_nowait()) is not None:
                    handle(topic, more, now)
        finally:
            self._subs.pop(topic, None)
            with contextlib.suppress(RosbridgeError):
                await asyncio.shield(sub.close())

    async def _look(self, session: SessionFacts) -> None:
        if self.nodes_seen is not None:
            return
        try:
            nodes = await node_names(self._graph)
        except RosbridgeError as exc:
            _log.debug("could not list the nodes on connection %d: %s", session.number, exc)
            return
        self.nodes_seen, self.nodes_seen_at = set(nodes), time.time()

    @property
    def dropped_by_queue(self) -> int:
        """Log messages the subscription's queue let go before the keeper took them."""
        sub = self._subs.get(self.source) if self.source else None
        return sub.dropped if sub is not None else 0
