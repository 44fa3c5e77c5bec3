"""One WebSocket to the bridge: its reader task and its table of requests waiting for replies."""

from __future__ import annotations

import asyncio
import logging
import ssl
from collections.abc import Callable, Sequence
from typing import Any, Final

from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed

from rosbridge_mcp_server.client.frames import frame_bytes
from rosbridge_mcp_server.errors import (
    ConnectionLostError,
    NotConnectedError,
    RequestTimeoutError,
)
from rosbridge_mcp_server.wire import protocol

__all__ = ["Connection", "GoalStream", "ReplyWaiter", "open_connection"]

logger = logging.getLogger("rosbridge_mcp_server.client")

_LEVELS: Final = {"debug": logging.DEBUG, "info": logging.INFO, "warning": logging.WARNING}

# Large maps and point clouds exceed websockets' 1 MiB default; ROS 2 fragments only above 10 MB
# (launch file default), so the limit sits above that.
MAX_FRAME_BYTES: Final = 64 * 1024 * 1024
#: Longest wait for a polite close before the socket is aborted.
_CLOSE_SECONDS: Final = 1.0
#: Frames shorter than this, written into an empty socket buffer, cannot wait on flow control
#: (websockets' default write high-water mark is 32 KiB).
_NEVER_BLOCKS: Final = 16 * 1024


class ReplyWaiter:
    """A request waiting for exactly one reply until *deadline* (loop time)."""

    __slots__ = ("deadline", "future", "timeout", "what")

    def __init__(
        self, future: asyncio.Future[dict[str, Any]], what: str, deadline: float, timeout: float
    ) -> None:
        self.future = future
        self.what = what
        self.deadline = deadline
        self.timeout = timeout

    def expire(self) -> None:
        if not self.future.done():
            self.future.set_exception(
                RequestTimeoutError(self.what, self.timeout, "The bridge answers many errors with silence.")
            )

    def deliver(self, op: str, frame: dict[str, Any]) -> None:
        if not self.future.done():
            self.future.set_result(frame)

    def lost(self, exc: BaseException) -> None:
        if not self.future.done():
            self.future.set_exception(exc)


class GoalStream:
    """An action goal waiting for feedback frames and one result."""

    __slots__ = ("max_feedback", "queue", "what")

    def __init__(self, what: str, max_feedback: int = 256) -> None:
        self.what = what
        self.queue: asyncio.Queue[tuple[str, dict[str, Any]] | BaseException] = asyncio.Queue()
        self.max_feedback = max_feedback

    def deliver(self, op: str, frame: dict[str, Any]) -> None:
        # Feedback beyond the bound is dropped (a slow on_feedback must not grow memory); results never are.
        if op == "action_feedback" and self.queue.qsize() >= self.max_feedback:
            return
        self.queue.put_nowait((op, frame))

    def lost(self, exc: BaseException) -> None:
        self.queue.put_nowait(exc)


Waiting = ReplyWaiter | GoalStream


