"""One client connection of the simulated rosbridge: its outgoing queue, fragments and subscriptions.

Memory per connection is bounded: data frames (``publish``) wait in a queue of at most
:data:`MAX_QUEUED_MESSAGES` messages / :data:`MAX_QUEUED_BYTES` bytes and a slow reader loses the oldest
first. Replies (``service_response``, ``action_result``...) are never dropped; there is at most one per
request, so they are bounded by what the client asked for.
"""

from __future__ import annotations

import asyncio
import base64
import json
import logging
import math
import time
from collections import deque
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import cbor2
from websockets.exceptions import ConnectionClosed

from rosbridge_mcp_server.sim.interfaces.base import ConversionError
from rosbridge_mcp_server.sim.png import encode_png

__all__ = [
    "MAX_QUEUED_BYTES",
    "MAX_QUEUED_MESSAGES",
    "Connection",
    "Dumps",
    "OutgoingMessage",
    "PeerSocket",
    "SubscriptionOptions",
    "TopicSubscription",
    "dumps_standard",
    "dumps_ujson",
    "png_frame_data",
]

log = logging.getLogger("rosbridge_mcp_server.sim")

MAX_QUEUED_MESSAGES = 1000


def dumps_standard(value: Any) -> str:
    """Python's json, as a rosbridge without ujson writes its frames."""
    return json.dumps(value)


def dumps_ujson(value: Any) -> str:
    """ujson's default output (rosbridge prefers ujson when installed, as on the 0.11.17 we ran): compact, and
    every '/' escaped as '\\/' (a '/' can only occur inside a JSON string, so the replace is exact)."""
    return json.dumps(value, separators=(",", ":")).replace("/", "\\/")


Dumps = Callable[[Any], str]
MAX_QUEUED_BYTES = 32 * 1024 * 1024


@dataclass
class OutgoingMessage:
    """A message published on a topic, shared by every connection that receives it.

    ``json_form`` is computed once (lazily) by the bridge's converter, and the ``publish`` frame text once per
    topic spelling, so many subscribers cost one serialisation.
    """

    topic: str
    type: str
    msg: dict[str, Any]
    to_json: Callable[[str, dict[str, Any]], dict[str, Any]]
    #: The registry's ``to_cbor`` (JSON form → CBOR values), for subscriptions asking for ``cbor``.
    to_cbor: Callable[[str, dict[str, Any]], dict[str, Any]] | None = None
    _json_form: dict[str, Any] | None = None
    _texts: dict[str, str] = field(default_factory=dict)
    _cbor: dict[str, bytes] = field(default_factory=dict)

    def frame_text(self, echo_topic: str, *, png: bool = False, dumps: Dumps = dumps_standard) -> str:
        """The ``publish`` frame for a subscription to ``echo_topic`` as spelled (or its ``png`` op)."""
        key = ("png:" if png else "") + ("u:" if dumps is dumps_ujson else "") + echo_topic
        text = self._texts.get(key)
        if text is None:
            if self._json_form is None:
                self._json_form = self.to_json(self.type, self.msg)
            text = dumps({"op": "publish", "topic": echo_topic, "msg": self._json_form})
            if png:
                text = dumps({"op": "png", "data": png_frame_data(text)})
            self._texts[key] = text
        return text

    def frame_cbor(self, echo_topic: str) -> bytes:
        """The ``publish`` op as one binary CBOR frame (rosbridge never fragments these);
        :class:`ConversionError` when rosbridge's CBOR converter fails on the message."""
        data = self._cbor.get(echo_topic)
        if data is None:
            if self.to_cbor is None:
                raise ConversionError(f"no CBOR conversion for {self.type}")
            if self._json_form is None:
                self._json_form = self.to_json(self.type, self.msg)
            values = self.to_cbor(self.type, self._json_form)
            data = self._cbor[echo_topic] = cbor2.dumps({"op": "publish", "topic": echo_topic, "msg": values})
        return data


def png_frame_data(text: str) -> str:
    """rosbridge's ``pngcompression.encode``: the text as the RGB pixels of a near-square PNG, padded with
    newlines, base64-encoded."""
    data = text.encode("utf-8")
    width = max(1, math.floor(math.sqrt(len(data) / 3.0)))
    height = math.ceil(len(data) / 3.0 / width)
    data += b"\n" * (width * height * 3 - len(data))
    return base64.b64encode(encode_png(width, height, data)).decode("ascii")


@dataclass
class SubscriptionOptions:
    """One ``subscribe`` request's options."""

    throttle_rate: int = 0
    queue_length: int = 0
    compression: str = "none"


