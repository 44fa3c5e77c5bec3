"""``read_recording``: the recordings in the recording directory, and what one holds — its topics, a field's
statistics over time, the messages around a moment, a chart of fields, or the map with the path driven."""

from __future__ import annotations

import asyncio
import functools
import itertools
import json
import math
import time
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, Field

from rosbridge_mcp_server.mcapfile import Budget
from rosbridge_mcp_server.pictures.charts import draw_chart, stats
from rosbridge_mcp_server.pictures.drawing import png_bytes
from rosbridge_mcp_server.pictures.maps import Overlay, draw_map
from rosbridge_mcp_server.pictures.summary import summarize
from rosbridge_mcp_server.robot.occupancy import MapError, decode_grid
from rosbridge_mcp_server.robot.recording.files import (
    PathRefused,
    list_recordings,
    resolve_recording,
)
from rosbridge_mcp_server.robot.recording.paths import PathReader
from rosbridge_mcp_server.robot.recording.reading import (
    NotARecording,
    RecordingSummary,
    decoded_messages,
    field_series,
    read_budget,
    summarize_recording,
)
from rosbridge_mcp_server.robot.series import FieldError
from rosbridge_mcp_server.robot.wording import counted, size_text
from rosbridge_mcp_server.tools.arguments import FROM_JSON_TEXT
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolImage,
    ToolSpec,
)

__all__ = ["SPEC", "ReadRecordingAnswer", "run"]

#: The text budget of one answer.
BUDGET = 8000
MAX_SERIES = 8
MAX_MESSAGES = 50
#: Topics a summary lists (text and structured content alike).
MAX_TOPICS = 500
PICTURE_SIZE = 800
#: stats: the recording's time span in this many windows.
BUCKETS = 10
_EXAMPLE = '["/odom pose.pose.position.x"]'
_FIELDS = '["/turtle1/pose x y"]'

Mode = Literal["summary", "stats", "messages", "plot", "map"]


class ReadRecordingAnswer(BaseModel):
    """What was read; ``details`` holds the mode's own figures."""

    file: str | None
    mode: str
    details: dict[str, Any]


SPEC = ToolSpec(
    name="read_recording",
    title="Read a recording",
    description=(
        "No file: list them. Modes: summary (counts, rates, gaps), stats (fields), "
        'messages (around at), plot, map (path). Example: {"file": "run1.mcap"}'
    ),
    hints=READS_ROBOT,
    output=ReadRecordingAnswer,
)


async def run(
    ctx: ToolContext,
    *,
    file: Annotated[str | None, Field(description='e.g. "run1.mcap"')] = None,
    mode: Annotated[Mode, Field(description='e.g. "stats"')] = "summary",
    fields: Annotated[
        list[str] | None,
        Field(max_length=MAX_SERIES, description=f"e.g. {_FIELDS}"),
        FROM_JSON_TEXT,
    ] = None,
    at: Annotated[float | None, Field(ge=0, description="s, e.g. 12.5")] = None,
    window: Annotated[float, Field(gt=0, le=3600, description="e.g. 0.5")] = 0.5,
    topics: Annotated[
        list[str] | None,
        Field(max_length=50, description='map: map, path; e.g. ["/map", "/odom"]'),
        FROM_JSON_TEXT,
    ] = None,
) -> ToolAnswer:
    directory = ctx.config.record_dir
    if file is None:
        return await asyncio.to_thread(_listing, directory)
    try:
        path = resolve_recording(directory, file)
    except PathRefused as exc:
        raise ToolFailure.carrying(exc) from None
    budget = read_budget()  # one call's memory and time, shared by the summary and the mode
    try:
        summary = await asyncio.to_thread(summarize_recording, path, budget)
        if mode == "summary":
            return _summary(file, summary)
        if mode == "messages":
            reading = functools.partial(_messages, at=at, window=window, topics=topics, budget=budget)
            return await asyncio.to_thread(reading, file, summary)
        if mode == "map":
            pair = [*(topics or ["/map"]), "/odom"]  # the map, then the path (/odom unless given)
            drawing = functools.partial(_map, map_topic=pair[0], path_topic=pair[1], budget=budget)
            return await asyncio.to_thread(drawing, file, summary)
        wanted = _wanted(fields, summary)
        if mode == "stats":
            return await asyncio.to_thread(_stats, file, summary, wanted, BUCKETS, budget)
        return await asyncio.to_thread(_plot, file, summary, wanted, PICTURE_SIZE, budget)
    except NotARecording as exc:
        raise ToolFailure(f"{exc} It was not read further.") from None
    except OSError as exc:
        raise ToolFailure(f"Cannot read {file!r}: {exc.strerror or exc}.") from None
    except FieldError as exc:
        raise ToolFailure(f"{exc} Fix the field and call again.") from None
    except asyncio.CancelledError:
        budget.abandoned = True  # the reading thread stops at its next check instead of reading on
        raise


