"""``list_actions``: every action server, once, with its type where it can be known."""

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

__all__ = ["DEFAULT_LIMIT", "SPEC", "ActionRow", "ActionsAnswer", "run"]

DEFAULT_LIMIT = 100


class ActionRow(BaseModel):
    """One action server."""

    name: str = Field(description="Action name, e.g. /turtle1/rotate_absolute")
    type: str | None = Field(
        description="Action type, e.g. turtlesim/action/RotateAbsolute (null if this bridge cannot tell)"
    )


class ActionsAnswer(BaseModel):
    """One page of the matching action servers, sorted by name."""

    count: int = Field(description="Action servers matching")
    offset: int = 0
    more: int = Field(default=0, description="Matches after this page")
    actions: list[ActionRow]


SPEC = ToolSpec(
    name="list_actions",
    title="List actions",
    description=(
        "List the action servers with their types. Read-only; use before publish_action. "
        'Example: {"filter": "navigate"}.'
    ),
    hints=READS_ROBOT,
    output=ActionsAnswer,
)


def _line(row: ActionRow) -> str:
    return typed_line(row.name, row.type)


async def run(
    ctx: ToolContext,
    filter: FilterArg = None,
    limit: Annotated[int, limit_arg(DEFAULT_LIMIT)] = DEFAULT_LIMIT,
    offset: OffsetArg = 0,
) -> ToolAnswer:
    """Ask rosapi for the action servers, then for each one's type."""
    actions = await ctx.graph.actions()
    wanted = matcher(filter)
    rows = [
        ActionRow(name=action.name, type=action.type)
        for action in actions
        if wanted(action.name) or wanted(action.type or "")
    ]
    page = page_of(rows, offset=offset, limit=limit, line=_line)
    if page.rows:
        text = f"{counted(len(rows), 'action server')}:\n" + "\n".join(map(_line, page.rows))
    elif actions:
        text = f"No action servers match {filter!r}." if filter else "No action servers on this page."
    else:
        text = "The robot has no action servers right now."
    note = page_note(page, "action servers", filter, len(actions))
    data = ActionsAnswer(count=len(rows), offset=offset, more=page.more, actions=page.rows)
    return ToolAnswer(text=f"{text}\n{note}" if note else text, data=data)
