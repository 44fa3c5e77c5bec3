"""One connection to the bridge: its reader task, moving frames between a transport and the conversation.

What waits for a reply and where each frame goes is the conversation's (``wire/conversation.py``, pure data);
how bytes travel is the transport's (``client/transport.py``). This
module owns what needs a loop: the futures and queues the table holds, the one deadline timer, the reader.
"""

from __future__ import annotations

import asyncio
import logging
import ssl
from collections.abc import Callable
from typing import Any, Final

from rosbridge_mcp_server.client.frame_limits import frame_bytes
from rosbridge_mcp_server.client.transport import MAX_FRAME_BYTES, BridgeTransport, Dial
from rosbridge_mcp_server.errors import (
    ConnectionLostError,
    NotConnectedError,
    RequestTimeoutError,
)
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.conversation import Conversation, Refused, Routed, Unawaited

__all__ = ["MAX_FRAME_BYTES", "Connection", "GoalStream", "ReplyWaiter", "open_connection"]

logger = logging.getLogger("rosbridge_mcp_server.client")

_LEVELS: Final = {"debug": logging.DEBUG, "info": logging.INFO, "warning": logging.WARNING}
#: The deadline timer may fire up to the clock's resolution early.
_TIMER_SLACK: Final = 0.001


class ReplyWaiter:
    """A request waiting for exactly one reply (its deadline is the conversation's)."""

    __slots__ = ("future", "timeout", "what")

    def __init__(self, future: asyncio.Future[dict[str, Any]], what: str, timeout: float) -> None:
        self.future = future
        self.what = what
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
    """Frames for as long as the connection lasts: an action goal's feedback and one result, or the calls of
    a service this connection offers."""

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

    async def next(self) -> tuple[str, dict[str, Any]]:
        """The next frame (op, frame); :class:`ConnectionLostError` once the connection is gone."""
        item = await self.queue.get()
        if isinstance(item, BaseException):
            raise item
        return item


Waiting = ReplyWaiter | GoalStream