# --- listing ------------------------------------------------------------------------------------------------


def _listing(directory: Path) -> ToolAnswer:
    entries = list_recordings(directory)
    rows: list[dict[str, Any]] = []
    lines = [f"{counted(len(entries), 'recording')} in {str(directory)!r}" + (":" if entries else ".")]
    for entry in entries[:200]:
        when = time.strftime("%Y-%m-%d %H:%M", time.localtime(entry.modified))
        rows.append({"file": entry.name, "bytes": entry.size, "modified": when, "mcap": entry.is_mcap})
        lines.append(
            f"- {entry.name}: {size_text(entry.size)}, {when}" + ("" if entry.is_mcap else " (not MCAP)")
        )
    if not entries:
        lines.append(
            'record {"topics": ["/rosout"], "duration": 10} makes one; MCAP files put there are read too.'
        )
    text = _fit(lines, "Only the newest are shown.")
    return ToolAnswer(
        text=text, data=ReadRecordingAnswer(file=None, mode="list", details={"recordings": rows})
    )


# --- summary ------------------------------------------------------------------------------------------------


def _summary(file: str, summary: RecordingSummary) -> ToolAnswer:
    start = (
        time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(summary.start_ns / 1e9))
        if summary.start_ns
        else "?"
    )
    how = "from its summary and index" if summary.indexed else "read through (it has no summary section)"
    if summary.damaged:
        how += f"; it breaks off: {summary.damaged}, so only what came before is counted"
    how += f"; {summary.note}" if summary.note else ""
    lines = [
        f"{file}: {size_text(summary.size)}, {counted(summary.messages, 'message')} on "
        f"{counted(len(summary.topics), 'topic')} "
        "over "
        f"{summary.seconds:.1f} s from {start} (profile {summary.profile or '-'}; {how})."
    ]
    topics = []
    for t in summary.topics[:MAX_TOPICS]:
        timing = t.timing
        rate = f", {timing.rate_hz:g} Hz" if timing.rate_hz is not None else ""
        span = f", {timing.first:g}-{timing.last:g} s" if timing.first is not None else ""
        gaps = (
            "; gaps " + ", ".join(f"{g.seconds:g} s at {g.at:g} s" for g in timing.gaps)
            if timing.gaps
            else ""
        )
        count = f"{timing.count} message" + ("" if timing.count == 1 else "s")
        lines.append(f"- {t.topic} ({t.type}, {t.encoding}): {count}{rate}{span}{gaps}")
        topics.append(
            {
                "topic": t.topic,
                "type": t.type,
                "encoding": t.encoding,
                "messages": timing.count,
                "rate_hz": timing.rate_hz,
                "first": timing.first,
                "last": timing.last,
                "gaps": [{"at": g.at, "seconds": g.seconds} for g in timing.gaps],
            }
        )
    more = len(summary.topics) - MAX_TOPICS
    text = _fit(lines, f"The structured answer lists up to {MAX_TOPICS} topics.") + (
        f"\n{more} more topics are not listed." if more > 0 else ""
    )
    details = {
        "bytes": summary.size,
        "messages": summary.messages,
        "seconds": round(summary.seconds, 3),
        "start_ns": summary.start_ns,
        "profile": summary.profile,
        "indexed": summary.indexed,
        "topics": topics,
    }
    return ToolAnswer(text=text, data=ReadRecordingAnswer(file=file, mode="summary", details=details))


# --- fields -------------------------------------------------------------------------------------------------


def _wanted(fields: list[str] | None, summary: RecordingSummary) -> dict[str, list[str]]:
    if not fields:
        raise ToolFailure(f'Name the fields, e.g. {{"fields": {_EXAMPLE}}}.')
    known = {t.topic for t in summary.topics}
    wanted: dict[str, list[str]] = {}
    for item in fields:
        words = item.split()
        if len(words) < 2:
            raise ToolFailure(
                f'fields {item!r} needs a topic and at least one field, e.g. "/odom twist.twist.linear.x".'
            )
        if words[0] not in known:
            raise ToolFailure(f"{words[0]} is not in this recording; its topics: {', '.join(sorted(known))}.")
        paths = wanted.setdefault(words[0], [])
        paths.extend(p.strip(".") for p in words[1:] if p.strip(".") not in paths)
    if sum(len(p) for p in wanted.values()) > MAX_SERIES:
        raise ToolFailure(f"At most {MAX_SERIES} fields at once.")
    return wanted