@dataclass
class TopicSubscription:
    """All of one connection's ``subscribe`` requests for one topic (rosbridge keeps one ROS subscription)."""

    topic: str
    echo_topic: str
    type: str
    by_id: dict[Any, SubscriptionOptions] = field(default_factory=dict)
    last_sent: float = 0.0
    queue: deque[OutgoingMessage] = field(default_factory=deque)
    release: asyncio.TimerHandle | None = None

    @property
    def throttle_rate(self) -> int:
        """rosbridge uses the smallest throttle of all requests (0.11.17 and 2.x)."""
        return min((o.throttle_rate for o in self.by_id.values()), default=0)

    @property
    def queue_length(self) -> int:
        """...and the smallest queue length."""
        return min((o.queue_length for o in self.by_id.values()), default=0)

    @property
    def png(self) -> bool:
        """...and the strongest compression: ``png`` if any request asked for it and none for CBOR."""
        return not self.cbor and any(o.compression == "png" for o in self.by_id.values())

    @property
    def cbor(self) -> bool:
        """``cbor`` beats ``png`` (rosbridge's ``update_params``; ``cbor-raw`` is not simulated: JSON)."""
        options = self.by_id.values()
        return any(o.compression == "cbor" for o in options) and all(
            o.compression != "cbor-raw" for o in options
        )


class PeerSocket(Protocol):
    """What the bridge uses of a client's socket: a ``websockets`` server connection, or the bridge's end of
    an in-memory one (``sim/memory.py``)."""

    @property
    def remote_address(self) -> Any: ...

    async def send(self, message: str | bytes) -> None: ...

    async def close(self, code: int = 1000, reason: str = "") -> None: ...

    async def wait_closed(self) -> None: ...

    def __aiter__(self) -> AsyncIterator[str | bytes]: ...


@dataclass
class _Queued:
    droppable: bool
    frames: list[str] | list[bytes]
    size: int


