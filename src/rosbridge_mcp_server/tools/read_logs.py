"""``read_logs``: the robot's log since the server connected, filtered, with repeats folded, paged."""

from __future__ import annotations

import asyncio
import time
from typing import TYPE_CHECKING, Annotated, Final, Literal

from pydantic import BaseModel, BeforeValidator, Field

from rosbridge_mcp_server.robot.logs import RING_LINES, RING_SECONDS, Fold, fold
from rosbridge_mcp_server.robot.wording import counted
from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolFailure, ToolSpec
from rosbridge_mcp_server.tools.paging import OffsetArg, limit_arg, page_of

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.log_keeper import LogKeeper

__all__ = ["DEFAULT_LIMIT", "SPEC", "LogsAnswer", "run"]

DEFAULT_LIMIT = 50
#: How long a call waits for the log subscription a just-started server is opening.
READY_WAIT = 3.0


class LogGroup(BaseModel):
    """Lines of one node and level whose texts differ at most in their numbers."""

    level: str
    node: str
    text: str = Field(description="The latest line's text")
    count: int
    first_ago: float = Field(description="Seconds since the first line")
    last_ago: float = Field(description="Seconds since the last line")
    where: str = Field(description="file:line (function) of the latest line, when the robot said")


class LogsAnswer(BaseModel):
    """One page of the matching log groups, oldest last line first."""

    source: str | None = Field(description="The topic read (/rosout, /rosout_agg), or null without one")
    since: str | None = Field(description="When the log was first read (local time)")
    lines: int = Field(description="Matching lines")
    count: int = Field(description="Matching groups")
    more: int = Field(description="Groups after this page")
    groups: list[LogGroup]
    dropped: int = Field(description="Lines the ring's bounds let go")


#: Other names of the levels, as loggers and people write them (Python's WARNING, syslog's err and crit, ...).
LEVEL_ALIASES: Final[dict[str, str]] = {
    "warning": "warn",
    "err": "error",
    "critical": "fatal",
    "crit": "fatal",
    "information": "info",
    "dbg": "debug",
}


def _level_name(value: object) -> object:
    """A level in any case, or one of its other names, as the level it is (``WARNING`` → ``warn``)."""
    if not isinstance(value, str):
        return value
    name = value.strip().lower()
    return LEVEL_ALIASES.get(name, name)


SPEC = ToolSpec(
    name="read_logs",
    title="Robot log",
    description=(
        f"The robot's /rosout since the server connected ({RING_LINES:,} lines, {RING_SECONDS / 60:.0f} "
        'min), repeats folded. Read-only. Example: {"node": "*controller*", "since": 60}'
    ),
    hints=READS_ROBOT,
    needs=frozenset({"robot_log"}),
    output=LogsAnswer,
)


async def run(
    ctx: ToolContext,
    *,
    level: Annotated[
        Literal["debug", "info", "warn", "error", "fatal"],
        BeforeValidator(_level_name),
        Field(description="Lowest level, e.g. info"),
    ] = "warn",
    node: Annotated[str | None, Field(description="Node name or glob, e.g. *costmap*")] = None,
    text: Annotated[str | None, Field(description="Text in the line, e.g. progress")] = None,
    since: Annotated[float | None, Field(gt=0, le=86_400, description="Last N seconds, e.g. 60")] = None,
    limit: Annotated[int, limit_arg(DEFAULT_LIMIT)] = DEFAULT_LIMIT,
    offset: OffsetArg = 0,
) -> ToolAnswer:
    """Read the session's log ring."""
    keeper = await _ready_keeper(ctx)
    if keeper.absent:
        return ToolAnswer(
            text="This robot has no /rosout topic, so there is no log to read (diagnose checks the rest).",
            data=LogsAnswer(source=None, since=None, lines=0, count=0, more=0, groups=[], dropped=0),
        )
    now = time.time()
    ring = keeper.ring
    lines = ring.select(level=level, node=node, text=text, since=since, now=now)
    folds = fold(lines)
    page = page_of(folds, offset=offset, limit=limit, line=lambda f: f.describe(now))
    started = keeper.listening_since or now
    since_text = time.strftime("%H:%M:%S", time.localtime(started))
    wanted = _wanted(level, node, text, since)
    bounds = f"the ring keeps the last {RING_LINES:,} lines and {RING_SECONDS / 60:.0f} min"
    if page.rows:
        head = (
            f"{counted(len(lines), 'line')}{wanted} in {counted(len(folds), 'group')}, read from "
            f"{keeper.source} since {since_text}"
            + (f" ({ring.dropped:,} older lines let go: {bounds})" if ring.dropped else "")
            + ":"
        )
        body = "\n".join(f.describe(now) for f in page.rows)
        text_out = f"{head}\n{body}"
        if page.more:
            text_out += f"\n{page.more} more groups: call again with offset {offset + len(page.rows)}."
    elif folds:
        text_out = f"No groups on this page ({counted(len(folds), 'group')} match; offset {offset})."
    else:
        text_out = (
            f"Nothing logged{wanted} since {since_text} ({_ago(now - started)} ago; {bounds}). "
            + ('level: "info" shows the quieter lines.' if level in ("warn", "error", "fatal") else "")
        ).strip()
    data = LogsAnswer(
        source=keeper.source,
        since=since_text,
        lines=len(lines),
        count=len(folds),
        more=page.more,
        groups=[_group(f, now) for f in page.rows],
        dropped=ring.dropped,
    )
    return ToolAnswer(text=text_out, data=data)


async def _ready_keeper(ctx: ToolContext) -> LogKeeper:
    """The robot's log keeper once its subscription is open (it opens in the background after connecting)."""
    keeper = ctx.robot.keep_logs()
    if not keeper.ready.is_set():
        await ctx.client.wait_connected(ctx.config.connect_timeout)
        try:
            await asyncio.wait_for(keeper.ready.wait(), READY_WAIT)
        except TimeoutError:
            raise ToolFailure(
                "The robot's log is not being read yet: the server is still connecting to it. Call again "
                "in a few seconds."
            ) from None
    return keeper


def _wanted(level: str, node: str | None, text: str | None, since: float | None) -> str:
    parts = [f"at {level} or above" if level != "debug" else "at any level"]
    if node:
        parts.append(f"from {node}")
    if text:
        parts.append(f"containing {text!r}")
    if since:
        parts.append(f"in the last {since:g} s")
    return " " + " ".join(parts)


def _ago(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.0f} min"


def _group(entry: Fold, now: float) -> LogGroup:
    return LogGroup(
        level=entry.level,
        node=entry.node,
        text=entry.text,
        count=entry.count,
        first_ago=round(now - entry.first, 1),
        last_ago=round(now - entry.last, 1),
        where=entry.where,
    )
