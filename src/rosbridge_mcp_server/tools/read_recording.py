"""``read_recording``: the recordings in the recording directory, and what one holds — its topics, a field's
statistics over time, the messages around a moment, a chart of fields, or the map with the path driven (those
four modes are ``recording_modes.py``'s)."""

from __future__ import annotations

import asyncio
import functools
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import Field

from rosbridge_mcp_server.robot.series import FieldError
from rosbridge_mcp_server.robot.text import shown
from rosbridge_mcp_server.robot.wording import counted, size_text
from rosbridge_mcp_server.tools.arguments import FROM_JSON_TEXT
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolSpec,
)
from rosbridge_mcp_server.tools.recording_modes import (
    MAX_SERIES,
    PICTURE_SIZE,
    ReadRecordingAnswer,
    fit,
    map_answer,
    messages_answer,
    plot_answer,
    stats_answer,
    wanted_fields,
)

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.recording.reading import RecordingSummary

__all__ = ["SPEC", "ReadRecordingAnswer", "run"]

#: Topics a summary lists (text and structured content alike).
MAX_TOPICS = 500
#: stats: the recording's time span in this many windows.
BUCKETS = 10
_FIELDS = '["/turtle1/pose x y"]'

Mode = Literal["summary", "stats", "messages", "plot", "map"]


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
    from rosbridge_mcp_server.robot.recording.files import PathRefused, resolve_recording  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.robot.recording.reading import NotARecording, read_budget, summarize_recording  # noqa: PLC0415 - on first use

    directory = ctx.config.record_dir
    if file is None:
        return await asyncio.to_thread(_listing, directory)
    try:
        path = resolve_recording(directory, file)
    except PathRefused as exc:
        raise ToolFailure.carrying(exc) from None
    file = shown(file)  # echoed in every answer: a name found in the listing may hold what was escaped there
    if path.parent == directory.resolve() and path.name in ctx.robot.recordings.names():
        raise ToolFailure(
            f"{path.name} is still being recorded: its summary and index are written when the recording "
            f'ends. Read it then, or end it now: record {{"stop": true, "name": "{path.stem}"}}.'
        )
    budget = read_budget()  # one call's memory and time, shared by the summary and the mode
    try:
        summary = await asyncio.to_thread(summarize_recording, path, budget)
        if mode == "summary":
            return _summary(file, summary)
        if mode == "messages":
            reading = functools.partial(messages_answer, at=at, window=window, topics=topics, budget=budget)
            return await asyncio.to_thread(reading, file, summary)
        if mode == "map":
            pair = [*(topics or ["/map"]), "/odom"]  # the map, then the path (/odom unless given)
            drawing = functools.partial(map_answer, map_topic=pair[0], path_topic=pair[1], budget=budget)
            return await asyncio.to_thread(drawing, file, summary)
        wanted = wanted_fields(fields, summary)
        if mode == "stats":
            return await asyncio.to_thread(stats_answer, file, summary, wanted, BUCKETS, budget)
        return await asyncio.to_thread(plot_answer, file, summary, wanted, PICTURE_SIZE, budget)
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
    from rosbridge_mcp_server.robot.recording.files import list_recordings  # noqa: PLC0415 - on first use

    entries = list_recordings(directory)
    rows: list[dict[str, Any]] = []
    lines = [f"{counted(len(entries), 'recording')} in {str(directory)!r}" + (":" if entries else ".")]
    for entry in entries[:200]:
        when = time.strftime("%Y-%m-%d %H:%M", time.localtime(entry.modified))
        name = shown(entry.name)  # anyone may put a file there: its name is data
        rows.append({"file": name, "bytes": entry.size, "modified": when, "mcap": entry.is_mcap})
        lines.append(f"- {name}: {size_text(entry.size)}, {when}" + ("" if entry.is_mcap else " (not MCAP)"))
    if not entries:
        lines.append(
            'record {"topics": ["/rosout"], "duration": 10} makes one; MCAP files put there are read too.'
        )
    text = fit(lines, "Only the newest are shown.")
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
    text = fit(lines, f"The structured answer lists up to {MAX_TOPICS} topics.") + (
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