class Connection:
    """The server side of one client's WebSocket."""

    def __init__(
        self,
        ws: PeerSocket,
        cid: int,
        *,
        fragment_size: int | None,
        fragment_id: Any,
        dumps: Dumps = dumps_standard,
    ) -> None:
        self.ws = ws
        #: How this server writes JSON (ROS 1: ujson's compact form with '\\/').
        self.dumps = dumps
        self.id = cid
        #: Fragment id of an id-less message: ``"0"`` on ROS 2, ``0`` on ROS 1.
        self.fragment_id = fragment_id
        #: Connection-wide outgoing fragment size as the client sent it; ``None`` = never fragment.
        self.fragment_size: Any = fragment_size
        #: rosbridge's per-connection input buffer (``protocol.incoming``) and its loop guard.
        self.buffer = ""
        self.old_buffer = ""
        #: The real server's incoming thread died on an input: every later frame is ignored.
        self.dead = False
        #: Frames dropped because the reading died, and frames ever queued for sending (for tests).
        self.frames_ignored = 0
        self.frames_queued = 0
        self.subscriptions: dict[str, TopicSubscription] = {}
        #: topic -> advertisement ids of this client (``None`` for an id-less advertise).
        self.advertisements: dict[str, list[Any]] = {}
        self.advertised_types: dict[str, str] = {}
        self.closed = False
        self.dropped = 0
        self._queue: deque[_Queued] = deque()
        self._queued_bytes = 0
        self._droppable_count = 0
        self._wakeup = asyncio.Event()

    # --- outgoing -------------------------------------------------------------------------------------

    def send(self, message: dict[str, Any]) -> None:
        """Queue a reply frame (never dropped)."""
        self._enqueue(self.dumps(message), droppable=False, fragment_id=message.get("id", self.fragment_id))

    def _enqueue(self, text: str | bytes, *, droppable: bool, fragment_id: Any) -> None:
        if self.closed:
            return
        if isinstance(text, bytes):
            # rosbridge cannot fragment a CBOR frame: above the connection's fragment size its send fails
            # (``message.get("id")`` on bytes) and the message is lost (ROS 2: 10 MB by default).
            size = self.fragment_size
            if isinstance(size, int | float) and len(text) > size:
                log.error(
                    "client %d: send failed: a CBOR frame of %d bytes cannot be fragmented",
                    self.id,
                    len(text),
                )
                return
            frames: list[str] | list[bytes] | None = [text]
        else:
            frames = self._fragments(text, fragment_id)
        if frames is None:
            return
        self.frames_queued += len(frames)
        item = _Queued(droppable, frames, len(text))
        self._queue.append(item)
        self._queued_bytes += item.size
        if droppable:
            self._droppable_count += 1
            self._shed()
        self._wakeup.set()

    def _fragments(self, text: str, fragment_id: Any) -> list[str] | None:
        """The frames for ``text`` as rosbridge's ``send`` cuts them; ``None`` when that send fails.

        The size is used as the client sent it, with Python's semantics: a string or other non-number
        fails every send (``len(...) > "big"`` raises), 0 fails (``range`` step 0), a float fails once a
        message is longer than it (``range`` wants ints), a negative size sends nothing at all.
        """
        size = self.fragment_size
        if size is None:
            return [text]
        if not isinstance(size, int | float):
            log.error("client %d: send failed: fragment_size %r is not a number", self.id, size)
            return None
        if len(text) <= size:
            return [text]
        if isinstance(size, float) or size == 0:
            log.error("client %d: send failed: cannot fragment with fragment_size %r", self.id, size)
            return None
        step = int(size)
        # Both lines compute ``total`` with Python 3's true division, so it is a float (5.5 for 5 parts;
        # 0.11.17 on Noetic, and the ros2 branch's fragmentation.py alike): the count is int(total).
        total = ((len(text) - 1) / step) + 1
        return [
            self.dumps(
                {"op": "fragment", "id": fragment_id, "data": text[i : i + step], "num": n, "total": total}
            )
            for n, i in enumerate(range(0, len(text), step))
        ]

    def _shed(self) -> None:
        """Drop the oldest data frames while the queue is over its bounds."""
        while self._droppable_count and (
            len(self._queue) > MAX_QUEUED_MESSAGES or self._queued_bytes > MAX_QUEUED_BYTES
        ):
            for index, item in enumerate(self._queue):
                if item.droppable:
                    del self._queue[index]
                    self._queued_bytes -= item.size
                    self._droppable_count -= 1
                    self.dropped += 1
                    if self.dropped in (1, 10, 100) or self.dropped % 1000 == 0:
                        log.warning(
                            "client %d reads too slowly: %d messages dropped so far", self.id, self.dropped
                        )
                    break

    async def writer(self) -> None:
        """Send queued frames until the connection closes."""
        try:
            while True:
                while not self._queue:
                    self._wakeup.clear()
                    await self._wakeup.wait()
                item = self._queue.popleft()
                self._queued_bytes -= item.size
                if item.droppable:
                    self._droppable_count -= 1
                for frame in item.frames:
                    await self.ws.send(frame)
        except ConnectionClosed:
            pass
        finally:
            self.closed = True

    # --- subscriptions --------------------------------------------------------------------------------

    def deliver(self, message: OutgoingMessage, fragment_id: Any) -> None:
        """Hand a topic message to this client, honouring throttle_rate and queue_length."""
        sub = self.subscriptions.get(message.topic)
        if sub is None or self.closed:
            return
        throttle = sub.throttle_rate / 1000.0
        if throttle <= 0:
            self._send_publish(sub, message, fragment_id)
            return
        now = time.monotonic()
        if sub.queue_length <= 0:
            # Throttled without a queue: a message arriving too soon after the last one is dropped.
            if now - sub.last_sent >= throttle:
                self._send_publish(sub, message, fragment_id)
            return
        sub.queue.append(message)
        while len(sub.queue) > sub.queue_length:
            sub.queue.popleft()
        if sub.release is None:
            delay = max(0.0, sub.last_sent + throttle - now)
            loop = asyncio.get_running_loop()
            sub.release = loop.call_later(delay, self._release, sub, fragment_id)

    def _release(self, sub: TopicSubscription, fragment_id: Any) -> None:
        sub.release = None
        if not sub.queue or self.subscriptions.get(sub.topic) is not sub:
            return
        self._send_publish(sub, sub.queue.popleft(), fragment_id)
        if sub.queue:
            loop = asyncio.get_running_loop()
            sub.release = loop.call_later(sub.throttle_rate / 1000.0, self._release, sub, fragment_id)

    def _send_publish(self, sub: TopicSubscription, message: OutgoingMessage, fragment_id: Any) -> None:
        sub.last_sent = time.monotonic()
        self._enqueue(
            message.frame_cbor(sub.echo_topic)
            if sub.cbor
            else message.frame_text(sub.echo_topic, png=sub.png, dumps=self.dumps),
            droppable=True,
            fragment_id=fragment_id,
        )

    def drop_subscription(self, topic: str) -> None:
        """Forget every subscription to ``topic`` (its queued messages too)."""
        sub = self.subscriptions.pop(topic, None)
        if sub is not None and sub.release is not None:
            sub.release.cancel()
