"""What a recording holds, read within a budget: its summary, a field over time, the messages around a moment.

Every file is read through :mod:`rosbridge_mcp_server.mcapfile`, which holds what a file declares (sizes,
counts, offsets, nesting) to the file's real size and to one call's ``Budget`` (:func:`read_budget`: the
decode budget of pictures, ``robot/budget.py``'s ``DECODE_BUDGET``, and :data:`READ_SECONDS`): a file that
would cost more, or is malformed, is refused with what is wrong.

The summary comes from the file's summary section (schemas, channels, statistics, chunk indexes) and its
message indexes (each chunk's log times per channel, read without decompressing a chunk), so a 1 GB recording
is summarised by reading a few kilobytes. A file without a summary section (a recorder that was killed) is
read through once; when it is cut off, what came before counts. Messages are decoded by their schemas:
``ros2msg``/``cdr`` with ``mcap-ros2-support``, ``ros1msg``/``ros1`` with ``mcap-ros1-support``, ``json`` as
JSON; whatever the file, whoever wrote it.
"""

from __future__ import annotations

import base64
import json
import math
from array import array
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rosbridge_mcp_server.mcapfile import (
    INDEX_ENTRY_COST,
    MAX_NESTING,
    Budget,
    Channel,
    CutOff,
    DecodeCost,
    McapFile,
    OverBudget,
    RecordingProblem,
    Summary,
    decode_cost,
)
from rosbridge_mcp_server.robot.budget import DECODE_BUDGET
from rosbridge_mcp_server.robot.recording.timing import TopicTiming, timing_of
from rosbridge_mcp_server.robot.series import FieldError, Series, unit_of, value_at
from rosbridge_mcp_server.robot.text import shown

__all__ = [
    "READ_SECONDS",
    "NotARecording",
    "RecordingSummary",
    "TopicSummary",
    "decoded_messages",
    "field_series",
    "plain",
    "read_budget",
    "summarize_recording",
]

#: The seconds one call may spend reading a recording.
READ_SECONDS = 30.0
#: Bytes one sample of a field series holds (its time and value as Python floats in two lists).
SAMPLE_COST = 64


class NotARecording(RecordingProblem):
    """The file is not an MCAP file, is damaged, or would cost more than the budget; ``str()`` says what."""


def read_budget() -> Budget:
    """One call's budget: the memory a picture may take, and :data:`READ_SECONDS`."""
    return Budget(DECODE_BUDGET, READ_SECONDS)


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
    damaged: str = ""  #: where a file read through breaks off, when it does
    note: str = ""  #: what the summary could not work out within the budget

    @property
    def seconds(self) -> float:
        return max(0, self.end_ns - self.start_ns) / 1e9


def _opened(path: Path, budget: Budget | None) -> tuple[Any, McapFile]:
    handle = path.open("rb")
    try:
        return handle, McapFile(handle, path.stat().st_size, budget or read_budget(), path.name)
    except BaseException:
        handle.close()
        raise


def summarize_recording(path: Path, budget: Budget | None = None) -> RecordingSummary:
    """The summary of the MCAP file at ``path``; :class:`NotARecording` with the reason when it is not one or
    cannot be read within the budget."""
    try:
        handle, mcap = _opened(path, budget)
        with handle:
            mcap.header()
            summary = mcap.summary()
            if summary is None or summary.statistics is None or not summary.chunk_indexes:
                return _scan(path, mcap)
            return _indexed(path, mcap, summary)
    except RecordingProblem as exc:
        raise _refusal(path, exc) from None


#: The longest topic, type or profile name shown as it is (longer ones are cut, the cut said).
NAME_CHARS = 200


def _topic(channel: Channel) -> str:
    """A channel's topic as this server names it: the file's text, escaped (and so compared)."""
    return shown(channel.topic, NAME_CHARS)


def _refusal(path: Path, problem: RecordingProblem) -> NotARecording:
    text = str(problem)
    text = text if text.startswith(path.name) else f"{path.name}: {text}"
    return NotARecording(shown(text, 2000) + ".")  # it may quote the file's own names


