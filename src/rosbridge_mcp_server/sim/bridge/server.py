"""The simulated rosbridge server: the core, its capabilities and the protocol, and each client connection's
life from connect to rosbridge's ``finish()``."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time

from websockets.exceptions import ConnectionClosed

from rosbridge_mcp_server.sim.bridge.capabilities import Actions, Fragments, Services, Topics
from rosbridge_mcp_server.sim.bridge.client_manager import ClientManager
from rosbridge_mcp_server.sim.bridge.core import BridgeConfig, BridgeCore, Capability, OpHandler
from rosbridge_mcp_server.sim.bridge.protocol import Protocol
from rosbridge_mcp_server.sim.connection import Connection, PeerSocket, dumps_standard, dumps_ujson
from rosbridge_mcp_server.sim.graph import Graph
from rosbridge_mcp_server.sim.interfaces import InterfaceRegistry
from rosbridge_mcp_server.sim.world import World

__all__ = ["Bridge"]

log = logging.getLogger("rosbridge_mcp_server.sim")


class Bridge(BridgeCore):
    """The rosbridge server process: connections, ops, and the routing of topic messages."""

    def __init__(self, config: BridgeConfig, registry: InterfaceRegistry, world: World, graph: Graph) -> None:
        super().__init__(config, registry, world, graph)
        self.connection_count = 0
        self._next_cid = 0
        self._readers: set[asyncio.Task[None]] = set()
        #: How long each client frame waits before it is handled (0 = at once): a busy bridge's incoming
        #: thread. rosbridge 2.x drops a connection's frames not yet handled when the connection closes, so
        #: with a delay a frame sent just before a close is lost, as on a loaded real bridge.
        self.incoming_delay = 0.0
        self.clients = ClientManager(self)
        self.topics = Topics(self)
        self.services = Services(self)
        self.actions = Actions(self)
        self.protocol = Protocol(self, {})
        fragments = Fragments(self, self.protocol.incoming)
        self.capabilities: list[Capability] = [fragments, self.topics, self.services, self.actions]
        ops: dict[str, OpHandler] = {}
        for capability in self.capabilities:
            ops.update(capability.ops())
        self.protocol.ops = ops

    @property
    def unregister_timeout(self) -> float:
        """0.11.17's ``unregister_timeout``: how long an unadvertised publisher lingers (ROS 1)."""
        return self.topics.unregister_timeout

    @unregister_timeout.setter
    def unregister_timeout(self, seconds: float) -> None:
        self.topics.unregister_timeout = seconds

    def add_client_topics(self) -> None:
        """rosbridge's latched ``/client_count`` and ``/connected_clients``."""
        self.clients.add_topics()

    async def incoming(self, conn: Connection, raw: str | bytes = "") -> None:
        """One frame from a client, through rosbridge's input buffer (see :class:`Protocol`)."""
        await self.protocol.incoming(conn, raw)

    # --- connections --------------------------------------------------------------------------------------

    async def serve_connection(self, ws: PeerSocket) -> None:
        """Run one client connection until it closes, then clean up after it like rosbridge does."""
        self._next_cid += 1
        conn = Connection(
            ws,
            self._next_cid,
            fragment_size=self.config.max_message_size,
            fragment_id=self.fragment_id,
            dumps=dumps_standard if self.ros2 else dumps_ujson,
        )
        self.connections[conn.id] = conn
        self.connection_count = len(self.connections)
        address = ws.remote_address[0] if ws.remote_address else ""
        self.clients.connected(conn.id, str(address), time.time())
        self.world.notify()
        log.info("client %d connected from %s", conn.id, ws.remote_address)
        writer = asyncio.create_task(conn.writer())
        # The reader is a task of its own: like rosbridge's incoming thread it may sit inside an in-order
        # service call or goal, while the socket's close is noticed (and cleaned up after) at once, as
        # Tornado's on_close does. A reader still blocked finishes its call later; its reply goes nowhere.
        reader = asyncio.create_task(self._read(conn))
        self._readers.add(reader)
        reader.add_done_callback(self._readers.discard)
        closed = asyncio.create_task(ws.wait_closed())
        try:
            await asyncio.wait([reader, closed], return_when=asyncio.FIRST_COMPLETED)
        finally:
            conn.closed = True
            for task in (closed, writer):
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
            # rosbridge's finish(): subscriptions and advertisements go. Advertised services are kept
            # (rosbridge 0.11 and 2.x do not remove them on disconnect), and goals keep running.
            for capability in self.capabilities:
                capability.client_gone(conn)
            del self.connections[conn.id]
            self.connection_count = len(self.connections)
            self.clients.disconnected(conn.id)
            self.world.notify()
            log.info("client %d disconnected", conn.id)

    async def _read(self, conn: Connection) -> None:
        try:
            async for raw in conn.ws:
                if self.incoming_delay > 0:
                    await asyncio.sleep(self.incoming_delay)
                if conn.closed:
                    break  # cleaned up already: frames still buffered would register things nobody removes
                await self.protocol.incoming(conn, raw)
        except ConnectionClosed:
            pass

    def cancel_all(self) -> None:
        """Stop everything running for clients: readers (also those blocked in-order), calls, goals' waits."""
        for task in list(self._readers):
            task.cancel()
        self.cancel_tasks()
        for capability in self.capabilities:
            capability.shutdown()