def _types(summary: RecordingSummary) -> dict[str, str]:
    return {t.topic: t.type for t in summary.topics}


def _stats(
    file: str, summary: RecordingSummary, wanted: dict[str, list[str]], buckets: int, budget: Budget
) -> ToolAnswer:
    lines_found, counts = field_series(summary.path, summary.start_ns, wanted, _types(summary), budget)
    span = max(summary.seconds, 1e-9)
    lines = [f"{file}: {summary.seconds:.1f} s in {buckets} windows of {span / buckets:.3g} s."]
    details: list[dict[str, Any]] = []
    for line in lines_found:
        whole = stats(line)
        unit = f" {line.unit}" if line.unit else ""
        if whole.count == 0 or whole.min is None:
            lines.append(f"{line.label}: no numeric samples ({counts[line.topic]} messages).")
            details.append({"series": line.label, "samples": 0})
            continue
        lines.append(
            f"{line.label}{unit}: min {whole.min:.6g} max {whole.max:.6g} mean {whole.mean:.6g} last "
            f"{whole.last:.6g}, {whole.count} samples."
        )
        windows = []
        for index in range(buckets):
            low, high = index * span / buckets, (index + 1) * span / buckets
            values = [
                v
                for t, v in zip(line.times, line.values, strict=True)
                if (low <= t < high or (index == buckets - 1 and t == high)) and math.isfinite(v)
            ]
            if values:
                windows.append(
                    {
                        "from": round(low, 3),
                        "to": round(high, 3),
                        "n": len(values),
                        "min": float(f"{min(values):.6g}"),
                        "max": float(f"{max(values):.6g}"),
                        "mean": float(f"{sum(values) / len(values):.6g}"),
                    }
                )
        for w in windows:
            lines.append(
                f"  {w['from']:g}-{w['to']:g} s: n {w['n']} min {w['min']:g} max {w['max']:g} "
                f"mean {w['mean']:g}"
            )
        details.append(
            {
                "series": line.label,
                "unit": line.unit,
                "samples": whole.count,
                "min": whole.min,
                "max": whole.max,
                "mean": whole.mean,
                "windows": windows,
            }
        )
    text = _fit(lines, "Fewer buckets or fields give the rest.")
    return ToolAnswer(
        text=text, data=ReadRecordingAnswer(file=file, mode="stats", details={"series": details})
    )


