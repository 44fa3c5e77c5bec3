"""Listening to a topic for a while: N messages, or everything for some seconds, with receive times.

The subscription has its own rosbridge id, so closing it never removes another listener of the same topic
(rosbridge keeps one ROS subscription per topic and connection while any id remains). It is closed in
``finally``, also when the caller is cancelled. :func:`read_topic` is ``subscribe_topic``'s whole read: the
topic's type checked against the graph, the fields against the type, the QoS as the bridge's dialect takes
it, then the listen.
"""

from __future__ import annotations

import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from rosbridge_mcp_server.errors import (
    Advice,
    NotOnRobotError,
    NotSentError,
    RequestTimeoutError,
    ServiceError,
    UnknownTypeError,
)
from rosbridge_mcp_server.robot.messages import TypeDef, short_type_name
from rosbridge_mcp_server.robot.names import absolute_name

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = [
    "Heard",
    "Listening",
    "Readout",
    "byte_array_paths",
    "listen",
    "read_topic",
    "unknown_field_path",
]

_BYTE_TYPES = frozenset({"uint8", "char", "octet", "byte"})


@dataclass(frozen=True)
class Heard:
    """One message and when it arrived (seconds after the subscribe was sent)."""

    at: float
    message: dict[str, Any]


@dataclass(frozen=True)
class Listening:
    """What a listen collected; ``first_timed_out`` when not even one message came in time."""

    messages: tuple[Heard, ...]
    first_timed_out: bool
    listened: float  # seconds from subscribe to the end

    @property
    def rate_hz(self) -> float | None:
        """The observed rate (messages per second between the first and the last), when two or more came."""
        if len(self.messages) < 2:
            return None
        span = self.messages[-1].at - self.messages[0].at
        return (len(self.messages) - 1) / span if span > 0 else None


async def listen(
    client: RosbridgeClient,
    topic: str,
    msg_type: str | None,
    *,
    count: int,
    duration: float | None,
    first_timeout: float,
    qos: dict[str, Any] | None = None,
    on_message: Callable[[int], Awaitable[None]] | None = None,
    compression: Literal["cbor"] | None = None,
) -> Listening:
    """Up to ``count`` messages; with ``duration``, those that arrive within that many seconds.

    Waits at most ``first_timeout`` for the first message (a latched / transient-local topic answers at
    once), and without ``duration`` as long for each next one. ``compression="cbor"``: numeric arrays
    arrive as ``array.array`` and byte arrays as bytes (see ``wire/cbor.py``).
    """
    heard: list[Heard] = []
    start = time.monotonic()
    end = None if duration is None else start + duration
    async with client.subscribe(
        topic, msg_type, max_queue=max(count, 1), qos=qos, compression=compression
    ) as sub:
        while len(heard) < count:
            # The first message, and each gap without a duration, may take up to first_timeout; with a
            # duration the listen ends at its end (once something came).
            wait = first_timeout
            if heard and end is not None:
                wait = end - time.monotonic()
                if wait <= 0:
                    break
            try:
                message = await sub.get(wait)
            except RequestTimeoutError:
                break
            heard.append(Heard(time.monotonic() - start, message))
            if on_message is not None:
                await on_message(len(heard))
    return Listening(tuple(heard), first_timed_out=not heard, listened=time.monotonic() - start)


@dataclass(frozen=True)
class Readout:
    """What :func:`read_topic` heard, with what the caller needs to shorten it."""

    topic: str  #: absolute
    message_type: str  #: the graph's type, or the one given (spelled for the bridge)
    heard: Listening
    byte_fields: list[str]  #: dotted paths of the type's byte arrays ([] when rosapi could not describe it)
    qos_note: str | None  #: what the bridge makes of the QoS asked for, when some was


