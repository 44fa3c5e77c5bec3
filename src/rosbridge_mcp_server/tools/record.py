"""``record``: topics written to an MCAP file in the recording directory, for some seconds or until
stopped."""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.wording import counted, size_text
from rosbridge_mcp_server.tools.arguments import FROM_JSON_TEXT
from rosbridge_mcp_server.tools.base import (
    LongWork,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolHints,
    ToolSpec,
)

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable

    from rosbridge_mcp_server.robot.recording.recorder import RecordingResult
    from rosbridge_mcp_server.safety.policy import RecordingLimits

__all__ = ["SPEC", "RecordAnswer", "run"]

#: Longest recording without a policy cap, and the size cap when none is given.
MAX_SECONDS = 3600.0
DEFAULT_MEGABYTES = 1000.0
MAX_TOPICS = 100

_ENDINGS = {
    "duration": "its time was up",
    "stopped": "it was stopped",
    "size": "it reached the size cap",
    "disk": "the disk neared its 32 MB floor (all recordings together stop above it: each file is whole)",
}


class RecordAnswer(BaseModel):
    """The file written, and what it holds."""

    file: str
    bytes: int
    seconds: float
    ended: str
    #: Per topic: topic, type, messages, rate_hz, lost, gaps [{at, seconds}], problem.
    topics: list[dict[str, Any]]
    skipped: list[str]
    stopped: list[str] = []


SPEC = ToolSpec(
    name="record",
    title="Record topics",
    description=(
        "Record topics to an MCAP file on the server's host, until duration, size cap or stop. Example: "
        '{"topics": ["/odom", "/tf*"], "duration": 30}'
    ),
    hints=ToolHints(read_only=False, destructive=False, idempotent=False),
    # It subscribes and writes a file: nothing is sent to the robot, so there is no act for the guard.
    changes="files on the server's host",
    output=RecordAnswer,
    long_work=LongWork(unless="stop", cancelled="the recording was closed"),
)


async def run(
    ctx: ToolContext,
    *,
    topics: Annotated[
        list[str] | None,
        Field(max_length=MAX_TOPICS, description='e.g. ["/odom", "/tf*"]'),
        FROM_JSON_TEXT,
    ] = None,
    duration: Annotated[float, Field(gt=0, le=MAX_SECONDS, description="Seconds, e.g. 30")] = 10.0,
    max_megabytes: Annotated[float, Field(gt=0, le=100_000, description="MB, e.g. 500")] = DEFAULT_MEGABYTES,
    name: Annotated[str | None, Field(description='File name, e.g. "run1"')] = None,
    stop: Annotated[bool, Field(description="End running ones, e.g. true")] = False,
) -> ToolAnswer:
    """Choose the topics, make the file, record, and say what was written."""
    from rosbridge_mcp_server.robot.recording.recorder import NoTopicMatched, choose_topics, record_topics  # noqa: PLC0415 - on first use

    if stop:
        return _stopping(ctx, name)
    max_megabytes = _within_policy(ctx.config.policy.recording, duration, max_megabytes)
    if not topics:
        raise ToolFailure(
            'Name the topics to record, e.g. {"topics": ["/odom", "/scan"]}; globs like "/tf*" work.'
        )
    try:
        chosen = await choose_topics(ctx.graph, topics)
    except NoTopicMatched as exc:
        raise ToolFailure(f"{exc} Nothing was recorded.") from None
    directory = ctx.config.record_dir
    path, fd = _new_file(directory, name)

    stop_event = ctx.robot.recordings.add(path.name)
    try:
        result = await record_topics(
            ctx.client,
            ctx.graph,
            chosen,
            path=path,
            fd=fd,
            duration=duration,
            max_bytes=int(max_megabytes * 1e6),
            free_bytes=lambda: shutil.disk_usage(path.parent).free,
            stop=stop_event,
            on_progress=_reporter(ctx, duration),
        )
    except BaseException:
        if path.exists() and path.stat().st_size == 0:
            os.unlink(path)
        raise
    finally:
        ctx.robot.recordings.remove(path.name)
    answer = _answer(result, directory)
    return ToolAnswer(text=_text(answer, result), data=answer)


def _reporter(ctx: ToolContext, duration: float) -> Callable[[float, int, int], Awaitable[None]]:
    """The recording's progress as the client sees it: seconds of the duration, messages, bytes written."""

    async def progress(seconds: float, messages: int, written: int) -> None:
        await ctx.report_progress(
            round(min(seconds, duration), 1),
            duration,
            f"{seconds:.0f} of {duration:g} s, {counted(messages, 'message')}, {size_text(written)}",
        )

    return progress


