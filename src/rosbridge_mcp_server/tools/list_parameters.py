"""``list_parameters``: parameter names grouped by node, of every node or of one, filtered and paged."""

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
from rosbridge_mcp_server.tools.paging import (
    TEXT_BUDGET,
    FilterArg,
    OffsetArg,
    limit_arg,
    matcher,
    page_note,
    page_of,
)

__all__ = ["DEFAULT_LIMIT", "SPEC", "NodeParameters", "ParametersAnswer", "run"]

DEFAULT_LIMIT = 250


class NodeParameters(BaseModel):
    """One node's parameters on this page (ROS 1: one namespace's)."""

    node: str
    names: list[str] = Field(
        description="Relative to the node; full name is node:name (ROS 2), node/name (ROS 1)"
    )


class ParametersAnswer(BaseModel):
    """One page of the matching parameter names, by node, sorted."""

    node: str | None
    separator: str = Field(description='Full name = node + separator + name: ":" on ROS 2, "/" on ROS 1')
    count: int = Field(description="Parameters matching")
    offset: int
    more: int = Field(description="Matches after this page")
    nodes: list[NodeParameters]


SPEC = ToolSpec(
    name="list_parameters",
    title="List parameters",
    description=(
        "List parameter names by node. Read-only. Full names: /node:name (ROS 2), /ns/name (ROS 1). "
        'Example: {"node": "/turtlesim"} or {"filter": "*vel*"}.'
    ),
    hints=READS_ROBOT,
    output=ParametersAnswer,
)


def _split(name: str, node: str | None) -> tuple[str, str]:
    """(node, name relative to it) of a full parameter name."""
    if ":" in name:
        owner, _, local = name.partition(":")
        return owner, local
    if node is not None and name.startswith(node.rstrip("/") + "/"):
        return node, name[len(node.rstrip("/")) + 1 :]
    # ROS 1: parameters belong to namespaces; group by the first one ("" for the top level).
    parts = name.split("/")
    return ("/" + parts[1], "/".join(parts[2:])) if len(parts) > 2 else ("", name.lstrip("/"))


async def run(
    ctx: ToolContext,
    node: Annotated[str | None, Field(description="Only this node's parameters, e.g. /turtlesim")] = None,
    filter: FilterArg = None,
    limit: Annotated[int, limit_arg(DEFAULT_LIMIT)] = DEFAULT_LIMIT,
    offset: OffsetArg = 0,
) -> ToolAnswer:
    """Ask the graph (ROS 1 parameter server, ROS 2 nodes) for the names."""
    name = absolute_name(node, "node") if node else None
    names = await list_parameters(ctx.graph, ctx.client, name)
    wanted = matcher(filter)
    selected = [full for full in names if wanted(full)] if filter else names
    # ROS 2 names hold their node before the ":"; the rest is split by _split.
    rows = sorted(
        [
            (owner, local) if sep else _split(full, name)
            for full in selected
            for owner, sep, local in (full.partition(":"),)
        ]
    )
    # Room for the node headings and the closing note.
    budget = TEXT_BUDGET - 800
    page = page_of(rows, offset=offset, limit=limit, line=lambda row: row[1] + ", ", budget=budget)
    grouped: dict[str, list[str]] = {}
    for owner, local in page.rows:
        grouped.setdefault(owner, []).append(local)
    where = f" of {name}" if name else ""
    if page.rows:
        lines = [f"{len(rows)} parameters{where}, by node:"]
        lines += [
            f"{owner or '(top level)'} ({len(locals_)}): {', '.join(locals_)}"
            for owner, locals_ in grouped.items()
        ]
    elif names and filter:
        lines = [f"No parameters{where} match {filter!r}."]
    else:
        lines = [f"No parameters{where}."]
    note = page_note(page, "parameters", filter, len(names))
    text = "\n".join([*lines, note] if note else lines)
    data = ParametersAnswer(
        node=name,
        separator=":" if (await ctx.graph.ros_info()).version == 2 else "/",
        count=len(rows),
        offset=offset,
        more=page.more,
        nodes=[NodeParameters(node=owner, names=locals_) for owner, locals_ in grouped.items()],
    )
    return ToolAnswer(text=text, data=data)
