"""``list_nodes``: the nodes running in the ROS graph."""

from __future__ import annotations

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.nodes import node_names
from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolSpec

__all__ = ["SPEC", "NodesAnswer", "run"]


class NodesAnswer(BaseModel):
    """The running nodes."""

    nodes: list[str] = Field(description="Full node names, sorted")


SPEC = ToolSpec(
    name="list_nodes",
    title="List nodes",
    description=(
        "List the running ROS nodes. Read-only. Example: call it with {}. get_node_info shows one node's "
        "topics and services."
    ),
    hints=READS_ROBOT,
    output=NodesAnswer,
)


async def run(ctx: ToolContext) -> ToolAnswer:
    """Ask rosapi for the node names."""
    nodes = await node_names(ctx.graph)
    text = (
        f"{len(nodes)} nodes:\n" + "\n".join(nodes) if nodes else "No nodes are running (rosapi lists none)."
    )
    return ToolAnswer(text=text, data=NodesAnswer(nodes=nodes))
