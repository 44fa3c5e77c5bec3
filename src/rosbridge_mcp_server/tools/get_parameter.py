"""``get_parameter``: one parameter's value."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.parameters import get_parameter
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolSpec,
    compact_json,
)

__all__ = ["SPEC", "ParameterAnswer", "run"]


class ParameterAnswer(BaseModel):
    """A parameter and its value."""

    name: str
    value: Any = Field(description="The value as JSON")


SPEC = ToolSpec(
    name="get_parameter",
    title="Read a parameter",
    description=(
        'Read one parameter. Read-only. Example: {"name": "/turtlesim:background_r"} (ROS 2) or '
        '"/turtlesim/background_r" (ROS 1).'
    ),
    hints=READS_ROBOT,
    output=ParameterAnswer,
)


async def run(
    ctx: ToolContext,
    name: Annotated[
        str, Field(description="ROS 2 /node:name or ROS 1 /ns/name, e.g. /turtlesim:background_r")
    ],
) -> ToolAnswer:
    """Check the parameter exists, then read it."""
    parsed, value = await get_parameter(ctx.graph, ctx.client, name)
    return ToolAnswer(
        text=f"{parsed.full} = {compact_json(value)}", data=ParameterAnswer(name=parsed.full, value=value)
    )
