"""``record``'s work: topics chosen by name or glob, subscribed, and written to an MCAP file until the time is
up, a cap is reached, or the recording is stopped.

Every topic has its own subscription (its own rosbridge id, closed in ``finally``) and its own pump task,
which stamps each message with its receive time (the MCAP ``log_time``, as ``ros2 bag record`` does) and hands
it to the writer thread (:mod:`.writing`). The subscription's local queue is large; messages the pumps could
not keep up with (dropped from the queue) and those the writer refused are counted and reported as lost.
"""

from __future__ import annotations

import asyncio
import functools
import os
import time
from collections.abc import Awaitable, Callable, Mapping, Sequence
from dataclasses import dataclass
from fnmatch import fnmatchcase
from pathlib import Path
from typing import TYPE_CHECKING

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import (
    ConnectionLostError,
    RequestTimeoutError,
    RosbridgeError,
    UnknownTypeError,
)
from rosbridge_mcp_server.robot.recording.encoding import EncodingError, MessageCodec, message_codec
from rosbridge_mcp_server.robot.recording.timing import TopicTiming, timing_of
from rosbridge_mcp_server.robot.recording.writing import FreeBytes, McapFileWriter

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["NoTopicMatched", "RecordedTopic", "RecordingResult", "choose_topics", "record_topics"]

#: Messages a topic's subscription may hold before the oldest are dropped (and counted as lost).
SUBSCRIPTION_QUEUE = 5000
PROGRESS_EVERY = 1.0


class NoTopicMatched(ValueError):
    """No topic of the graph matched; ``str()`` names what was asked and the topics there are."""


@dataclass(frozen=True)
class RecordedTopic:
    """One topic's part of a recording."""

    topic: str
    type: str
    timing: TopicTiming
    lost: int
    problem: str | None


@dataclass(frozen=True)
class RecordingResult:
    """What was written: the file, its size, why it ended, and each topic."""

    path: Path
    size: int
    seconds: float
    ended: str  # "duration", "stopped", "size", "disk", "error: ..."
    topics: tuple[RecordedTopic, ...]
    skipped: tuple[str, ...]
    finish_error: str | None


def _is_glob(text: str) -> bool:
    return any(ch in text for ch in "*?[")


async def choose_topics(graph: RosGraph, wanted: Sequence[str]) -> list[tuple[str, str]]:
    """The graph's topics (name, type) that ``wanted``'s names and globs match, in the graph's order.

    A name that is not in the graph, or a glob that matches nothing, raises :class:`NoTopicMatched` naming
    the topics there are.
    """
    entries = [e for e in await graph.topics() if e.type]
    chosen: dict[str, str] = {}
    for pattern in wanted:
        text = pattern.strip()
        if not text.startswith("/") and not text.startswith("*"):
            text = "/" + text
        matched = [e for e in entries if (fnmatchcase(e.name, text) if _is_glob(text) else e.name == text)]
        if not matched:
            names = [e.name for e in entries]
            shown = ", ".join(names[:40]) + (f" and {len(names) - 40} more" if len(names) > 40 else "")
            what = "matches no topic" if _is_glob(text) else "is not in the ROS graph"
            raise NoTopicMatched(f"{pattern!r} {what}. The topics there are: {shown}.")
        for entry in matched:
            chosen.setdefault(entry.name, entry.type)
    return list(chosen.items())


async def record_topics(
    client: RosbridgeClient,
    graph: RosGraph,
    topics: Sequence[tuple[str, str]],
    *,
    path: Path,
    fd: int,
    duration: float,
    max_bytes: int,
    free_bytes: FreeBytes,
    stop: asyncio.Event | None = None,
    on_progress: Callable[[float, int, int], Awaitable[None]] | None = None,
    compression: str = "zstd",
) -> RecordingResult:
    """Record ``topics`` into the file open at ``fd`` for ``duration`` seconds (or until ``stop`` is set, or a
    cap ends it). The file is always finished, also when the call is cancelled.

    ``on_progress(seconds, messages, bytes)`` is called about once a second.
    """
    try:
        version, codecs, types, skipped = await _codecs(graph, topics)
    except BaseException:
        os.close(fd)  # the writer never took the file over
        raise
    stopped = stop or asyncio.Event()
    loop = asyncio.get_running_loop()
    writer = McapFileWriter(
        fd,
        codecs,
        ros_version=version,
        max_bytes=max_bytes,
        free_bytes=free_bytes,
        on_stop=lambda: _call_soon(loop, stopped.set),
        compression=compression,
    )
    lost = dict.fromkeys(codecs, 0)
    start = time.monotonic()
    end = start + duration
    pump = functools.partial(_pump, client, writer, stopped=stopped, end=end, lost=lost)
    tasks = [asyncio.create_task(pump(topic, types[topic], codecs[topic])) for topic in codecs]
    reporter = asyncio.create_task(_progress(on_progress, writer, start))
    try:
        if tasks:
            await asyncio.wait(tasks, timeout=duration + 5.0)
        else:
            await asyncio.wait_for(stopped.wait(), timeout=duration)
    except TimeoutError:
        pass
    except asyncio.CancelledError:
        stopped.set()
        raise
    finally:
        seconds = time.monotonic() - start
        # Finished also when the call was cancelled: the file must be readable whatever ended it.
        finish_error = await _finished([*tasks, reporter], writer)
    errors = [t.exception() for t in tasks if t.done() and not t.cancelled() and t.exception() is not None]
    ended, recorded = _ended(writer, stopped, errors), _recorded(writer, types, lost)
    return RecordingResult(
        path, _size(path), round(seconds, 2), ended, recorded, tuple(skipped), finish_error
    )