def _indexed(path: Path, mcap: McapFile, summary: Summary) -> RecordingSummary:
    assert summary.statistics is not None
    start, end = summary.statistics.start, summary.statistics.end
    note = ""
    try:
        times = mcap.message_times(summary)
        timings = {cid: timing_of(times.get(cid, array("Q")), start) for cid in summary.channels}
    except OverBudget as exc:
        # Too many messages to time each one: the counts the file declares, and mean rates over its span.
        note = f"{exc}; counts and mean rates are the file's statistics, gaps are not known"
        declared, span = summary.statistics.channel_counts, max(end - start, 0) / 1e9
        timings = {cid: _counted(declared.get(cid, 0), span) for cid in summary.channels}
    topics = [
        TopicSummary(
            _topic(channel),
            shown(schema.name, NAME_CHARS) if (schema := summary.schemas.get(channel.schema_id)) else "",
            shown(channel.message_encoding, NAME_CHARS),
            timings[cid],
        )
        for cid, channel in sorted(summary.channels.items(), key=lambda kv: kv[1].topic)
    ]
    return RecordingSummary(
        path,
        mcap.size,
        shown(mcap.profile, NAME_CHARS),
        shown(mcap.library, NAME_CHARS),
        start,
        end,
        summary.statistics.message_count,
        tuple(topics),
        indexed=True,
        note=note,
    )


def _counted(count: int, span: float) -> TopicTiming:
    rate = round((count - 1) / span, 2) if count > 1 and span > 0 else None
    return TopicTiming(count, None, None, rate, ())


def _scan(path: Path, mcap: McapFile) -> RecordingSummary:
    """A file without a usable summary section, read through (messages up to where it breaks off)."""
    times: dict[int, array[int]] = {}
    damaged = ""
    count = 0
    try:
        for channel, log_time, _ in mcap.messages(wanted=set()):
            times.setdefault(channel.id, array("Q")).append(log_time)
            count += 1
            if count % 65536 == 0:
                mcap.budget.check_bytes(
                    f"{path.name} holds over {count} messages; their times would take",
                    count * INDEX_ENTRY_COST,
                )
    except CutOff as exc:
        if not count:
            raise
        damaged = shown(str(exc), 2000)
    every = [t for ts in times.values() for t in (min(ts), max(ts))]
    start, end = (min(every), max(every)) if every else (0, 0)
    topics = []
    for cid, ts in times.items():
        known = mcap.channels.get(cid)
        schema = mcap.schemas.get(known.schema_id) if known else None
        topics.append(
            TopicSummary(
                _topic(known) if known else f"(channel {cid})",
                shown(schema.name, NAME_CHARS) if schema else "",
                shown(known.message_encoding, NAME_CHARS) if known else "",
                timing_of(ts, start),
            )
        )
    topics.sort(key=lambda topic: topic.topic)
    return RecordingSummary(
        path,
        mcap.size,
        shown(mcap.profile, NAME_CHARS),
        shown(mcap.library, NAME_CHARS),
        *(start, end, count, tuple(topics), False, damaged),
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
    path: Path,
    topics: Sequence[str] | None = None,
    start_ns: int | None = None,
    end_ns: int | None = None,
    budget: Budget | None = None,
) -> Iterator[tuple[str, int, Any]]:
    """(topic, log time in ns, message as plain data) in the file's order; :class:`NotARecording` naming the
    problem when a message cannot be decoded, or the file not read within the budget."""
    try:
        handle, mcap = _opened(path, budget)
        with handle:
            summary = mcap.summary()
            factories = _decoder_factories()
            wanted = None
            if summary is not None and topics:
                wanted = {cid for cid, ch in summary.channels.items() if _topic(ch) in topics}
            decoders: dict[int, tuple[Any, DecodeCost | None]] = {}
            for channel, log_time, data in mcap.messages(wanted, start_ns, end_ns, summary):
                if data is None or (topics and _topic(channel) not in topics):
                    continue
                mcap.budget.check_time()
                if channel.id not in decoders:
                    decoders[channel.id] = _decoder_for(factories, mcap, channel)
                decoder, cost = decoders[channel.id]
                if cost is not None:
                    mcap.budget.check_bytes(
                        f"the message on {channel.topic[:100]} at log time {log_time} ns holds {len(data)} "
                        "bytes; decoded by its schema it could take",
                        cost.memory(len(data)),
                    )
                yield _topic(channel), log_time, _decoded(decoder, data, channel.topic, log_time)
    except RecordingProblem as exc:
        raise _refusal(path, exc) from None


