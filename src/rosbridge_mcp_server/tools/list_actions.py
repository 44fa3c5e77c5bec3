"""``list_actions``: every action server, once, with its type where it can be known."""

from __future__ import annotations

from pydantic import BaseModel, Field

from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolSpec

__all__ = ["SPEC", "ActionRow", "ActionsAnswer", "run"]


class ActionRow(BaseModel):
    """One action server."""

    name: str = Field(description="Action name, e.g. /turtle1/rotate_absolute")
    type: str | None = Field(
        description="Action type, e.g. turtlesim/action/RotateAbsolute (null if this bridge cannot tell)"
    )


class ActionsAnswer(BaseModel):
    """Every action server, sorted by name."""

    count: int
    actions: list[ActionRow]


SPEC = ToolSpec(
    name="list_actions",
    title="List actions",
    description=(
        "List every ROS action server (long-running goals such as navigation or rotation), each once, with "
        "its action type where the bridge can tell (e.g. /fibonacci of type "
        "example_interfaces/action/Fibonacci). Read-only; use it before publish_action. Takes no "
        "arguments: call it with {}."
    ),
    hints=READS_ROBOT,
    output=ActionsAnswer,
)


async def run(ctx: ToolContext) -> ToolAnswer:
    """Ask rosapi for the action servers, then for each one's type."""
    actions = await ctx.graph.actions()
    rows = [ActionRow(name=action.name, type=action.type) for action in actions]
    if rows:
        lines = [f"{row.name} ({row.type or 'type unknown'})" for row in rows]
        text = f"{len(rows)} action servers:\n" + "\n".join(lines)
    else:
        text = "The robot has no action servers right now."
    return ToolAnswer(text=text, data=ActionsAnswer(count=len(rows), actions=rows))
