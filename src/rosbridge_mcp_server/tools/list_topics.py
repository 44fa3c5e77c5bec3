"""``list_topics``: the topics in the ROS graph with their types, filtered and paged."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.wording import counted
from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolSpec
from rosbridge_mcp_server.tools.paging import (
    FilterArg,
    OffsetArg,
    limit_arg,
    matcher,
    page_note,
    page_of,
    typed_line,
)

__all__ = ["DEFAULT_LIMIT", "SPEC", "TopicRow", "TopicsAnswer", "run"]

DEFAULT_LIMIT = 100


class TopicRow(BaseModel):
    """One topic."""

    name: str
    type: str = Field(description='"" if unknown')


class TopicsAnswer(BaseModel):
    """One page of the matching topics, sorted by name."""

    count: int = Field(description="Topics matching (all of them without a filter)")
    offset: int
    more: int = Field(description="Matches after this page")
    topics: list[TopicRow]


SPEC = ToolSpec(
    name="list_topics",
    title="List topics",
    description=(
        "List the robot's topics with their message types. Read-only; start here. Example: "
        '{"filter": "scan"}.'
    ),
    hints=READS_ROBOT,
    output=TopicsAnswer,
)


def _line(row: TopicRow) -> str:
    return typed_line(row.name, row.type)


async def run(
    ctx: ToolContext,
    filter: FilterArg = None,
    limit: Annotated[int, limit_arg(DEFAULT_LIMIT)] = DEFAULT_LIMIT,
    offset: OffsetArg = 0,
) -> ToolAnswer:
    """Ask rosapi for the topics and their types; keep the page asked for."""
    topics = await ctx.graph.topics()
    wanted = matcher(filter)
    rows = [
        TopicRow.model_construct(name=t.name, type=t.type) for t in topics if wanted(t.name) or wanted(t.type)
    ]
    page = page_of(rows, offset=offset, limit=limit, line=_line)
    note = page_note(page, "topics", filter, len(topics))
    if page.rows:
        text = f"{counted(len(rows), 'topic')}:\n" + "\n".join(map(_line, page.rows))
    elif not topics:
        text = "The robot has no topics right now (nothing publishes or subscribes)."
    else:
        text = f"No topics on this page{' match ' + repr(filter) if filter and not rows else ''}."
    text = f"{text}\n{note}" if note else text
    data = TopicsAnswer(count=len(rows), offset=offset, more=page.more, topics=page.rows)
    return ToolAnswer(text=text, data=data)
