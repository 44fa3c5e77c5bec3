"""What a recording holds, read with the ``mcap`` package: its summary, a field over time, the messages
around a moment.

The summary comes from the file's summary section (schemas, channels, statistics, chunk indexes) and its
message indexes (each chunk's log times per channel, read without decompressing a chunk), so a 1 GB recording
is summarised by reading a few kilobytes. A file without a summary section (a recorder that was killed) is
read through once. Messages are decoded by their schemas: ``ros2msg``/``cdr`` with ``mcap-ros2-support``,
``ros1msg``/``ros1`` with ``mcap-ros1-support``, ``json`` as JSON; whatever the file, whoever wrote it.
"""

from __future__ import annotations

import base64
import json
import math
import struct
from array import array
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from rosbridge_mcp_server.robot.recording.files import MCAP_MAGIC
from rosbridge_mcp_server.robot.recording.timing import TopicTiming, timing_of
from rosbridge_mcp_server.robot.series import FieldError, Series, unit_of, value_at

__all__ = [
    "NotARecording",
    "RecordingSummary",
    "TopicSummary",
    "decoded_messages",
    "field_series",
    "plain",
    "summarize_recording",
]

_MESSAGE_INDEX = 0x07
#: A file without a summary section is read through at most this far.
MAX_SCAN_BYTES = 2 * 1024**3


class NotARecording(ValueError):
    """The file is not an MCAP file, or is damaged; ``str()`` says what was found."""


@dataclass(frozen=True)
class TopicSummary:
    """One channel of a recording."""

    topic: str
    type: str
    encoding: str
    timing: TopicTiming


@dataclass(frozen=True)
class RecordingSummary:
    """What a recording holds."""

    path: Path
    size: int
    profile: str
    library: str
    start_ns: int
    end_ns: int
    messages: int
    topics: tuple[TopicSummary, ...]
    indexed: bool  #: whether it came from the summary and index (False: the file was read through)

    @property
    def seconds(self) -> float:
        return max(0, self.end_ns - self.start_ns) / 1e9


def _check_magic(handle: IO[bytes], path: Path) -> None:
    head = handle.read(len(MCAP_MAGIC))
    if head != MCAP_MAGIC:
        shown = head[:8]
        what = "an empty file" if not head else f"a file starting with {shown!r}"
        if head.startswith(b"#ROSBAG"):
            what = "a ROS 1 bag (.bag), not MCAP; convert it with `mcap convert`"
        elif head.startswith(b"SQLite format"):
            what = "a SQLite file (a ROS 2 .db3 bag?), not MCAP"
        raise NotARecording(
            f"{path.name} is not an MCAP recording: it is {what} (MCAP starts with \\x89MCAP0)."
        )


def summarize_recording(path: Path) -> RecordingSummary:
    """The summary of the MCAP file at ``path``; :class:`NotARecording` with the reason when it is not one."""
    from mcap.exceptions import McapError  # noqa: PLC0415
    from mcap.reader import SeekingReader  # noqa: PLC0415

    size = path.stat().st_size
    with path.open("rb") as handle:
        _check_magic(handle, path)
        handle.seek(0)
        try:
            reader = SeekingReader(handle)
            header = reader.get_header()
            summary = reader.get_summary()
        except (McapError, struct.error, ValueError, EOFError) as exc:
            summary = None
            header = None
            damaged = str(exc)
        else:
            damaged = ""
        if summary is None or summary.statistics is None or not summary.chunk_indexes:
            return _scan(path, size, header, damaged)
        times: dict[int, list[int]] = {cid: [] for cid in summary.channels}
        for chunk in summary.chunk_indexes:
            _index_times(handle, chunk, times)
        start, end = summary.statistics.message_start_time, summary.statistics.message_end_time
        topics = []
        for cid, channel in sorted(summary.channels.items(), key=lambda kv: kv[1].topic):
            schema = summary.schemas.get(channel.schema_id)
            topics.append(
                TopicSummary(
                    channel.topic,
                    schema.name if schema else "",
                    channel.message_encoding,
                    timing_of(times.get(cid, []), start),
                )
            )
        return RecordingSummary(
            path,
            size,
            header.profile if header else "",
            header.library if header else "",
            start,
            end,
            summary.statistics.message_count,
            tuple(topics),
            indexed=True,
        )


def _index_times(handle: IO[bytes], chunk: Any, times: dict[int, list[int]]) -> None:
    """Every message's log time of one chunk, per channel, from its message index records."""
    if not chunk.message_index_offsets:
        return
    begin = min(chunk.message_index_offsets.values())
    handle.seek(begin)
    data = handle.read(chunk.message_index_length)
    pos = 0
    while pos + 9 <= len(data):
        opcode = data[pos]
        (length,) = struct.unpack_from("<Q", data, pos + 1)
        body = pos + 9
        if opcode == _MESSAGE_INDEX and length >= 6:
            (channel,) = struct.unpack_from("<H", data, body)
            (records_len,) = struct.unpack_from("<I", data, body + 2)
            count = records_len // 16
            values = struct.unpack_from(f"<{count * 2}Q", data, body + 6)
            times.setdefault(channel, []).extend(values[0::2])
        pos = body + length


