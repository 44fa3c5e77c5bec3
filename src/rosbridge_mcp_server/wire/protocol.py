"""The rosbridge v2 wire protocol, without I/O.

Builders return plain dicts for the ops a client sends; :func:`encode` turns one into the text of one
WebSocket frame. :class:`InboundDecoder` turns received frames into events (a ``publish`` routed by
topic, a reply routed by id, or a notice worth logging), with :class:`~.fragments.FragmentAssembler`
rebuilding messages the server split into ``fragment`` ops. :class:`IdMinter` makes readable unique ids.

Facts about real servers that shape this module (more in ``docs/rosbridge-behaviour.md``):

* rosbridge_suite (ROS 1 0.11.x, every ROS 2 release) reads some keys before its per-op error
  handler, so ``png``, ``message_intervall`` or ``fragment_size: null`` can silently kill a
  connection's reader. No builder here ever emits them.
* ROS 2 servers may write bare ``NaN``/``Infinity`` tokens (fixed-size float arrays), so parsing is
  lenient; the server's own parser accepts them inbound too.
"""

from __future__ import annotations

import itertools
import json
import re
import secrets
from dataclasses import dataclass, field
from typing import Any, Final, Literal

from rosbridge_mcp_server.errors import ProtocolError
from rosbridge_mcp_server.wire.cbor import decode_cbor
from rosbridge_mcp_server.wire.fragments import FragmentAssembler

__all__ = [
    "BRIDGE_MAX_FRAME_BYTES",
    "ID_NAME_CHARS",
    "REPLY_OPS",
    "IdMinter",
    "InboundDecoder",
    "Notice",
    "PublishEvent",
    "ReplyEvent",
    "advertise",
    "call_service",
    "cancel_action_goal",
    "encode",
    "publish",
    "send_action_goal",
    "subscribe",
    "unadvertise",
    "unsubscribe",
]

#: The largest frame rosbridge takes: ROS 2 rosbridge runs on tornado, whose default
#: ``websocket_max_message_size`` (10 MiB, not overridden by rosbridge 2.x) closes the connection (code 1009)
#: on a larger frame. ROS 1's 0.11.17 (autobahn) sets no limit; the same bound keeps what one request costs
#: the robot's link the same on both lines.
BRIDGE_MAX_FRAME_BYTES: Final = 10 * 1024 * 1024
#: At most this much of a name goes into a request id.
ID_NAME_CHARS: Final = 100

#: Server → client ops answered to one of our requests, matched by ``id``.
REPLY_OPS: Final = frozenset({"service_response", "action_feedback", "action_result"})

_encoder = json.JSONEncoder(separators=(",", ":"), ensure_ascii=False, allow_nan=True)
_decoder = json.JSONDecoder()
#: A JSON escape of a UTF-16 surrogate: a pair is one character once decoded, a lone one is no text at all.
_ESCAPED_SURROGATE = re.compile(r"\\u[dD][89a-fA-F]")
_SURROGATE = re.compile("[\ud800-\udfff]")


def encode(op: dict[str, Any]) -> str:
    """The text of one frame: exactly one JSON object, compact.

    ``NaN``/``Infinity`` are written as bare tokens, which rosbridge's parser accepts (and ``null``
    for a float field it rejects).
    """
    return _encoder.encode(op)


# --- builders ---------------------------------------------------------------------------------------


def advertise(
    topic: str, msg_type: str, *, id: str, latch: bool = False, queue_size: int = 10
) -> dict[str, Any]:
    """``advertise``: create (or share) the bridge's publisher for *topic*."""
    return {
        "op": "advertise",
        "id": id,
        "topic": topic,
        "type": msg_type,
        "latch": bool(latch),
        "queue_size": int(queue_size),
    }


def unadvertise(topic: str, *, id: str | None = None) -> dict[str, Any]:
    """``unadvertise``: drop our advertisement *id* of *topic* (all of ours if no id)."""
    op: dict[str, Any] = {"op": "unadvertise", "topic": topic}
    if id is not None:
        op["id"] = id
    return op


def publish(topic: str, msg: dict[str, Any], *, id: str | None = None, latch: bool = False) -> dict[str, Any]:
    """``publish``: one message on an advertised topic.

    A publish on a latched advertisement must say ``latch`` too: both rosbridge lines register the publisher
    again with the publish's own flag, and a non-latched registration of a latched topic logs two warnings
    per message (on Kilted's 2.1.0, where a warning can raise, the message is then lost).
    """
    op: dict[str, Any] = {"op": "publish", "topic": topic, "msg": msg}
    if id is not None:
        op["id"] = id
    if latch:
        op["latch"] = True
    return op