def _decoded(decoder: Any, data: bytes, topic: str, log_time: int) -> Any:
    try:
        message = plain(decoder(data))
    except RecursionError:
        message = None
    except Exception as exc:  # a message its own schema does not describe: the file's fault, worded
        raise RecordingProblem(
            f"the message on {topic[:100]} at log time {log_time} ns cannot be decoded: "
            f"{type(exc).__name__}: {str(exc)[:200]}"
        ) from None
    if message is None or _depth(message) > MAX_NESTING:
        raise RecordingProblem(
            f"the message on {topic[:100]} at log time {log_time} ns nests over {MAX_NESTING} levels deep; "
            "it was not decoded"
        )
    return message


def _depth(value: Any) -> int:
    """How deep lists and dicts nest in ``value``, counted without recursion (stopping past the cap)."""
    deepest = 0
    stack = [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict | list):
            deepest = max(deepest, depth)
            if deepest > MAX_NESTING:
                return deepest
            stack.extend((child, depth + 1) for child in (item.values() if isinstance(item, dict) else item))
    return deepest


def _decoder_for(factories: list[Any], mcap: McapFile, channel: Any) -> tuple[Any, DecodeCost | None]:
    """The channel's decoder and what a message may cost decoded by its schema."""
    if channel.message_encoding == "json":
        return json.loads, None
    schema = mcap.schemas.get(channel.schema_id)
    cost = None if schema is None else decode_cost(schema)
    if isinstance(cost, str):
        raise RecordingProblem(f"messages on {channel.topic[:100]} cannot be read: {cost}")
    for factory in factories:
        try:
            decoder = factory.decoder_for(channel.message_encoding, schema)
        except RecursionError:
            decoder = None
        except Exception as exc:  # the decoder cannot parse the schema: the file's fault, worded
            raise RecordingProblem(
                f"the schema of {channel.topic[:100]} cannot be parsed: "
                f"{type(exc).__name__}: {str(exc)[:200]}"
            ) from None
        if decoder is not None:
            return decoder, cost
    encoding = f"{channel.message_encoding} ({schema.encoding if schema else 'no schema'})"
    raise RecordingProblem(
        f"messages on {channel.topic[:100]} are {encoding[:100]}, which this reader cannot decode"
    )


def field_series(
    path: Path,
    start_ns: int,
    wanted: dict[str, list[str]],
    types: dict[str, str],
    budget: Budget | None = None,
) -> tuple[list[Series], dict[str, int]]:
    """Each topic's fields over the whole recording, times in seconds from ``start_ns``.

    Raises :class:`FieldError` when a topic's first message lacks a field.
    """
    series = {
        (t, p): Series(t, p, unit_of(types.get(t, ""), p)) for t, paths in wanted.items() for p in paths
    }
    counts = dict.fromkeys(wanted, 0)
    budget = budget or read_budget()
    for topic, log_time, message in decoded_messages(path, list(wanted), budget=budget):
        counts[topic] += 1
        if counts[topic] % 65536 == 0:
            samples = sum(len(line.times) for line in series.values())
            if samples * SAMPLE_COST > budget.memory:
                raise _refusal(
                    path,
                    RecordingProblem(f"its fields hold over {samples} samples, over the budget of one call"),
                )
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