class Connection:
    """A WebSocket with a reader task routing every frame; replies are matched by id.

    When the socket closes, every request still waiting fails at once with
    :class:`ConnectionLostError`.
    """

    def __init__(
        self,
        ws: ClientConnection,
        url: str,
        name: str,
        on_publish: Callable[[protocol.PublishEvent], None] | None = None,
        send_timeout: float = 10.0,
    ) -> None:
        self.ws = ws
        self.url = url
        self.name = name
        self.pending: dict[str, Waiting] = {}
        self.advertised: set[str] = set()
        self.is_open = True
        self.close_reason: str | None = None
        self.send_timeout = send_timeout
        self._on_publish = on_publish
        self._decoder = protocol.InboundDecoder()
        self.closed = asyncio.Event()
        self._loop = asyncio.get_running_loop()
        self._sweep: asyncio.TimerHandle | None = None
        self._sweep_at = 0.0
        self.reader = asyncio.create_task(self._read(), name=f"rosbridge reader ({name})")

    async def _read(self) -> None:
        decoder = self._decoder
        pending = self.pending
        # recv() in a loop rather than `async for`: the iterator is an async generator, one more
        # layer per frame on the hot path. ConnectionClosed (OK or not) ends the loop either way.
        recv = self.ws.recv
        try:
            while True:
                data = await recv()
                try:
                    event = decoder.feed(data)
                    if type(event) is protocol.ReplyEvent:
                        waiting = pending.get(event.id)
                        if waiting is not None:
                            waiting.deliver(event.op, event.frame)
                        elif event.op == "status":
                            # A refused op nobody waits on (a subscribe, a publish): its only trace.
                            logger.warning(
                                "%s: the bridge refused %s: %.300s",
                                self.name,
                                event.id,
                                event.frame.get("msg"),
                            )
                        elif logger.isEnabledFor(logging.DEBUG):
                            logger.debug(
                                "%s: %s for %s, which nobody awaits any more", self.name, event.op, event.id
                            )
                    elif type(event) is protocol.PublishEvent:
                        if self._on_publish is not None:
                            self._on_publish(event)
                    elif isinstance(event, protocol.Notice):
                        level = _LEVELS[event.level]
                        if logger.isEnabledFor(level):
                            logger.log(level, "%s: %s", self.name, event.text)
                except Exception as exc:
                    # One bad frame (or a bug in a listener) must not end the connection's reader, nor
                    # fill the log: one line per frame, the traceback only at debug level.
                    logger.error(
                        "%s: error while handling a frame; frame dropped (%s: %.200s)",
                        self.name,
                        type(exc).__name__,
                        exc,
                        exc_info=logger.isEnabledFor(logging.DEBUG),
                    )
        except ConnectionClosed:
            self.close_reason = _close_text(self.ws)
        except Exception as exc:  # a transport error: treat as a drop
            self.close_reason = f"{type(exc).__name__}: {exc}"
            logger.debug("%s: reader stopped", self.name, exc_info=True)
        finally:
            self.is_open = False
            if self._sweep is not None:
                self._sweep.cancel()
                self._sweep = None
            self.fail_pending()
            self.closed.set()

    def fail_pending(self) -> None:
        """Fail every waiting request with :class:`ConnectionLostError` and empty the table."""
        waiting = list(self.pending.values())
        self.pending.clear()
        for item in waiting:
            item.lost(ConnectionLostError(self.url, item.what))

    async def send(self, op: dict[str, Any]) -> None:
        """Send one op now; raises :class:`NotConnectedError` if the socket is closed (nothing sent).

        Waiting on flow control (only when the bridge stops reading) is bounded by ``send_timeout``.
        """
        if not self.is_open:
            raise NotConnectedError(self.url, self.close_reason or "the connection closed")
        what = f"{op.get('op')} {op.get('topic', '')}".rstrip()
        await self._write(frame_bytes(protocol.encode(op), what), what, self.send_timeout)

    async def _write(self, data: bytes, what: str, timeout: float) -> None:
        try:
            # ws.send() waits for the socket buffer to drain below its high-water mark (32 KiB) after
            # writing. A small frame into an empty buffer can never wait, so it skips the timer.
            if len(data) < _NEVER_BLOCKS and not self.ws.transport.get_write_buffer_size():
                await self.ws.send(data, text=True)
                return
            try:
                async with asyncio.timeout(timeout):
                    await self.ws.send(data, text=True)
            except TimeoutError:
                raise RequestTimeoutError(
                    f"sending {what}",
                    timeout,
                    "The bridge has stopped reading from the connection; the frame may still be delivered.",
                ) from None
        except ConnectionClosed:
            raise NotConnectedError(self.url, "the connection closed") from None
        except (OSError, AttributeError) as exc:
            # websockets 17 can fail inside send() when the peer closed the socket mid-frame (it aborts a
            # transport that is already gone: AttributeError). Whether the frame got through is unknown.
            raise ConnectionLostError(self.url, what) from exc

    async def ping(self, timeout: float) -> float:
        """A WebSocket ping answered within *timeout* seconds: the bridge is reading this socket now.

        Returns the round trip in seconds. :class:`RequestTimeoutError` if no pong came in time.
        """
        start = self._loop.time()
        try:
            async with asyncio.timeout(timeout):
                pong = await self.ws.ping()
                await pong
        except TimeoutError:
            raise RequestTimeoutError(
                f"a ping to rosbridge at {self.url}",
                timeout,
                "The bridge is not reading this connection (frozen, or the network to it is down).",
            ) from None
        except ConnectionClosed:
            raise NotConnectedError(self.url, self.close_reason or "the connection closed") from None
        return self._loop.time() - start

    async def request(self, rid: str, op: dict[str, Any], what: str, timeout: float) -> dict[str, Any]:
        """Send *op* and wait up to *timeout* seconds for the reply with id *rid*."""
        loop = self._loop
        future: asyncio.Future[dict[str, Any]] = loop.create_future()
        deadline = loop.time() + timeout
        self.pending[rid] = ReplyWaiter(future, what, deadline, timeout)
        if self._sweep is None or deadline < self._sweep_at:
            self._arm_sweep(deadline)
        try:
            if not self.is_open:
                raise NotConnectedError(self.url, self.close_reason or "the connection closed")
            data = frame_bytes(protocol.encode(op), what)
            ws = self.ws
            if len(data) < _NEVER_BLOCKS and not ws.transport.get_write_buffer_size():
                # _write()'s fast path, inlined: one coroutine frame less per call.
                try:
                    await ws.send(data, text=True)
                except ConnectionClosed:
                    raise NotConnectedError(self.url, "the connection closed") from None
            else:
                await self._write(data, what, timeout)
            return await future
        finally:
            self.pending.pop(rid, None)
            # A send that failed (or waited on flow control past the deadline, when the sweep has already
            # failed the reply) raised its own error: the reply's future is not awaited by anyone now.
            if not future.done():
                future.cancel()
            elif not future.cancelled():
                future.exception()

    def expect(self, rid: str, what: str, timeout: float) -> asyncio.Future[dict[str, Any]]:
        """A future for the reply with id *rid* to something sent next (``forget(rid)`` when done).

        For an op that gets no reply unless the bridge refuses it: rosbridge-server-rs answers a refused
        ``cancel_action_goal`` with an error ``status`` carrying the goal's id.
        """
        future: asyncio.Future[dict[str, Any]] = self._loop.create_future()
        deadline = self._loop.time() + timeout
        self.pending[rid] = ReplyWaiter(future, what, deadline, timeout)
        if self._sweep is None or deadline < self._sweep_at:
            self._arm_sweep(deadline)
        # Nobody may await it (the usual outcome is silence): its timeout must not be logged as unretrieved.
        future.add_done_callback(_consume)
        return future

    def forget(self, rid: str) -> None:
        """Stop waiting for a reply with id *rid*."""
        waiting = self.pending.pop(rid, None)
        if type(waiting) is ReplyWaiter and not waiting.future.done():
            waiting.future.cancel()

    # Deadlines: one timer per connection, armed for the earliest deadline and left armed while
    # later requests come and go. A timer per request (asyncio.timeout, call_later) costs several
    # microseconds per call, which a benchmark against a raw websockets round trip notices.

    def _arm_sweep(self, when: float) -> None:
        if self._sweep is not None:
            self._sweep.cancel()
        self._sweep_at = when
        self._sweep = self._loop.call_at(when, self._expire_due)

    def _expire_due(self) -> None:
        self._sweep = None
        # call_at may fire up to the clock resolution early.
        now = self._loop.time() + 0.001
        earliest: float | None = None
        for waiting in list(self.pending.values()):
            if type(waiting) is ReplyWaiter:
                if waiting.deadline <= now:
                    waiting.expire()
                elif earliest is None or waiting.deadline < earliest:
                    earliest = waiting.deadline
        if earliest is not None:
            self._arm_sweep(earliest)

    async def aclose(self) -> None:
        """Close the socket and wait for the reader to finish (fails whatever is pending)."""
        self.is_open = False
        try:
            # websockets bounds the closing handshake by close_timeout, but not the wait for the
            # socket buffer to drain before the close frame goes out: a bridge that stopped reading
            # would hold close() until keepalive gives up (~20 s). So the whole close is bounded.
            async with asyncio.timeout(_CLOSE_SECONDS):
                await self.ws.close()
        except TimeoutError:
            self.ws.transport.abort()
        except Exception:
            logger.debug("%s: error while closing", self.name, exc_info=True)
        if not self.reader.done():
            try:
                async with asyncio.timeout(2.0):
                    await asyncio.shield(self.reader)
            except TimeoutError:
                self.reader.cancel()
        self.fail_pending()