class Connection:
    """A transport with a reader task routing every frame through the conversation; replies matched by id.

    When the connection closes, every request still waiting fails at once with :class:`ConnectionLostError`.
    """

    def __init__(
        self,
        transport: BridgeTransport,
        url: str,
        name: str,
        on_publish: Callable[[protocol.PublishEvent], None] | None = None,
        send_timeout: float = 10.0,
    ) -> None:
        self.transport = transport
        self.url = url
        self.name = name
        self.conversation: Conversation[Waiting] = Conversation()
        self.is_open = True
        self.close_reason: str | None = None
        self.send_timeout = send_timeout
        self._on_publish = on_publish
        self.closed = asyncio.Event()
        self._loop = asyncio.get_running_loop()
        self._timer: asyncio.TimerHandle | None = None
        self.reader = asyncio.create_task(self._read(), name=f"rosbridge reader ({name})")

    @property
    def pending(self) -> dict[str, Waiting]:
        """The requests waiting, by id (to read: `expect`, `stream` and `forget` write it)."""
        return self.conversation.pending

    @property
    def advertised(self) -> set[str]:
        """The topics advertised on this connection."""
        return self.conversation.advertised

    async def _read(self) -> None:
        receive = self.conversation.receive
        # recv() in a loop, the transport's own: no layer of ours per frame on the hot path. Whatever it
        # raises ends the loop: the connection closed (the transport words why) or failed.
        recv = self.transport.recv
        try:
            while True:
                data = await recv()
                try:
                    event = receive(data)
                    if type(event) is Routed:
                        event.handle.deliver(event.op, event.frame)
                    elif type(event) is protocol.PublishEvent:
                        if self._on_publish is not None:
                            self._on_publish(event)
                    else:
                        self._log(event)
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
        except Exception as exc:
            self.close_reason = self.transport.ended_by(exc)
            logger.debug("%s: reader stopped (%s)", self.name, self.close_reason)
        finally:
            self.is_open = False
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
            self.conversation.timer_stopped()
            self.fail_pending()
            self.closed.set()

    def _log(self, event: object) -> None:
        if type(event) is Refused:
            # A refused op nobody waits on (a subscribe, a publish): its only trace.
            logger.warning("%s: the bridge refused %s: %.300s", self.name, event.id, event.text)
        elif type(event) is protocol.Notice:
            level = _LEVELS[event.level]
            if logger.isEnabledFor(level):
                logger.log(level, "%s: %s", self.name, event.text)
        elif type(event) is Unawaited and logger.isEnabledFor(logging.DEBUG):
            logger.debug("%s: %s for %s, which nobody awaits any more", self.name, event.op, event.id)

    def fail_pending(self) -> None:
        """Fail every waiting request with :class:`ConnectionLostError` and empty the table."""
        for item in self.conversation.lose_all():
            item.lost(ConnectionLostError(self.url, item.what))

    async def send(self, op: dict[str, Any]) -> None:
        """Send one op now; raises :class:`NotConnectedError` if the connection is closed (nothing sent).

        Waiting on flow control (only when the bridge stops reading) is bounded by ``send_timeout``.
        """
        if not self.is_open:
            raise NotConnectedError(self.url, self.close_reason or "the connection closed")
        what = f"{op.get('op')} {op.get('topic', '')}".rstrip()
        await self._write(frame_bytes(self.conversation.outbound(op), what), what, self.send_timeout)

    async def _write(self, data: bytes, what: str, timeout: float) -> None:
        try:
            await self.transport.send(data, timeout)
        except EOFError:
            raise NotConnectedError(self.url, "the connection closed") from None
        except TimeoutError:
            raise RequestTimeoutError(
                f"sending {what}",
                timeout,
                "The bridge has stopped reading from the connection; the frame may still be delivered.",
            ) from None
        except OSError as exc:
            # The connection went away mid-frame: whether the frame got through is unknown.
            raise ConnectionLostError(self.url, what) from exc

    async def ping(self, timeout: float) -> float:
        """A ping answered within *timeout* seconds: the bridge is reading this connection now.

        Returns the round trip in seconds. :class:`RequestTimeoutError` if no pong came in time.
        """
        start = self._loop.time()
        try:
            await self.transport.ping(timeout)
        except TimeoutError:
            raise RequestTimeoutError(
                f"a ping to rosbridge at {self.url}",
                timeout,
                "The bridge is not reading this connection (frozen, or the network to it is down).",
            ) from None
        except EOFError:
            raise NotConnectedError(self.url, self.close_reason or "the connection closed") from None
        return self._loop.time() - start

    async def request(self, rid: str, op: dict[str, Any], what: str, timeout: float) -> dict[str, Any]:
        """Send *op* and wait up to *timeout* seconds for the reply with id *rid*."""
        future: asyncio.Future[dict[str, Any]] = self._loop.create_future()
        self._wait(rid, ReplyWaiter(future, what, timeout), timeout)
        try:
            if not self.is_open:
                raise NotConnectedError(self.url, self.close_reason or "the connection closed")
            await self._write(frame_bytes(self.conversation.outbound(op), what), what, timeout)
            return await future
        finally:
            self.conversation.forget(rid)
            # A send that failed (or waited on flow control past the deadline, when the timer has already
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
        self._wait(rid, ReplyWaiter(future, what, timeout), timeout)
        # Nobody may await it (the usual outcome is silence): its timeout must not be logged as unretrieved.
        future.add_done_callback(_consume)
        return future

    def forget(self, rid: str) -> None:
        """Stop waiting for a reply with id *rid*."""
        waiting = self.conversation.forget(rid)
        if type(waiting) is ReplyWaiter and not waiting.future.done():
            waiting.future.cancel()

    def stream(self, rid: str, what: str) -> GoalStream:
        """Every frame with id *rid* (a goal's feedback and result) as a stream, until ``forget(rid)``."""
        stream = GoalStream(what)
        self.conversation.listen(rid, stream)
        return stream

    def host(self, service: str, what: str) -> GoalStream:
        """The bridge's calls of *service*, which this connection offers, as a stream of frames."""
        stream = GoalStream(what)
        self.conversation.host(service, stream)
        return stream

    def _wait(self, rid: str, waiter: ReplyWaiter, timeout: float) -> None:
        arm_at = self.conversation.wait(rid, waiter, self._loop.time() + timeout)
        if arm_at is not None:
            self._arm(arm_at)

    # Deadlines: one timer per connection, armed for the earliest deadline (the conversation says when).

    def _arm(self, when: float) -> None:
        if self._timer is not None:
            self._timer.cancel()
        self._timer = self._loop.call_at(when, self._expire_due)

    def _expire_due(self) -> None:
        self._timer = None
        expired, next_at = self.conversation.due(self._loop.time() + _TIMER_SLACK)
        for waiting in expired:
            if type(waiting) is ReplyWaiter:
                waiting.expire()
        if next_at is not None:
            self._arm(next_at)

    async def aclose(self) -> None:
        """Close the connection and wait for the reader to finish (fails whatever is pending)."""
        self.is_open = False
        await self.transport.close()
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


async def open_connection(
    dial: Dial,
    url: str,
    name: str,
    timeout: float,
    *,
    on_publish: Callable[[protocol.PublishEvent], None] | None = None,
    send_timeout: float = 10.0,
) -> Connection:
    """Open a connection to *url* through *dial* within *timeout* seconds (or :class:`NotConnectedError`)."""
    try:
        transport = await dial(timeout)
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
    return Connection(transport, url, name, on_publish, send_timeout)
