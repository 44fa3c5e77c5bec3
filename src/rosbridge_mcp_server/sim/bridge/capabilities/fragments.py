"""rosbridge's ``Defragment`` capability: the ``fragment`` op, joining a message sent in parts."""

from __future__ import annotations

import logging
import time
from collections import OrderedDict
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

from rosbridge_mcp_server.sim.bridge.core import BridgeCore, Capability, OpError, OpHandler, check_fields
from rosbridge_mcp_server.sim.connection import Connection

__all__ = ["FRAGMENT_TIMEOUT", "MAX_FRAGMENT_BUFFERS", "MAX_FRAGMENT_BYTES", "Fragments"]

log = logging.getLogger("rosbridge_mcp_server.sim")

#: rosbridge keeps incomplete fragment lists this long (``fragment_timeout``, 600 s).
FRAGMENT_TIMEOUT = 600.0
#: Our own bounds on incoming fragments, so that one client cannot grow the server without limit.
MAX_FRAGMENT_BUFFERS = 256
MAX_FRAGMENT_BYTES = 64 * 1024 * 1024

#: Where a joined message goes: the protocol's input buffer of the connection it came from.
Reassembled = Callable[[Connection, str], Awaitable[None]]


@dataclass
class _FragmentBuffer:
    total: int
    parts: list[str] = field(default_factory=list)
    size: int = 0
    started: float = field(default_factory=time.monotonic)


class Fragments(Capability):
    """Incoming ``fragment`` ops, joined in arrival order; ids are shared by all clients, as the real
    server's dictionary is."""

    def __init__(self, core: BridgeCore, reassembled: Reassembled) -> None:
        super().__init__(core)
        self._reassembled = reassembled
        self._buffers: OrderedDict[Any, _FragmentBuffer] = OrderedDict()
        self._bytes = 0

    def ops(self) -> dict[str, OpHandler]:
        return {"fragment": self.fragment}

    def fragment(self, conn: Connection, msg: dict[str, Any]) -> Awaitable[None] | None:
        check_fields(
            msg,
            [
                (True, "id", (str, int)),
                (True, "data", (str,)),
                (True, "num", (int,)),
                (True, "total", (int,)),
            ],
        )
        now = time.monotonic()
        while self._buffers:
            oldest = next(iter(self._buffers.values()))
            if now - oldest.started < FRAGMENT_TIMEOUT and len(self._buffers) < MAX_FRAGMENT_BUFFERS:
                break
            _, dropped = self._buffers.popitem(last=False)
            self._bytes -= dropped.size
            log.warning("fragments of an incomplete message dropped (expired or too many)")
        fid = msg["id"]
        buffer = self._buffers.get(fid)
        if buffer is None or msg["num"] == 0:
            if buffer is not None:
                self._bytes -= buffer.size
            buffer = self._buffers[fid] = _FragmentBuffer(total=msg["total"])
        data: str = msg["data"]
        if self._bytes + len(data) > MAX_FRAGMENT_BYTES:
            raise OpError("too much fragment data pending; fragment dropped")
        buffer.parts.append(data)
        buffer.size += len(data)
        self._bytes += len(data)
        if len(buffer.parts) < buffer.total:
            return None
        del self._buffers[fid]
        self._bytes -= buffer.size
        # Joined in arrival order, as the real server does.
        return self._reassembled(conn, "".join(buffer.parts))
