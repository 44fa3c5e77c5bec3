"""The conversation on one connection to the bridge, sans I/O: what waits for a reply, until when, and where
each incoming frame goes.

:class:`Conversation` is fed the frames a connection receives (:meth:`~Conversation.receive`) and returns
what each one means for the requests waiting on it; it is asked for the frames to send
(:meth:`~Conversation.outbound`) and for what is due at a given time (:meth:`~Conversation.due`). It holds no
socket, no task and no clock: the caller (``client/connection.py``) moves the bytes, keeps the one timer and
owns the futures and queues, which the table holds as opaque handles. So every rule here is tested by feeding
it text (``tests/wire``).

The table maps a request's id to its handle: a reply waited for once, with a deadline (:meth:`wait`), or a
stream of frames for as long as the connection lasts (a goal's feedback and result, registered without a
deadline). A service this connection offers is waited on by its name (:meth:`host`): the bridge's
``call_service`` for it comes to that handle.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from rosbridge_mcp_server.wire import protocol

__all__ = [
    "Conversation",
    "ConversationEvent",
    "Refused",
    "Routed",
    "Unawaited",
]

H = TypeVar("H")


@dataclass(slots=True)
class Routed(Generic[H]):
    """A frame for a request (or a hosted service) that is waited on: hand *frame* to *handle*."""

    handle: H
    op: str
    frame: dict[str, Any]


@dataclass(slots=True)
class Refused:
    """An error ``status`` for an id nobody waits on (a refused subscribe or publish): its only trace."""

    id: str
    text: str


@dataclass(slots=True)
class Unawaited:
    """A reply for an id nobody waits on any more (it timed out, or its caller gave up)."""

    op: str
    id: str


ConversationEvent = Routed[H] | Refused | Unawaited | protocol.PublishEvent | protocol.Notice


class Conversation(Generic[H]):
    """One connection's requests and what the bridge says of them; *H* is the caller's handle type.

    ``pending`` (id → handle) and ``advertised`` (the topics this connection advertised) are plain data the
    caller may read; only :meth:`wait`, :meth:`listen`, :meth:`host` and :meth:`forget` write the table.
    """

    __slots__ = ("_deadlines", "_timer_at", "advertised", "decoder", "hosted", "pending")

    def __init__(self, decoder: protocol.InboundDecoder | None = None) -> None:
        self.pending: dict[str, H] = {}
        self.hosted: dict[str, H] = {}
        self.advertised: set[str] = set()
        self.decoder = decoder if decoder is not None else protocol.InboundDecoder()
        self._deadlines: dict[str, float] = {}
        #: The deadline the caller's one timer is armed for (None: no timer armed).
        self._timer_at: float | None = None

    # --- outbound ---------------------------------------------------------------------------------------

    @staticmethod
    def outbound(op: dict[str, Any]) -> str:
        """The text frame for *op*."""
        return protocol.encode(op)

    def wait(self, rid: str, handle: H, deadline: float) -> float | None:
        """Wait for one reply with id *rid* until *deadline*.

        Returns the time to arm the caller's one timer for when it must be (re)armed now, else None (a timer
        for an earlier deadline is armed already). One timer for the whole table: a timer per request costs
        microseconds per call, which a round trip against a raw socket notices.
        """
        self.pending[rid] = handle
        self._deadlines[rid] = deadline
        if self._timer_at is None or deadline < self._timer_at:
            self._timer_at = deadline
            return deadline
        return None

    def listen(self, rid: str, handle: H) -> None:
        """Every frame with id *rid* goes to *handle* (a goal's stream: feedback and result), with no
        deadline, until :meth:`forget`."""
        self.pending[rid] = handle

    def host(self, service: str, handle: H) -> None:
        """The bridge's calls of *service* (offered on this connection) go to *handle*."""
        self.hosted[service] = handle

    def forget(self, rid: str) -> H | None:
        """Stop waiting for *rid*; its handle, if it was still waited on."""
        self._deadlines.pop(rid, None)
        return self.pending.pop(rid, None)

    # --- inbound ----------------------------------------------------------------------------------------

    def receive(self, data: str | bytes) -> ConversationEvent[H]:
        """What one received frame means (never raises)."""
        event = self.decoder.feed(data)
        if isinstance(event, protocol.ReplyEvent):
            handle = self.pending.get(event.id)
            if handle is not None:
                return Routed(handle, event.op, event.frame)
            if event.op == "status":
                return Refused(event.id, str(event.frame.get("msg")))
            return Unawaited(event.op, event.id)
        if isinstance(event, protocol.Notice):
            frame = event.frame
            if frame is not None and frame.get("op") == "call_service" and self.hosted:
                hosted = self.hosted.get(str(frame.get("service")))
                if hosted is not None:
                    return Routed(hosted, "call_service", frame)
        return event

    # --- time -------------------------------------------------------------------------------------------

    def due(self, now: float) -> tuple[list[H], float | None]:
        """The timer fired at *now*: the handles whose deadline has passed (each once; they stay in the table
        until forgotten), and when to arm the timer next (None: nothing left with a deadline)."""
        self._timer_at = None
        expired: list[H] = []
        earliest: float | None = None
        for rid, deadline in list(self._deadlines.items()):
            if deadline <= now:
                del self._deadlines[rid]
                handle = self.pending.get(rid)
                if handle is not None:
                    expired.append(handle)
            elif earliest is None or deadline < earliest:
                earliest = deadline
        self._timer_at = earliest
        return expired, earliest

    def timer_stopped(self) -> None:
        """The caller's timer is gone (the connection closed): the next :meth:`wait` arms a new one."""
        self._timer_at = None

    # --- the end ----------------------------------------------------------------------------------------

    def lose_all(self) -> list[H]:
        """The connection is gone: every handle still waiting (replies, streams, hosted services), the table
        emptied."""
        lost = [*self.pending.values(), *self.hosted.values()]
        self.pending.clear()
        self.hosted.clear()
        self._deadlines.clear()
        return lost
