"""``list_nodes``: the nodes running in the ROS graph."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.nodes import node_names
from rosbridge_mcp_server.robot.wording import counted
from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolSpec
from rosbridge_mcp_server.tools.paging import FilterArg, OffsetArg, limit_arg, matcher, page_note, page_of

__all__ = ["DEFAULT_LIMIT", "SPEC", "NodesAnswer", "run"]

DEFAULT_LIMIT = 200


class NodesAnswer(BaseModel):
    """One page of the matching nodes."""

    count: int = Field(description="Nodes matching")
    offset: int
    more: int = Field(description="Matches after this page")
    nodes: list[str] = Field(description="Full node names, sorted")


SPEC = ToolSpec(
    name="list_nodes",
    title="List nodes",
    description=('List the running nodes. Read-only. Example: {"filter": "map"}; get_node_info shows one.'),
    hints=READS_ROBOT,
    output=NodesAnswer,
)


async def run(
    ctx: ToolContext,
    filter: FilterArg = None,
    limit: Annotated[int, limit_arg(DEFAULT_LIMIT)] = DEFAULT_LIMIT,
    offset: OffsetArg = 0,
) -> ToolAnswer:
    """Ask rosapi for the node names."""
    nodes = await node_names(ctx.graph)
    wanted = matcher(filter)
    matching = [node for node in nodes if wanted(node)]
    page = page_of(matching, offset=offset, limit=limit, line=str)
    if page.rows:
        text = f"{counted(len(matching), 'node')}:\n" + "\n".join(page.rows)
    elif nodes:
        text = f"No nodes match {filter!r}." if filter else "No nodes on this page."
    else:
        text = "No nodes are running (rosapi lists none)."
    note = page_note(page, "nodes", filter, len(nodes))
    data = NodesAnswer(count=len(matching), offset=offset, more=page.more, nodes=page.rows)
    return ToolAnswer(text=f"{text}\n{note}" if note else text, data=data)