async def read_topic(
    graph: RosGraph,
    client: RosbridgeClient,
    topic: str,
    message_type: str | None,
    *,
    count: int,
    duration: float | None,
    first_timeout: float,
    fields: list[str] | None = None,
    qos: dict[str, Any] | None = None,
    on_message: Callable[[int], Awaitable[None]] | None = None,
) -> Readout:
    """Check the topic's type (the graph's, or *message_type* when it agrees) and *fields* against it, then
    :func:`listen` with the QoS as this bridge takes it (*qos*: reliability, durability, depth).

    Raises :class:`NotSentError` for a type that is not the topic's or a field path the type does not have,
    :class:`NotOnRobotError` for a topic nothing publishes when no type was given.
    """
    name = absolute_name(topic, "topic")
    dialect = await graph.dialect()
    graph_type = await graph.topic_type(name)
    if message_type:
        msg_type = dialect.message_type(message_type)
        if graph_type and not dialect.same_type(graph_type, msg_type):
            raise NotSentError(
                f"Topic {name} has type {graph_type}, not {msg_type}; rosbridge would not subscribe. Leave "
                "message_type out to use the topic's own type."
            )
    elif graph_type:
        msg_type = graph_type
    else:
        missing, _ = await graph.unknown_topic(name, " (nothing publishes it)")
        raise NotOnRobotError(missing).advise(Advice.TOPICS_OR_TYPE)
    typedefs = await _typedefs_or_none(graph, msg_type)
    if fields and typedefs and (problem := unknown_field_path(msg_type, typedefs, fields)):
        raise NotSentError(f"{problem} Nothing was subscribed; fix fields or leave them out.")
    wire_qos, qos_note = dialect.subscription_qos(qos)
    heard = await listen(
        client,
        name,
        msg_type,
        count=count,
        duration=duration,
        first_timeout=first_timeout,
        qos=wire_qos,
        on_message=on_message,
    )
    byte_fields = byte_array_paths(msg_type, typedefs) if typedefs else []
    return Readout(name, msg_type, heard, byte_fields, qos_note)


async def _typedefs_or_none(graph: RosGraph, msg_type: str) -> dict[str, TypeDef]:
    try:
        return await graph.message_typedefs(msg_type)
    except (UnknownTypeError, ServiceError, RequestTimeoutError):
        # Without a description the summary still spots byte arrays by their base64 look, and fields are
        # checked against the first message instead.
        return {}


def byte_array_paths(type_name: str, typedefs: dict[str, TypeDef], *, depth: int = 6) -> list[str]:
    """Dotted paths of every ``uint8[]``/``char[]`` field of a type (arrays of messages included)."""
    paths: list[str] = []

    def walk(current: str, prefix: str, left: int) -> None:
        typedef = typedefs.get(current)
        if typedef is None or left <= 0:
            return
        for name, base, length in _plain_fields(typedef):
            path = f"{prefix}{name}"
            if base in _BYTE_TYPES and length >= 0:
                paths.append(path)
            elif base in typedefs:
                walk(base, f"{path}.", left - 1)

    walk(short_type_name(type_name), "", depth)
    return paths


def unknown_field_path(type_name: str, typedefs: dict[str, TypeDef], paths: list[str]) -> str | None:
    """A sentence naming the first dotted path that is not a field of the type, or ``None`` when all are.

    Numbers in a path (array indices) are skipped; a path into a type rosapi did not describe is accepted.
    """
    for raw in paths:
        current: str | None = short_type_name(type_name)
        walked: list[str] = []
        for part in raw.strip().strip(".").split("."):
            if part.isdigit() or current is None:
                continue
            typedef = typedefs.get(current)
            if typedef is None:
                break
            names = {name: base for name, base, _ in _plain_fields(typedef)}
            if part not in names:
                where = f" in {'.'.join(walked)}" if walked else ""
                return (
                    f"Field {raw!r}: there is no {part!r}{where}; the fields there are: {', '.join(names)}."
                )
            walked.append(part)
            current = names[part] if names[part] in typedefs else None
    return None


def _plain_fields(typedef: TypeDef) -> list[tuple[str, str, int]]:
    """The fields with rosapi 2.1.0's Python-slot underscore (``_linear``) dropped from their names."""
    fields = list(typedef.fields())
    if fields and all(name.startswith("_") and len(name) > 1 for name, _, _ in fields):
        return [(name[1:], base, length) for name, base, length in fields]
    return fields
