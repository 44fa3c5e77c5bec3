"""``get_node_info``: what one node publishes, subscribes and serves."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.nodes import node_details
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolSpec,
    absolute_name,
)

__all__ = ["SPEC", "NodeInfoAnswer", "run"]


class NamedType(BaseModel):
    """Name and type ("" when unknown)."""

    name: str
    type: str


class NodeInfoAnswer(BaseModel):
    """One node's connections."""

    node: str
    publications: list[NamedType]
    subscriptions: list[NamedType]
    services: list[NamedType]


SPEC = ToolSpec(
    name="get_node_info",
    title="Node details",
    description=(
        "Show what one ROS node publishes, subscribes to and serves, with types. Read-only. "
        'Example: {"node": "/turtlesim"}.'
    ),
    hints=READS_ROBOT,
    output=NodeInfoAnswer,
)


async def run(
    ctx: ToolContext,
    node: Annotated[str, Field(description="Full node name, e.g. /turtlesim")],
) -> ToolAnswer:
    """Ask rosapi for the node's topics and services, then their types."""
    name = absolute_name(node, "node")
    details = await node_details(ctx.graph, name)
    answer = NodeInfoAnswer(
        node=name,
        publications=[NamedType(name=n, type=t) for n, t in details.publishes],
        subscriptions=[NamedType(name=n, type=t) for n, t in details.subscribes],
        services=[NamedType(name=n, type=t) for n, t in details.services],
    )
    lines = [name]
    for title, items in (
        ("publishes", answer.publications),
        ("subscribes", answer.subscriptions),
        ("services", answer.services),
    ):
        lines.append(f"{title} ({len(items)}):")
        lines.extend(f"  {item.name} [{item.type or 'type unknown'}]" for item in items)
    return ToolAnswer(text="\n".join(lines), data=answer)
