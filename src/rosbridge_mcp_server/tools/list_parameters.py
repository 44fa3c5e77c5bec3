"""``list_parameters``: parameter names grouped by node, of every node or of one, filtered and paged."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.parameters import parameter_groups
from rosbridge_mcp_server.robot.wording import counted
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
    page_of_groups,
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
        'Example: {"node": "/turtlesim"}.'
    ),
    hints=READS_ROBOT,
    output=ParametersAnswer,
)


def _listed(name: str) -> str:
    return name + ", "


async def run(
    ctx: ToolContext,
    node: Annotated[str | None, Field(description="Only this node's parameters, e.g. /turtlesim")] = None,
    filter: FilterArg = None,
    limit: Annotated[int, limit_arg(DEFAULT_LIMIT)] = DEFAULT_LIMIT,
    offset: OffsetArg = 0,
) -> ToolAnswer:
    """Ask the graph (ROS 1 parameter server, ROS 2 nodes) for the names."""
    name = absolute_name(node, "node") if node else None
    groups = await parameter_groups(ctx.graph, ctx.client, name)
    separator = ":" if (await ctx.graph.ros_info()).version == 2 else "/"
    total = sum(len(names) for _, names in groups)
    if filter:
        wanted = matcher(filter)
        groups = [
            (owner, kept)
            for owner, names in groups
            if (kept := [local for local in names if wanted(f"{owner}{separator}{local}")])
        ]
    # Room for the node headings and the closing note.
    shown, page = page_of_groups(groups, offset=offset, limit=limit, line=_listed, budget=TEXT_BUDGET - 800)
    where = f" of {name}" if name else ""
    if shown:
        lines = [f"{counted(page.matched, 'parameter')}{where}, by node:"]
        lines += [f"{owner or '(top level)'} ({len(names)}): {', '.join(names)}" for owner, names in shown]
    elif total and filter:
        lines = [f"No parameters{where} match {filter!r}."]
    else:
        lines = [f"No parameters{where}."]
    note = page_note(page, "parameters", filter, total)
    text = "\n".join([*lines, note] if note else lines)
    # Built from our own rows: nothing to validate.
    data = ParametersAnswer.model_construct(
        node=name,
        separator=separator,
        count=page.matched,
        offset=offset,
        more=page.more,
        nodes=[NodeParameters.model_construct(node=owner, names=names) for owner, names in shown],
    )
    return ToolAnswer(text=text, data=data)
