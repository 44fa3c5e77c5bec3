"""The simulated bridge reached in memory: a client's connection handed straight to the bridge's handler.

For tests where a port adds nothing. :meth:`MemoryServer.dial` opens one connection and returns its client
end, which has the shape of the server's ``BridgeTransport`` (``recv``, ``ended_by``, ``send``, ``ping``,
``close``, ``abort``) without importing it: the simulated robot shares nothing with the server but the wire.
The bridge end has the shape of the ``websockets`` server connection the bridge reads (:class:`PeerSocket`).

What a socket would do is kept where a client can tell: frames arrive whole and in order, text as text and
CBOR as bytes; a close carries its code and reason to the other end, after the frames sent before it; a frame
above the bridge's incoming limit closes the connection with 1009, as Tornado's limit does; a connection to a
stopped robot is refused. What is not modelled: flow control (a send never waits; tests of a bridge that
stops reading keep a real socket), TLS, headers, and the handshake's timing.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any, Final

from websockets.exceptions import ConnectionClosedOK

__all__ = ["MemoryClientEnd", "MemoryServer"]

log = logging.getLogger("rosbridge_mcp_server.sim")

#: What a stopped robot's dial says (a real one: "Connect call failed ('127.0.0.1', 9090)").
_REFUSED: Final = "Connect call failed (the simulated robot is stopped)"


class _Pipe:
    """Both directions of one connection and how it ended."""

    def __init__(self, incoming_limit: int | None) -> None:
        self.to_bridge: asyncio.Queue[str | bytes | None] = asyncio.Queue()
        self.to_client: asyncio.Queue[str | bytes | None] = asyncio.Queue()
        self.incoming_limit = incoming_limit
        self.code: int | None = None
        self.reason = ""
        self.is_closed = False
        self.closed = asyncio.Event()

    def close(self, code: int | None, reason: str = "") -> None:
        if self.is_closed:
            return
        self.is_closed = True
        self.code, self.reason = code, reason
        # The frames already sent are still read, then the end.
        self.to_bridge.put_nowait(None)
        self.to_client.put_nowait(None)
        self.closed.set()

    def ended(self) -> str:
        if self.code is None:
            return "the connection closed"
        return f"the connection closed (code {self.code}{f': {self.reason}' if self.reason else ''})"


class MemoryClientEnd:
    """The client's end of one in-memory connection (a ``BridgeTransport`` in shape)."""

    def __init__(self, pipe: _Pipe) -> None:
        self._pipe = pipe

    async def recv(self) -> str | bytes:
        """The next frame from the bridge; ``EOFError`` once the connection is closed."""
        item = await self._pipe.to_client.get()
        if item is None:
            self._pipe.to_client.put_nowait(None)  # every later recv() ends too
            raise EOFError(self._pipe.ended())
        return item

    def ended_by(self, exc: BaseException) -> str:
        """Why the connection ended."""
        if isinstance(exc, EOFError):
            return self._pipe.ended()
        return f"{type(exc).__name__}: {exc}"

    async def send(self, data: bytes, timeout: float) -> None:
        """One text frame to the bridge (never waits: no flow control in memory)."""
        pipe = self._pipe
        if pipe.is_closed:
            raise EOFError("the connection closed")
        if pipe.incoming_limit is not None and len(data) > pipe.incoming_limit:
            # Tornado refuses a frame above its limit and closes the connection (websockets: 1009).
            pipe.close(1009, "message too big")
            return
        try:
            text = data.decode()
        except UnicodeDecodeError:
            pipe.close(1007, "invalid UTF-8 in a text frame")
            return
        pipe.to_bridge.put_nowait(text)

    async def ping(self, timeout: float) -> None:
        """The bridge's WebSocket layer answers pings itself, whatever its handler is doing."""
        if self._pipe.is_closed:
            raise EOFError("the connection closed")

    async def close(self) -> None:
        """A normal close (1000)."""
        self._pipe.close(1000)

    def abort(self) -> None:
        """Dropped without a close frame."""
        self._pipe.close(None)


class _BridgeEnd:
    """The bridge's end: what ``Bridge.serve_connection`` reads of a ``websockets`` server connection."""

    remote_address: Any = ("127.0.0.1", 0)

    def __init__(self, pipe: _Pipe) -> None:
        self._pipe = pipe

    async def send(self, message: str | bytes) -> None:
        if self._pipe.is_closed:
            raise ConnectionClosedOK(None, None)
        self._pipe.to_client.put_nowait(message)

    async def close(self, code: int = 1000, reason: str = "") -> None:
        self._pipe.close(code, reason)

    async def wait_closed(self) -> None:
        await self._pipe.closed.wait()

    def __aiter__(self) -> AsyncIterator[str | bytes]:
        return self._frames()

    async def _frames(self) -> AsyncIterator[str | bytes]:
        while True:
            item = await self._pipe.to_bridge.get()
            if item is None:
                self._pipe.to_bridge.put_nowait(None)
                return
            yield item


class MemoryServer:
    """The in-memory connections of one simulated bridge: opened by :meth:`dial` while it :attr:`accepts`."""

    def __init__(self, serve: Callable[[Any], Awaitable[None]], incoming_limit: int | None) -> None:
        self._serve = serve
        self._incoming_limit = incoming_limit
        self._served: dict[asyncio.Task[None], _Pipe] = {}
        self.accepts = False

    async def dial(self, timeout: float) -> MemoryClientEnd:
        """Open a connection to the bridge (``ConnectionRefusedError`` while the robot is stopped)."""
        if not self.accepts:
            raise ConnectionRefusedError(111, _REFUSED)
        pipe = _Pipe(self._incoming_limit)
        task = asyncio.get_running_loop().create_task(self._run(pipe), name="simulated in-memory connection")
        self._served[task] = pipe
        task.add_done_callback(lambda done: self._served.pop(done, None))
        return MemoryClientEnd(pipe)

    async def _run(self, pipe: _Pipe) -> None:
        try:
            await self._serve(_BridgeEnd(pipe))
        except Exception:
            log.exception("in-memory connection failed")
        finally:
            # As a websockets server closes a connection whose handler returned.
            pipe.close(1000)

    async def close_all(self) -> None:
        """Close every connection as a server going away does (1001), and wait for their handlers."""
        self.accepts = False
        served = dict(self._served)
        for pipe in served.values():
            pipe.close(1001)
        for task in served:
            with contextlib.suppress(asyncio.CancelledError):
                await task