def _scan(path: Path, size: int, header: Any, damaged: str) -> RecordingSummary:
    """A file without a usable summary section, read through (messages up to where it breaks off)."""
    from mcap.exceptions import McapError  # noqa: PLC0415
    from mcap.reader import NonSeekingReader  # noqa: PLC0415

    times: dict[str, list[int]] = {}
    types: dict[str, tuple[str, str]] = {}
    read = 0
    with path.open("rb") as handle:
        try:
            for schema, channel, message in NonSeekingReader(handle, validate_crcs=False).iter_messages(
                log_time_order=False
            ):
                times.setdefault(channel.topic, []).append(message.log_time)
                types.setdefault(channel.topic, (schema.name if schema else "", channel.message_encoding))
                read += len(message.data)
                if read > MAX_SCAN_BYTES:
                    break
        except (McapError, struct.error, ValueError, EOFError):
            pass  # a file cut off mid-record: what came before counts
    if not times and damaged:
        raise NotARecording(f"{path.name} starts like MCAP but cannot be read: {damaged}")
    every = [t for ts in times.values() for t in ts]
    start, end = (min(every), max(every)) if every else (0, 0)
    topics = tuple(
        TopicSummary(topic, types[topic][0], types[topic][1], timing_of(ts, start))
        for topic, ts in sorted(times.items())
    )
    return RecordingSummary(
        path,
        size,
        getattr(header, "profile", ""),
        getattr(header, "library", ""),
        start,
        end,
        len(every),
        topics,
        indexed=False,
    )


def _decoder_factories() -> list[Any]:
    factories: list[Any] = []
    try:
        from mcap_ros2.decoder import DecoderFactory as Ros2Factory  # noqa: PLC0415

        factories.append(Ros2Factory())
    except ImportError:  # pragma: no cover - a dependency
        pass
    try:
        from mcap_ros1.decoder import DecoderFactory as Ros1Factory  # noqa: PLC0415

        factories.append(Ros1Factory())
    except ImportError:  # pragma: no cover - a dependency
        pass
    return factories


def plain(value: Any) -> Any:
    """A decoded message (generated classes with ``__slots__``) as JSON-like dicts and lists; byte arrays as
    base64 text, as rosbridge sends them."""
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float):
        return value
    if isinstance(value, bytes | bytearray | memoryview):
        return base64.b64encode(bytes(value)).decode()
    if isinstance(value, list | tuple):
        return [plain(item) for item in value]
    if isinstance(value, array):
        return value.tolist()
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    slots = getattr(type(value), "__slots__", None)
    if slots:
        names = [slots] if isinstance(slots, str) else list(slots)
        return {name: plain(getattr(value, name, None)) for name in names if not name.startswith("_")}
    if hasattr(value, "tolist"):
        return value.tolist()
    return str(value)


def decoded_messages(
    path: Path, topics: Sequence[str] | None = None, start_ns: int | None = None, end_ns: int | None = None
) -> Iterator[tuple[str, int, Any]]:
    """(topic, log time in ns, message as plain data) in log-time order; undecodable messages are skipped
    with a ``ValueError`` naming the encoding when no message could be decoded."""
    from mcap.reader import make_reader  # noqa: PLC0415

    factories = _decoder_factories()
    with path.open("rb") as handle:
        _check_magic(handle, path)
        handle.seek(0)
        reader = make_reader(handle, decoder_factories=factories)
        decoders: dict[int, Any] = {}
        for schema, channel, message in reader.iter_messages(
            topics=list(topics) if topics else None, starting_at=start_ns, ending_before=end_ns
        ):
            decoder = decoders.get(channel.id)
            if decoder is None:
                decoder = _decoder_for(factories, schema, channel)
                decoders[channel.id] = decoder
            yield channel.topic, message.log_time, plain(decoder(message.data))


def _decoder_for(factories: list[Any], schema: Any, channel: Any) -> Any:
    if channel.message_encoding == "json":
        return json.loads
    for factory in factories:
        decoder = factory.decoder_for(channel.message_encoding, schema)
        if decoder is not None:
            return decoder
    encoding = f"{channel.message_encoding} ({schema.encoding if schema else 'no schema'})"
    raise NotARecording(f"messages on {channel.topic} are {encoding}, which this reader cannot decode")


def field_series(
    path: Path, start_ns: int, wanted: dict[str, list[str]], types: dict[str, str]
) -> tuple[list[Series], dict[str, int]]:
    """Each topic's fields over the whole recording, times in seconds from ``start_ns``.

    Raises :class:`FieldError` when a topic's first message lacks a field.
    """
    series = {
        (t, p): Series(t, p, unit_of(types.get(t, ""), p)) for t, paths in wanted.items() for p in paths
    }
    counts = dict.fromkeys(wanted, 0)
    for topic, log_time, message in decoded_messages(path, list(wanted)):
        counts[topic] += 1
        at = (log_time - start_ns) / 1e9
        for field_path in wanted[topic]:
            try:
                value = value_at(message, field_path)
            except FieldError:
                if counts[topic] == 1:
                    raise
                value = math.nan
            line = series[(topic, field_path)]
            line.times.append(at)
            line.values.append(value)
    return list(series.values()), counts
