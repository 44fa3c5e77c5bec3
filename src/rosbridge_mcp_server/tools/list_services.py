"""``list_services``: every service in the ROS graph with its type."""

from __future__ import annotations

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.known_types import per_node_types, rosapi_types
from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolSpec

__all__ = ["SPEC", "ServiceRow", "ServicesAnswer", "listing_text", "run"]


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
    """Ask rosapi for the services (their types are known once per connection)."""
    services = await ctx.graph.services()
    rows = [ServiceRow(name=service.name, type=service.type) for service in services]
    if rows:
        text = listing_text(rows, (await ctx.graph.ros_info()).version)
    else:
        text = "The robot offers no services right now."
    return ToolAnswer(text=text, data=ServicesAnswer(count=len(rows), services=rows))


def listing_text(rows: list[ServiceRow], version: int) -> str:
    """The robot's own services a line each; the services every node offers, and rosapi's, grouped.

    A ROS 2 node offers seven services of its own (its parameters and its type descriptions), so on a real
    graph most rows are those: grouped, the text a model reads stays short, and every name and type can still
    be read from it. The structured content lists every row.
    """
    names = [row.name for row in rows]
    per_node, rosapi = per_node_types(names, version), rosapi_types(names, version)
    own = [row for row in rows if row.name not in per_node and row.name not in rosapi]
    lines = [f"{row.name} ({row.type or 'type unknown'})" for row in own]
    offered: dict[str, list[str]] = {}
    for name, kind in sorted(per_node.items()):
        node, _, leaf = name.rpartition("/")
        offered.setdefault(node or "/", []).append(f"<node>/{leaf} ({kind})")
    nodes_by_set: dict[tuple[str, ...], list[str]] = {}
    for node, services in offered.items():
        nodes_by_set.setdefault(tuple(services), []).append(node)
    for common, nodes in nodes_by_set.items():
        lines.append(f"On {_count(len(nodes), 'node')} ({', '.join(nodes)}): {', '.join(common)}")
    if rosapi:
        package = next(iter(rosapi.values())).rpartition("/")[0]
        api = ", ".join(
            f"{name.rpartition('/')[2]} ({kind.rpartition('/')[2]})" for name, kind in sorted(rosapi.items())
        )
        lines.append(f"rosapi's own, /rosapi/<name> ({package}/<Type>): {api}")
    grouped = len(rows) - len(own)
    head = _count(len(rows), "service")
    if grouped:
        head += f": the robot's {len(own)}, then {grouped} that every node and rosapi offer, grouped"
    return f"{head}:\n" + "\n".join(lines)


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"
