"""``list_services``: every service in the ROS graph with its type."""

from __future__ import annotations

from pydantic import BaseModel, Field

from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolSpec

__all__ = ["SPEC", "ServiceRow", "ServicesAnswer", "run"]


class ServiceRow(BaseModel):
    """One service."""

    name: str = Field(description="Service name, e.g. /spawn")
    type: str = Field(description='Service type, e.g. turtlesim/srv/Spawn ("" if rosapi could not tell)')


class ServicesAnswer(BaseModel):
    """Every service, sorted by name."""

    count: int
    services: list[ServiceRow]


SPEC = ToolSpec(
    name="list_services",
    title="List services",
    description=(
        "List every ROS service the robot offers, with its service type (e.g. /reset of type "
        "std_srvs/srv/Empty). Read-only; use it before publish_service. Takes no arguments: call it with "
        "{}."
    ),
    hints=READS_ROBOT,
    output=ServicesAnswer,
)


async def run(ctx: ToolContext) -> ToolAnswer:
    """Ask rosapi for the services, then for each service's type side by side."""
    services = await ctx.graph.services()
    rows = [ServiceRow(name=service.name, type=service.type) for service in services]
    if rows:
        lines = [f"{row.name} ({row.type or 'type unknown'})" for row in rows]
        text = f"{len(rows)} services:\n" + "\n".join(lines)
    else:
        text = "The robot offers no services right now."
    return ToolAnswer(text=text, data=ServicesAnswer(count=len(rows), services=rows))