def _plot(
    file: str, summary: RecordingSummary, wanted: dict[str, list[str]], width: int, budget: Budget
) -> ToolAnswer:
    lines_found, counts = field_series(summary.path, summary.start_ns, wanted, _types(summary), budget)
    if all(n == 0 for n in counts.values()):
        raise ToolFailure(f"No message of {', '.join(counts)} in {file}.")
    image = png_bytes(draw_chart(lines_found, max(summary.seconds, 1e-3), width, max(160, width // 2)))
    rows = []
    for line in lines_found:
        found = stats(line)
        if found.min is None:
            rows.append(f"{line.label}: no numeric samples")
        else:
            rows.append(
                f"{line.label}: min {found.min:.6g} max {found.max:.6g} mean {found.mean:.6g}, "
                f"{found.count} samples"
            )
    text = f"{file}, {summary.seconds:.1f} s: " + "; ".join(rows) + "."
    details = {"series": [{"series": line.label, "samples": len(line.values)} for line in lines_found]}
    return ToolAnswer(
        text=text,
        data=ReadRecordingAnswer(file=file, mode="plot", details=details),
        images=(ToolImage(image, "image/png"),),
    )


# --- messages -----------------------------------------------------------------------------------------------


def _messages(
    file: str,
    summary: RecordingSummary,
    *,
    at: float | None,
    window: float,
    topics: list[str] | None,
    budget: Budget,
) -> ToolAnswer:
    if at is None:
        raise ToolFailure(
            f"Give at (seconds from the start, 0-{summary.seconds:.1f}) for the messages around it."
        )
    if at - window > summary.seconds:
        # The meaningful bound is the file's own length (and a far later one overflowed the nanoseconds).
        raise ToolFailure(
            f"at {at:g} s is after the end of {file}, which is {summary.seconds:.1f} s long; give 0-"
            f"{summary.seconds:.1f}."
        )
    known = {t.topic for t in summary.topics}
    if topics:
        missing = [t for t in topics if t not in known]
        if missing:
            raise ToolFailure(
                f"{', '.join(missing)} not in this recording; its topics: {', '.join(sorted(known))}."
            )
    centre = summary.start_ns + int(at * 1e9)
    low, high = centre - int(window * 1e9), centre + int(window * 1e9) + 1
    shown: list[dict[str, Any]] = []
    total = 0
    lines = [f"{file}: messages from {max(0.0, at - window):g} to {at + window:g} s."]
    used = len(lines[0])
    for topic, log_time, message in decoded_messages(summary.path, topics, low, high, budget):
        total += 1
        if len(shown) >= MAX_MESSAGES:
            continue
        short = summarize(message)
        body = json.dumps(short.message, separators=(",", ":"), default=str, allow_nan=True)
        line = f"[{(log_time - summary.start_ns) / 1e9:.3f} s] {topic}: {body}"
        if used + len(line) > BUDGET - 300:
            if len(line) > 1500 and used + 1500 < BUDGET - 300:
                line = line[:1500] + "…"
            else:
                continue
        used += len(line) + 1
        lines.append(line)
        shown.append(
            {"topic": topic, "t": round((log_time - summary.start_ns) / 1e9, 6), "message": short.message}
        )
    if total == 0:
        lines.append("No message in that window; a larger window, or mode summary for the time span.")
    elif len(lines) - 1 < total:
        lines.append(f"{len(lines) - 1} of {total} shown; a smaller window or topics gives the rest.")
    details = {"total": total, "messages": shown}
    return ToolAnswer(
        text="\n".join(lines), data=ReadRecordingAnswer(file=file, mode="messages", details=details)
    )


# --- map ----------------------------------------------------------------------------------------------------


def _map(
    file: str,
    summary: RecordingSummary,
    *,
    map_topic: str,
    path_topic: str,
    budget: Budget,
    max_size: int = PICTURE_SIZE,
) -> ToolAnswer:
    known = {t.topic for t in summary.topics}
    if map_topic not in known:
        raise ToolFailure(
            f"{map_topic} is not in this recording (map_topic); its topics: {', '.join(sorted(known))}."
        )
    grid_message: dict[str, Any] | None = None
    tf_topics = [t.topic for t in summary.topics if t.type.replace("/msg/", "/") == "tf2_msgs/TFMessage"]
    wanted = list(dict.fromkeys([map_topic, *([path_topic] if path_topic in known else []), *tf_topics]))
    reader = PathReader(path_topic)
    for topic, log_time, message in decoded_messages(summary.path, wanted, budget=budget):
        if topic == map_topic:
            grid_message = message
        else:
            reader.feed(topic, log_time, message)
    if grid_message is None:
        raise ToolFailure(f"No message on {map_topic} in {file}.")
    try:
        grid = decode_grid(grid_message)
    except MapError as exc:
        raise ToolFailure(f"{map_topic}: {exc}") from None
    found = reader.path(grid.frame_id)
    points = found.poses
    step = max(1, len(points) // 2000)
    path = [(p.x, p.y) for p in points[::step]]
    overlay = Overlay(robot=points[-1] if points else None, path=path)
    picture = draw_map(grid, max_size=max_size, overlay=overlay)
    heard = any(t.topic == path_topic and t.timing.count for t in summary.topics)
    note = found.note if heard else f"{path_topic} has no message in the recording: no path drawn."
    note = note if path_topic in known else f"{path_topic} is not in the recording: no path drawn."
    travelled = sum(math.dist(a, b) for a, b in itertools.pairwise(path))
    where = (
        f", from ({points[0].x:.2f}, {points[0].y:.2f}) to ({points[-1].x:.2f}, {points[-1].y:.2f}) in "
        f"{grid.frame_id or 'the map frame'}"
        if points
        else ""
    )
    text = (
        f"{file}: {map_topic} ({grid.width}x{grid.height} cells of {grid.resolution:g} m) with "
        f"{len(points)} poses of {path_topic} ({travelled:.2f} m driven){where}."
    ) + (f" {note}" if note else "")
    details = {"poses": len(points), "metres": round(travelled, 3), "map_frame": grid.frame_id}
    details |= {"path_frame": found.frame, "placed": not found.note}
    return ToolAnswer(
        text=text,
        data=ReadRecordingAnswer(file=file, mode="map", details=details),
        images=(ToolImage(png_bytes(picture.image), "image/png"),),
    )


def _fit(lines: list[str], more: str) -> str:
    """Lines up to the budget; a note when some did not fit."""
    out: list[str] = []
    used = 0
    for index, line in enumerate(lines):
        if used + len(line) + 1 > BUDGET - 200:
            out.append(f"... {len(lines) - index} more lines. {more}")
            break
        out.append(line)
        used += len(line) + 1
    return "\n".join(out)
