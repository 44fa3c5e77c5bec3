"""One session with the bridge: the main connection and what was learnt on it, replaced whole on a reconnect.

Named ``BridgeSession`` (the client's, one per connection) to tell it from ``robot/session.py``'s
``RobotSession`` (one robot as this server drives it, for the server's life) and the MCP session (one
assistant's conversation with the server). It stays inside ``client/``: nothing above imports it.

Whatever depends on the bridge behind the connection (its ROS version and distro, whether it may handle
a connection in order, whether it honours a service call's ``timeout``) lives here, so a new connection
can never inherit a fact about the old one: the client swaps the whole object.
"""

from __future__ import annotations

import asyncio
import dataclasses
import itertools
import logging
from collections.abc import Awaitable, Callable
from typing import Any

from rosbridge_mcp_server.client.capabilities import BridgeCapabilities
from rosbridge_mcp_server.client.connection import Connection
from rosbridge_mcp_server.client.detect import detect
from rosbridge_mcp_server.client.dialect import Dialect
from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.ros_versions import RosInfo

__all__ = ["BridgeSession", "open_session", "send_quietly"]

logger = logging.getLogger("rosbridge_mcp_server.client")

_barrier_ids = itertools.count(1)


class BridgeSession:
    """The main connection to the bridge, with the bridge's :class:`RosInfo` detected on it."""

    __slots__ = (
        "connection",
        "dialect",
        "info",
        "lanes_by_default",
        "number",
        "ordering_known",
        "send_service_timeout",
        "spread_calls",
    )

    def __init__(self, connection: Connection, info: RosInfo, number: int) -> None:
        self.connection = connection
        self.info = info
        #: How this bridge spells types and time fields (what ``robot/`` asks instead of the ROS version).
        self.dialect = Dialect(info)
        #: 1 for the first connection of a client, 2 after the first reconnect, ...
        self.number = number
        caps = self.dialect.capabilities
        # Read off the capabilities once per connection, so the hot path does not look them up.
        self.lanes_by_default = caps.calls_may_queue
        #: Set once whether calls hold each other up is known (told by the bridge's answers, measured, or
        #: given up on: then the connection is taken to be in order). See :mod:`.ordering`.
        self.ordering_known = asyncio.Event()
        if info.version == 1 or info.calls_threaded is not None:
            self.ordering_known.set()
        self.spread_calls = caps.one_call_per_connection
        self.send_service_timeout = caps.service_timeout_field

    @property
    def capabilities(self) -> BridgeCapabilities:
        """What the bridge behind this session can do (decided once, in :mod:`.capabilities`)."""
        return self.dialect.capabilities

    def learn_cancel_by_owner_only(self) -> None:
        """The bridge refused to cancel a goal another connection started: only the starter may cancel."""
        caps = self.dialect.capabilities
        if not caps.cancel_by_owner_only:
            self.dialect.capabilities = dataclasses.replace(caps, cancel_by_owner_only=True)

    @property
    def is_open(self) -> bool:
        """The connection is open (it may still be dying: only :meth:`confirm` proves the bridge reads it)."""
        return self.connection.is_open

    async def send(self, op: dict[str, Any]) -> None:
        """Send one op on this session's connection; :class:`NotConnectedError` once it is closed."""
        await self.connection.send(op)

    async def try_send(self, op: dict[str, Any]) -> bool:
        """Send one op if the connection is open; False (and nothing raised) when it could not be sent."""
        return await send_quietly(self.connection, op)

    async def handled(self, timeout: float) -> bool:
        """Whether the bridge has handled (not only read) everything sent on this session so far.

        Both rosbridge lines (0.11.17, 2.1.0) pass a connection's frames to an incoming thread one at a time,
        and a close drops those it has not handled yet: a frame sent just before closing may never act. A
        reply to a call sent now comes only after the frames before it were handled; a pong does not.
        """
        rid = f"handled:{next(_barrier_ids)}"
        op = protocol.call_service("/rosapi/get_time", None, id=rid)
        try:
            await self.connection.request(rid, op, "a call to see earlier frames handled", timeout)
        except RosbridgeError:
            return False
        return True

    async def confirm(self, timeout: float) -> bool:
        """Whether the bridge has read everything sent on this session so far (a pong came back in time)."""
        if not self.connection.is_open:
            return False
        try:
            await self.connection.ping(timeout)
        except RosbridgeError:
            return False
        except Exception:
            logger.debug("ping on %s failed", self.connection.name, exc_info=True)
            return False
        return True


async def send_quietly(conn: Connection | None, op: dict[str, Any]) -> bool:
    """Send *op* on *conn* if it is open; False when it could not be sent (logged at debug level)."""
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


async def open_session(
    connect: Callable[[], Awaitable[Connection]],
    ids: protocol.IdMinter,
    url: str,
    *,
    number: int,
    detect_timeout: float,
    prepare: Callable[[BridgeSession], Awaitable[None]],
) -> BridgeSession:
    """Connect, learn what the bridge is, and let *prepare* restore what is still wanted on the new session.

    On any failure, cancellation included, the half-set-up socket is closed here: it is nobody's session yet,
    so nobody else would close it.
    """
    conn = await connect()
    try:
        info = await detect(conn, ids, url, detect_timeout)
        session = BridgeSession(conn, info, number)
        await prepare(session)
    except BaseException:
        await conn.aclose()
        raise
    return session