def _consume(future: asyncio.Future[Any]) -> None:
    if not future.cancelled():
        future.exception()


def _close_text(ws: ClientConnection) -> str:
    code = ws.close_code
    if code is not None:
        reason = f": {ws.close_reason}" if ws.close_reason else ""
        return f"the connection closed (code {code}{reason})"
    return "the connection closed"


async def open_connection(
    url: str,
    name: str,
    timeout: float,
    on_publish: Callable[[protocol.PublishEvent], None] | None = None,
    send_timeout: float = 10.0,
    *,
    ssl_context: ssl.SSLContext | None = None,
    headers: Sequence[tuple[str, str]] = (),
) -> Connection:
    """Open a WebSocket to *url* within *timeout* seconds; raises :class:`NotConnectedError`.

    ``ssl_context`` (wss:// only) carries a private CA or a client certificate; ``headers`` go with the
    opening handshake (e.g. ``Authorization`` for a bridge behind an authenticating proxy).
    """
    # websockets refuses an ssl argument for a ws:// URL, and picks the system's CAs for wss:// without one.
    tls: dict[str, Any] = {"ssl": ssl_context} if ssl_context is not None else {}
    try:
        ws = await connect(
            url,
            additional_headers=list(headers) or None,
            **tls,
            open_timeout=timeout,
            close_timeout=1.0,
            max_size=MAX_FRAME_BYTES,
            # rosbridge (tornado) does not negotiate permessage-deflate; skipping the offer keeps
            # the handshake and every frame lean. No proxy: a robot is on the local network.
            compression=None,
            proxy=None,
        )
    except asyncio.CancelledError:
        raise
    except TimeoutError:
        raise NotConnectedError(url, f"no WebSocket answer within {timeout:g} s", timed_out=True) from None
    except ssl.SSLCertVerificationError as exc:
        raise NotConnectedError(
            url, f"the bridge's TLS certificate was not accepted: {exc.verify_message or exc}"
        ) from None
    except OSError as exc:
        raise NotConnectedError(url, exc.strerror or str(exc)) from None
    except Exception as exc:
        raise NotConnectedError(url, f"{type(exc).__name__}: {exc}") from None
    return Connection(ws, url, name, on_publish, send_timeout)