def subscribe(
    topic: str,
    msg_type: str | None,
    *,
    id: str,
    throttle_rate: int = 0,
    queue_length: int = 0,
    qos: dict[str, Any] | None = None,
    compression: Literal["cbor"] | None = None,
) -> dict[str, Any]:
    """``subscribe`` with its own id, so it can be removed without touching other listeners.

    ``throttle_rate`` and ``queue_length`` must be JSON integers: every server type-checks them and
    silently ignores a subscribe with ``100.0``. ``qos`` is ROS 2's QoS object (rosbridge 2.0.7 / 2.7.0 /
    3.3.0 on); older servers and ROS 1 ignore the key. ``compression="cbor"`` asks for binary CBOR
    frames (ROS 1 0.11.17, ROS 2 2.1.0 and rosbridge-server-rs 0.1.6 send them; a server that ignores the
    key sends JSON, which is decoded the same). rosbridge uses CBOR for every subscription of the
    connection to that topic once one asks for it.
    """
    op: dict[str, Any] = {"op": "subscribe", "id": id, "topic": topic}
    if msg_type:
        op["type"] = msg_type
    if throttle_rate:
        op["throttle_rate"] = int(throttle_rate)
    if queue_length:
        op["queue_length"] = int(queue_length)
    if qos:
        op["qos"] = qos
    if compression:
        op["compression"] = compression
    return op


def unsubscribe(topic: str, *, id: str) -> dict[str, Any]:
    """``unsubscribe`` one subscription id (never the id-less form, which drops every listener)."""
    return {"op": "unsubscribe", "id": id, "topic": topic}


def call_service(
    service: str,
    args: dict[str, Any] | list[Any] | None,
    *,
    id: str,
    timeout: float | None = None,
) -> dict[str, Any]:
    """``call_service``; *timeout* (seconds) is the ROS 2 field (Humble 2.0.1+, Jazzy 2.2.0+)."""
    op: dict[str, Any] = {"op": "call_service", "id": id, "service": service}
    if args is not None:
        op["args"] = args
    if timeout is not None and timeout > 0:
        op["timeout"] = float(timeout)
    return op


def send_action_goal(
    action: str,
    action_type: str,
    args: dict[str, Any] | list[Any] | None,
    *,
    id: str,
    feedback: bool = True,
) -> dict[str, Any]:
    """``send_action_goal`` (ROS 2 only); the field is ``action_type``, not ``type``."""
    op: dict[str, Any] = {
        "op": "send_action_goal",
        "id": id,
        "action": action,
        "action_type": action_type,
        "feedback": bool(feedback),
    }
    if args is not None:
        op["args"] = args
    return op


def cancel_action_goal(action: str, *, id: str) -> dict[str, Any]:
    """``cancel_action_goal``: *id* is the goal's id; the server sends no direct reply."""
    return {"op": "cancel_action_goal", "id": id, "action": action}


# --- ids --------------------------------------------------------------------------------------------


class IdMinter:
    """Readable, unique request ids such as ``call_service:/add_two_ints:7``.

    Goal ids also carry a random per-client token: rosbridge keeps its goal table per *process*
    (a class attribute in ``send_action_goal.py``, every ROS 2 release), so two clients using the
    same goal id would cancel each other's goals.
    """

    __slots__ = ("_counter", "token")

    def __init__(self, token: str | None = None) -> None:
        self.token = token if token is not None else secrets.token_hex(4)
        self._counter = itertools.count(1)

    def mint(self, op: str, name: str) -> str:
        """A fresh id for *op* on *name* (topic, service or action)."""
        return f"{op}:{_id_name(name)}:{next(self._counter)}"

    def goal_id(self, action: str) -> str:
        """A goal id unique across every client of the bridge."""
        return f"goal:{_id_name(action)}:{self.token}-{next(self._counter)}"


def _id_name(name: str) -> str:
    # The name is there to read a log; the counter makes the id unique. A whole name would make every frame
    # that carries it twice as large: a 6 MB topic name became a 12 MB advertise, which the bridge answered
    # by dropping the connection.
    return name if len(name) <= ID_NAME_CHARS else name[: ID_NAME_CHARS - 3] + "..."


# --- inbound ----------------------------------------------------------------------------------------


def _parsed(text: str) -> Any:
    """One JSON text decoded, every unpaired UTF-16 surrogate (``"\\ud800"``, which JSON may carry and no
    text can hold) replaced by U+FFFD: anyone on the robot's graph can publish one, and written on as it came
    it ends whatever writes it (the MCP SDK's JSON writer refuses it, and the stdio server with it)."""
    item = _decoder.decode(text)
    # The usual frame holds no backslash at all (a memchr: 0.2 ms for a 9 MB image, where the pattern's scan
    # costs 10 ms), or no surrogate escape: nothing more to look at.
    if "\\" not in text or _ESCAPED_SURROGATE.search(text) is None:
        return item
    whole = _encoder.encode(item)
    return _decoder.decode(_SURROGATE.sub("\ufffd", whole)) if _SURROGATE.search(whole) else item


