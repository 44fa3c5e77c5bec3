"""How bytes reach the bridge: the :class:`BridgeTransport` seam and its WebSocket implementation.

The client never knows whether its frames cross a socket. A :data:`Dial` opens one connection; the client
takes one (``RosbridgeClient(url, transport=...)``) and opens every connection through it: the main one,
lanes, goal lanes and the ordering probe's. :func:`websocket_dial` is the real one (the one place that
wires in ``websockets.connect``); the simulated robot offers an in-memory one
(``SimulatedRobot.dial_in_memory``) that talks to its bridge in the same process, for tests where a port adds
nothing.

The contract, for any implementation: ``recv()`` returns one frame (text or binary) and raises when the
connection is over (``ended_by`` then says why); ``send`` writes one text frame, raising ``EOFError`` when the
connection is closed, ``TimeoutError`` when the peer did not take it within *timeout* seconds, and
``OSError`` when whether it got through is unknown.
"""

from __future__ import annotations

import asyncio
import itertools
import logging
import ssl
from collections.abc import Awaitable, Callable, Sequence
from typing import Any, Final, Protocol

from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed

__all__ = ["MAX_FRAME_BYTES", "BridgeTransport", "Dial", "WebSocketTransport", "websocket_dial"]

logger = logging.getLogger("rosbridge_mcp_server.client")

# Large maps and point clouds exceed websockets' 1 MiB default; ROS 2 fragments only above 10 MB
# (launch file default), so the limit sits above that.
MAX_FRAME_BYTES: Final = 64 * 1024 * 1024
#: Longest wait for a polite close before the socket is aborted.
_CLOSE_SECONDS: Final = 1.0
#: A ping's wait is measured in slices of this many seconds; a slice that ends more than _STALL_GRACE late
#: measured time this process did not run, which is not counted against the bridge (see ``ping``).
_PING_SLICE: Final = 0.1
_STALL_GRACE: Final = 0.05
#: At most this many times a ping's limit is given back for such stalls (a ping never waits past 4 limits).
_GIVEN_BACK: Final = 3.0
#: Frames shorter than this, written into an empty socket buffer, cannot wait on flow control
#: (websockets' default write high-water mark is 32 KiB).
_NEVER_BLOCKS: Final = 16 * 1024


class BridgeTransport(Protocol):
    """One open connection to a bridge, moving frames and nothing else (see the module's docstring)."""

    def recv(self) -> Awaitable[str | bytes]:
        """The next frame; raises when the connection is over."""

    def ended_by(self, exc: BaseException) -> str:
        """Why the connection ended, said for a person, given what ``recv`` raised."""

    async def send(self, data: bytes, timeout: float) -> None:
        """Write one text frame (UTF-8 *data*) within *timeout* seconds of flow control."""

    async def ping(self, timeout: float) -> None:
        """A ping answered within *timeout* seconds (``TimeoutError`` if not, ``EOFError`` if closed).

        Seconds this process did not run are not the peer's: a starved process waits up to four limits."""

    async def close(self) -> None:
        """Close politely, bounded; never raises."""

    def abort(self) -> None:
        """Drop the connection at once."""


#: Opens one connection within the given seconds (raises ``TimeoutError``, ``OSError``, or anything else
#: the client words as "cannot connect").
Dial = Callable[[float], Awaitable[BridgeTransport]]


class _CountedPings(ClientConnection):
    """websockets' connection whose pings carry a count when given no payload: its keepalive's pings too.

    websockets' own payload draws from the process's shared ``random`` state, which is the host's (a property
    test's strategies failed on it, its draws changed by a keepalive ping in the middle)."""

    _count = itertools.count()

    async def ping(self, data: Any = None) -> Awaitable[float]:
        if data is None:
            data = next(self._count).to_bytes(8, "big")
        return await super().ping(data)


