"""``read_recording``'s modes over one recording, each run in a worker thread within the call's budget: a
field's statistics over time (:func:`stats_answer`), a chart of fields (:func:`plot_answer`), the messages
around a moment (:func:`messages_answer`), the map with the path driven (:func:`map_answer`); and what every
answer shares (:class:`ReadRecordingAnswer`, the text budget: :func:`fit`)."""

from __future__ import annotations

import itertools
import json
import math
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel

from rosbridge_mcp_server.robot.occupancy import MapError, decode_grid
from rosbridge_mcp_server.tools.base import ToolAnswer, ToolFailure, ToolImage

if TYPE_CHECKING:
    from rosbridge_mcp_server.mcapfile import Budget
    from rosbridge_mcp_server.robot.occupancy import Grid
    from rosbridge_mcp_server.robot.recording.paths import PathReader
    from rosbridge_mcp_server.robot.recording.reading import RecordingSummary

__all__ = [
    "BUDGET",
    "MAX_SERIES",
    "PICTURE_SIZE",
    "ReadRecordingAnswer",
    "fit",
    "map_answer",
    "messages_answer",
    "plot_answer",
    "stats_answer",
    "wanted_fields",
]

#: The text budget of one answer.
BUDGET = 8000
MAX_SERIES = 8
MAX_MESSAGES = 50
PICTURE_SIZE = 800
_EXAMPLE = '["/odom pose.pose.position.x"]'


class ReadRecordingAnswer(BaseModel):
    """What was read; ``details`` holds the mode's own figures."""

    file: str | None
    mode: str
    details: dict[str, Any]


# --- fields -------------------------------------------------------------------------------------------------


def wanted_fields(fields: list[str] | None, summary: RecordingSummary) -> dict[str, list[str]]:
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


def stats_answer(
    file: str, summary: RecordingSummary, wanted: dict[str, list[str]], buckets: int, budget: Budget
) -> ToolAnswer:
    from rosbridge_mcp_server.pictures.charts import stats  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.robot.recording.reading import field_series  # noqa: PLC0415 - on first use

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
    text = fit(lines, "Fewer buckets or fields give the rest.")
    return ToolAnswer(
        text=text, data=ReadRecordingAnswer(file=file, mode="stats", details={"series": details})
    )


def plot_answer(
    file: str, summary: RecordingSummary, wanted: dict[str, list[str]], width: int, budget: Budget
) -> ToolAnswer:
    from rosbridge_mcp_server.pictures.charts import draw_chart, stats  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.pictures.drawing import png_bytes  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.robot.recording.reading import field_series  # noqa: PLC0415 - on first use

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


def messages_answer(
    file: str,
    summary: RecordingSummary,
    *,
    at: float | None,
    window: float,
    topics: list[str] | None,
    budget: Budget,
) -> ToolAnswer:
    from rosbridge_mcp_server.pictures.summary import summarize  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.robot.recording.reading import decoded_messages  # noqa: PLC0415 - on first use

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


def map_answer(
    file: str,
    summary: RecordingSummary,
    *,
    map_topic: str,
    path_topic: str,
    budget: Budget,
    max_size: int = PICTURE_SIZE,
) -> ToolAnswer:
    from rosbridge_mcp_server.pictures.drawing import png_bytes  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.pictures.maps import Overlay, draw_map  # noqa: PLC0415 - on first use

    known = {t.topic for t in summary.topics}
    if map_topic not in known:
        raise ToolFailure(
            f"{map_topic} is not in this recording (map_topic); its topics: {', '.join(sorted(known))}."
        )
    grid, reader = _map_and_path(file, summary, map_topic, path_topic, budget)
    found = reader.path(grid.frame_id)
    points = found.poses
    path = [(p.x, p.y) for p in points[:: max(1, len(points) // 2000)]]  # at most ~2,000 drawn
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


def fit(lines: list[str], more: str) -> str:
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


def _map_and_path(
    file: str, summary: RecordingSummary, map_topic: str, path_topic: str, budget: Budget
) -> tuple[Grid, PathReader]:
    """The recording read once: its last map decoded, and the path (with tf) fed to a reader."""
    from rosbridge_mcp_server.robot.recording.paths import PathReader  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.robot.recording.reading import decoded_messages  # noqa: PLC0415 - on first use

    known = {t.topic for t in summary.topics}
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
        return decode_grid(grid_message), reader
    except MapError as exc:
        raise ToolFailure(f"{map_topic}: {exc}") from None