# Not frozen: a frozen dataclass's __init__ costs a microsecond per frame on the hot path.
@dataclass(slots=True)
class PublishEvent:
    """A message on a topic we subscribed to (rosbridge sends it without an id)."""

    topic: str
    msg: dict[str, Any]
    #: It came as a binary CBOR frame: typed arrays as ``array.array``, ``uint8[]`` as bytes (a listener that
    #: asked for JSON gets :func:`~rosbridge_mcp_server.wire.cbor.json_shaped` of it).
    binary: bool = False


@dataclass(slots=True)
class ReplyEvent:
    """A reply to request *id*: service_response, action_feedback, action_result or an error status."""

    op: str
    id: str
    frame: dict[str, Any]


@dataclass(slots=True)
class Notice:
    """A frame we do not act on, with the reason; the client logs it and moves on."""

    level: Literal["debug", "info", "warning"]
    text: str
    frame: dict[str, Any] | None = field(default=None)


InboundEvent = PublishEvent | ReplyEvent | Notice

_PREVIEW = 200


def _short(exc: Exception) -> str:
    text = str(exc)
    return text[:_PREVIEW] + ("…" if len(text) > _PREVIEW else "")


def _preview(data: str | bytes) -> str:
    text = data if isinstance(data, str) else repr(data[:_PREVIEW])
    return text[:_PREVIEW] + ("…" if len(text) > _PREVIEW else "")


class InboundDecoder:
    """Turns received frames into events; never raises.

    One decoder per connection, because fragment buffers belong to the connection.
    """

    def __init__(self, assembler: FragmentAssembler | None = None) -> None:
        self.assembler = assembler if assembler is not None else FragmentAssembler()

    def feed(self, data: str | bytes) -> InboundEvent:
        """Decode one WebSocket frame."""
        if isinstance(data, bytes | bytearray | memoryview):
            # Binary frames are CBOR answers to subscriptions asking for it: the same ops as JSON.
            try:
                item = decode_cbor(data)
            except ValueError as exc:
                return Notice("warning", f"binary frame of {len(data)} bytes ignored ({_short(exc)})")
            except RecursionError:
                return Notice("warning", "binary frame nested too deep to decode ignored")
            if not isinstance(item, dict):
                return Notice("warning", f"binary frame of {len(data)} bytes that is not a CBOR map ignored")
            event = self.route(item)
            if isinstance(event, PublishEvent):
                event.binary = True
            return event
        try:
            frame = _parsed(data)
        except ValueError as exc:
            return Notice("warning", f"malformed JSON frame ignored ({_short(exc)}): {_preview(data)}")
        except RecursionError:
            # Python's JSON parser recurses once per level; no rosbridge message nests anywhere near
            # this deep.
            return Notice("warning", f"frame nested too deep to parse ignored: {_preview(data)}")
        if not isinstance(frame, dict):
            return Notice("warning", f"frame that is not a JSON object ignored: {_preview(data)}")
        return self.route(frame)

    def route(self, frame: dict[str, Any]) -> InboundEvent:
        """Classify one decoded frame."""
        op = frame.get("op")
        if not isinstance(op, str):
            return Notice("warning", "frame without an op ignored", frame)
        if op == "publish":
            topic = frame.get("topic")
            msg = frame.get("msg")
            if isinstance(topic, str) and isinstance(msg, dict):
                return PublishEvent(topic, msg)
            return Notice("warning", "publish frame without topic or msg object ignored", frame)
        if op in REPLY_OPS:
            rid = frame.get("id")
            if isinstance(rid, str):
                return ReplyEvent(op, rid, frame)
            if rid is not None:
                return ReplyEvent(op, str(rid), frame)
            return Notice("warning", f"{op} without an id ignored (we always send one)", frame)
        if op == "fragment":
            try:
                text = self.assembler.add(frame)
            except ProtocolError as exc:
                return Notice("warning", str(exc))
            if text is None:
                return Notice("debug", "fragment buffered")
            try:
                whole = _parsed(text)
            except ValueError as exc:
                return Notice("warning", f"reassembled fragments are not JSON ({_short(exc)}); dropped")
            except RecursionError:
                return Notice("warning", "reassembled fragments nest too deep to parse; dropped")
            if not isinstance(whole, dict) or whole.get("op") == "fragment":
                return Notice("warning", "reassembled fragments are not a rosbridge op; dropped")
            return self.route(whole)
        if op == "status":
            # rosbridge_suite never sends status (ROS 1 0.11.x, ROS 2 all); other bridges do:
            # rosbridge-server-rs 0.1.6 answers a failed op with one (level "error", the op's id).
            # An error naming a request of ours goes to it (a refused call fails now, not at its
            # timeout); anything else is logged, never waited for.
            level = frame.get("level")
            rid = frame.get("id")
            if level == "error" and rid is not None:
                return ReplyEvent("status", rid if isinstance(rid, str) else str(rid), frame)
            return Notice("info", f"bridge status ({level}): {frame.get('msg')}", frame)
        if op == "png":
            return Notice("warning", "png frame ignored (we never ask for png compression)", frame)
        return Notice("warning", f"unsupported op {op[:100]!r} ignored", frame)
