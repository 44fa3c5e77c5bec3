"""``list_parameters``: parameter names, of every node or of one."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.parameters import list_parameters
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolSpec,
    absolute_name,
)

__all__ = ["SPEC", "ParametersAnswer", "run"]


class ParametersAnswer(BaseModel):
    """Parameter names."""

    node: str | None
    parameters: list[str] = Field(description="Full names: /node:name on ROS 2, /ns/name on ROS 1")


SPEC = ToolSpec(
    name="list_parameters",
    title="List parameters",
    description=(
        "List ROS parameter names, of all nodes or of one. Read-only. Names are /node:name on ROS 2 "
        '(/turtlesim:background_r) and /ns/name on ROS 1. Example: {"node": "/turtlesim"}.'
    ),
    hints=READS_ROBOT,
    output=ParametersAnswer,
)


async def run(
    ctx: ToolContext,
    node: Annotated[str | None, Field(description="Only this node's parameters, e.g. /turtlesim")] = None,
) -> ToolAnswer:
    """Ask the graph (ROS 1 parameter server, ROS 2 nodes) for the names."""
    name = absolute_name(node, "node") if node else None
    names = await list_parameters(ctx.graph, ctx.client, name)
    where = f" of {name}" if name else ""
    text = f"{len(names)} parameters{where}:\n" + "\n".join(names) if names else f"No parameters{where}."
    return ToolAnswer(text=text, data=ParametersAnswer(node=name, parameters=names))