class WebSocketTransport:
    """A ``websockets`` client connection as a :class:`BridgeTransport`."""

    __slots__ = ("recv", "ws")

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        # recv() is websockets' own: the reader's hot path gets no frame of ours in between.
        self.recv = ws.recv

    def ended_by(self, exc: BaseException) -> str:
        if isinstance(exc, ConnectionClosed):
            code = self.ws.close_code
            if code is not None:
                reason = f": {self.ws.close_reason}" if self.ws.close_reason else ""
                return f"the connection closed (code {code}{reason})"
            return "the connection closed"
        return f"{type(exc).__name__}: {exc}"

    async def send(self, data: bytes, timeout: float) -> None:
        ws = self.ws
        try:
            # ws.send() waits for the socket buffer to drain below its high-water mark (32 KiB) after
            # writing. A small frame into an empty buffer can never wait, so it skips the timer.
            if len(data) < _NEVER_BLOCKS and not ws.transport.get_write_buffer_size():
                await ws.send(data, text=True)
                return
            async with asyncio.timeout(timeout):
                await ws.send(data, text=True)
        except ConnectionClosed:
            raise EOFError("the connection closed") from None
        except AttributeError as exc:
            # websockets 17 can fail inside send() when the peer closed the socket mid-frame (it aborts a
            # transport that is already gone: AttributeError). Whether the frame got through is unknown.
            raise OSError(f"the socket went away while sending ({exc})") from exc

    async def ping(self, timeout: float) -> None:
        loop = asyncio.get_running_loop()
        began = loop.time()
        try:
            async with asyncio.timeout(timeout):
                # A count for a payload (``_CountedPings``), one sequence with the keepalive's.
                pong = asyncio.ensure_future(await self.ws.ping())
        except ConnectionClosed:
            raise EOFError("the connection closed") from None
        left = timeout - (loop.time() - began)
        given_back = 0.0
        while True:
            step = min(_PING_SLICE, max(left, 0.0))
            slice_began = loop.time()
            # A pong read in the same turn of the loop as a slice's end counts: it was waiting.
            await asyncio.wait((pong,), timeout=step)
            if pong.done():
                try:
                    pong.result()
                except ConnectionClosed:
                    raise EOFError("the connection closed") from None
                return
            took = loop.time() - slice_began
            # Time the slice overran by is time this process did not run (a loaded machine): the bridge
            # is not blamed for it, up to three times the limit in all.
            stalled = min(max(0.0, took - step - _STALL_GRACE), _GIVEN_BACK * timeout - given_back)
            given_back += stalled
            left -= took - stalled
            if left <= 0:
                raise TimeoutError

    async def close(self) -> None:
        try:
            # websockets bounds the closing handshake by close_timeout, but not the wait for the
            # socket buffer to drain before the close frame goes out: a bridge that stopped reading
            # would hold close() until keepalive gives up (~20 s). So the whole close is bounded.
            async with asyncio.timeout(_CLOSE_SECONDS):
                await self.ws.close()
        except TimeoutError:
            self.ws.transport.abort()
        except Exception:
            logger.debug("error while closing a WebSocket", exc_info=True)

    def abort(self) -> None:
        self.ws.transport.abort()


def websocket_dial(
    url: str, *, ssl_context: ssl.SSLContext | None = None, headers: Sequence[tuple[str, str]] = ()
) -> Dial:
    """Opens WebSockets to *url*.

    ``ssl_context`` (wss:// only) carries a private CA or a client certificate; ``headers`` go with the
    opening handshake (e.g. ``Authorization`` for a bridge behind an authenticating proxy).
    """
    # websockets refuses an ssl argument for a ws:// URL, and picks the system's CAs for wss:// without one.
    options: dict[str, Any] = {"ssl": ssl_context} if ssl_context is not None else {}
    extra = list(headers) or None

    async def dial(timeout: float) -> BridgeTransport:
        ws = await connect(
            url,
            additional_headers=extra,
            **options,
            open_timeout=timeout,
            close_timeout=1.0,
            max_size=MAX_FRAME_BYTES,
            # rosbridge (tornado) does not negotiate permessage-deflate; skipping the offer keeps
            # the handshake and every frame lean. No proxy: a robot is on the local network.
            compression=None,
            proxy=None,
            create_connection=_CountedPings,
        )
        return WebSocketTransport(ws)

    return dial
