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
from rosbridge_mcp_server.tools.paging import FRAME_RESERVE, TEXT_BUDGET, FilterArg, matcher

__all__ = ["SPEC", "NodeInfoAnswer", "run"]


class NamedType(BaseModel):
    """Name and type ("" when unknown)."""

    name: str
    type: str


class NodeInfoAnswer(BaseModel):
    """One node's connections (those matching the filter, as many as the text budget holds)."""

    node: str
    publications: list[NamedType]
    subscriptions: list[NamedType]
    services: list[NamedType]
    more: int = 0


SPEC = ToolSpec(
    name="get_node_info",
    title="Node details",
    description=(
        "A node's publications, subscriptions and services, with types. Read-only. "
        'Example: {"node": "/turtlesim"}.'
    ),
    hints=READS_ROBOT,
    output=NodeInfoAnswer,
)


async def run(
    ctx: ToolContext,
    node: Annotated[str, Field(description="Full node name, e.g. /turtlesim")],
    filter: FilterArg = None,
) -> ToolAnswer:
    """Ask rosapi for the node's topics and services, then their types; keep what matches and fits."""
    name = absolute_name(node, "node")
    details = await node_details(ctx.graph, name)
    wanted = matcher(filter)
    used, cut = len(name), 0
    sections: list[list[NamedType]] = []
    for pairs in (details.publishes, details.subscribes, details.services):
        kept: list[NamedType] = []
        for row_name, row_type in pairs:
            if not (wanted(row_name) or wanted(row_type)):
                continue
            used += len(row_name) + len(row_type) + 6
            if used > TEXT_BUDGET - FRAME_RESERVE:
                cut += 1
                continue
            kept.append(NamedType(name=row_name, type=row_type))
        sections.append(kept)
    answer = NodeInfoAnswer(
        node=name, publications=sections[0], subscriptions=sections[1], services=sections[2], more=cut
    )
    lines = [name]
    for title, items in zip(("publishes", "subscribes", "services"), sections, strict=True):
        lines.append(f"{title} ({len(items)}):")
        lines.extend(f"  {item.name} [{item.type or 'type unknown'}]" for item in items)
    if filter:
        lines.append(f"(only what matches {filter!r})")
    if cut:
        lines.append(f"({cut} more not shown: narrow with filter, e.g. a topic name part or a type)")
    return ToolAnswer(text="\n".join(lines), data=answer)