def _stopping(ctx: ToolContext, name: str | None) -> ToolAnswer:
    """``stop``: the running recordings (all, or the one named) told to end."""
    stopped = ctx.robot.recordings.stop(name)
    text = (
        f"Stopping {', '.join(stopped)}; its record call answers with what was written."
        if stopped
        else "No recording is running" + (f" named {name!r}." if name else ".")
    )
    answer = RecordAnswer(file="", bytes=0, seconds=0, ended="", topics=[], skipped=[], stopped=stopped)
    return ToolAnswer(text=text, data=answer)


def _within_policy(limits: RecordingLimits, duration: float, max_megabytes: float) -> float:
    """The size cap to record with, after the policy's ``[recording]`` allowed the recording at all."""
    if not limits.enabled:
        raise ToolFailure(
            "The safety policy forbids recording ([recording] enabled = false); nothing was recorded."
        )
    if limits.max_seconds is not None and duration > limits.max_seconds:
        raise ToolFailure(
            f"duration {duration:g} s is over the policy's cap of {limits.max_seconds:g} s ([recording] "
            "max_seconds); ask for less."
        )
    if limits.max_megabytes is not None:
        return min(max_megabytes, limits.max_megabytes)
    return max_megabytes


def _new_file(directory: Path, name: str | None) -> tuple[Path, int]:
    """A new recording file in *directory* (its path and open descriptor), or a worded failure."""
    from rosbridge_mcp_server.robot.recording.files import PathRefused, create_recording  # noqa: PLC0415 - on first use

    try:
        return create_recording(directory, name)
    except PathRefused as exc:
        raise ToolFailure.carrying(exc) from None
    except OSError as exc:
        raise ToolFailure(
            f"Cannot write in the recording directory {str(directory)!r}: {exc.strerror or exc}. Set "
            "--record-dir to a writable folder."
        ) from None


def _answer(result: RecordingResult, directory: Path) -> RecordAnswer:
    topics = [
        {
            "topic": t.topic,
            "type": t.type,
            "messages": t.timing.count,
            "rate_hz": t.timing.rate_hz,
            "lost": t.lost,
            "gaps": [{"at": g.at, "seconds": g.seconds} for g in t.timing.gaps],
            "problem": t.problem,
        }
        for t in result.topics
    ]
    try:
        relative = str(result.path.resolve().relative_to(directory.resolve()))
    except ValueError:
        relative = result.path.name
    return RecordAnswer(
        file=relative,
        bytes=result.size,
        seconds=result.seconds,
        ended=result.ended,
        topics=topics,
        skipped=list(result.skipped),
    )


def _text(answer: RecordAnswer, result: RecordingResult) -> str:
    why = _ENDINGS.get(answer.ended, answer.ended)
    total = sum(t["messages"] for t in answer.topics)
    lines = [
        f"Recorded {answer.file} ({size_text(answer.bytes)}, {answer.seconds:g} s, "
        f"{counted(total, 'message')}) in {str(result.path.parent)!r}; it ended because {why}."
    ]
    if result.finish_error:
        lines.append(
            f"The file could not be finished ({result.finish_error}): its messages are readable, "
            "its index not."
        )
    for t in answer.topics[:40]:
        rate = f", {t['rate_hz']:g} Hz" if t["rate_hz"] is not None else ""
        lost = f", {t['lost']} LOST" if t["lost"] else ""
        gaps = (
            "; gaps " + ", ".join(f"{g['seconds']:g} s at {g['at']:g} s" for g in t["gaps"])
            if t["gaps"]
            else ""
        )
        problem = f"; {t['problem']}" if t["problem"] else ""
        count = f"{t['messages']} message" + ("" if t["messages"] == 1 else "s")
        lines.append(f"- {t['topic']} ({t['type']}): {count}{rate}{lost}{gaps}{problem}")
    if len(answer.topics) > 40:
        lines.append(f"... and {len(answer.topics) - 40} more topics (read_recording lists every one).")
    if answer.skipped:
        lines.append("Not recorded: " + "; ".join(answer.skipped[:10]))
    lines.append(
        f'read_recording {{"file": "{answer.file}"}} summarises it; ros2 bag info / Foxglove open it.'
    )
    return "\n".join(lines)