def _recorded(
    writer: McapFileWriter, types: Mapping[str, str], lost: Mapping[str, int]
) -> tuple[RecordedTopic, ...]:
    """What was recorded of each topic: its timing from the recording's first message, what was lost or
    failed."""
    state = writer.state
    start_ns = min((t[0] for t in state.times.values() if t), default=0)
    return tuple(
        RecordedTopic(
            topic, types[topic], timing_of(state.times[topic], start_ns), lost[topic], state.failed.get(topic)
        )
        for topic in types
    )


async def _codecs(
    graph: RosGraph, topics: Sequence[tuple[str, str]]
) -> tuple[int, dict[str, MessageCodec], dict[str, str], list[str]]:
    """The ROS version, a codec and the type of each topic whose type could be encoded, and the ones skipped
    with why."""
    codecs: dict[str, MessageCodec] = {}
    types: dict[str, str] = {}
    skipped: list[str] = []
    version = (await graph.dialect()).info.version
    for topic, msg_type in topics:
        try:
            typedefs = await graph.message_typedefs(msg_type)
            codecs[topic] = message_codec(msg_type, typedefs, version)
            types[topic] = msg_type
        except (EncodingError, UnknownTypeError, RosbridgeError) as exc:
            skipped.append(f"{topic} ({msg_type}): {exc}")
    return version, codecs, types, skipped


async def _pump(
    client: RosbridgeClient,
    writer: McapFileWriter,
    topic: str,
    msg_type: str,
    codec: MessageCodec,
    *,
    stopped: asyncio.Event,
    end: float,
    lost: dict[str, int],
) -> None:
    """One topic's messages into the writer until *end*, a stop, or the writer stopping; what was lost is
    counted in *lost*."""
    # CBOR where rosbridge can send it: byte arrays come as bytes, numbers as typed arrays, NaN and ±inf
    # as themselves (JSON sends both as null); a type with a fixed-size array comes as JSON.
    compression = Dialect.compression_for(fixed_size_arrays=codec.fixed_size_arrays)
    async with client.subscribe(
        topic, msg_type, max_queue=SUBSCRIPTION_QUEUE, compression=compression
    ) as sub:
        try:
            while not stopped.is_set():
                left = end - time.monotonic()
                if left <= 0:
                    return
                try:
                    message = await sub.get(min(left, 0.5))
                except RequestTimeoutError:
                    continue
                except ConnectionLostError:
                    continue  # the subscription is restored on the next connection: a gap, not an end
                if writer.state.stopped is not None:
                    return
                if not writer.put(topic, time.time_ns(), message):
                    lost[topic] += 1
        finally:
            lost[topic] += sub.dropped


async def _progress(
    on_progress: Callable[[float, int, int], Awaitable[None]] | None, writer: McapFileWriter, start: float
) -> None:
    while on_progress is not None:
        await asyncio.sleep(PROGRESS_EVERY)
        await on_progress(time.monotonic() - start, sum(writer.state.written.values()), writer.state.bytes_in)


def _ended(writer: McapFileWriter, stopped: asyncio.Event, errors: Sequence[BaseException | None]) -> str:
    """What ended the recording: the writer's cap, a stop, a failed topic, or its duration."""
    if writer.state.stopped is not None:
        return writer.state.stopped
    if stopped.is_set():
        return "stopped"
    if errors:
        return f"error: {errors[0]}"
    return "duration"


async def _finished(tasks: list[asyncio.Task[None]], writer: McapFileWriter) -> str | None:
    """Stop the pumps and finish the file (its last chunk, summary and index), to the end even when the call
    is cancelled again meanwhile; the first such cancel is raised once the file is finished."""
    for task in tasks:
        task.cancel()

    async def wind_down() -> str | None:
        await asyncio.gather(*tasks, return_exceptions=True)
        return await asyncio.to_thread(writer.close)

    closing = asyncio.ensure_future(wind_down())
    cancel: asyncio.CancelledError | None = None
    while not closing.done():
        try:
            await asyncio.shield(closing)
        except asyncio.CancelledError as exc:
            cancel = cancel or exc
    if cancel is not None:
        raise cancel
    return closing.result()


def _size(path: Path) -> int:
    try:
        return path.stat().st_size
    except OSError:
        return 0


def _call_soon(loop: asyncio.AbstractEventLoop, callback: Callable[[], object]) -> None:
    loop.call_soon_threadsafe(callback)
