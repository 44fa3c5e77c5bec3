"""``list_parameters``: parameter names grouped by node, of every node or of one, filtered and paged."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.parameters import ParameterGroup, parameter_groups
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
    Page,
    limit_arg,
    matcher,
    page_note,
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
    """ROS 1: (namespace, name relative to it) of a full parameter name."""
    if node is not None and name.startswith(node.rstrip("/") + "/"):
        return node, name[len(node.rstrip("/")) + 1 :]
    # ROS 1 parameters belong to namespaces: group by the first one ("" for the top level).
    parts = name.split("/")
    return ("/" + parts[1], "/".join(parts[2:])) if len(parts) > 2 else ("", name.lstrip("/"))


def _by_namespace(names: list[str], node: str | None) -> list[ParameterGroup]:
    """ROS 1's full names grouped by namespace (or under ``node``), sorted."""
    grouped: dict[str, list[str]] = {}
    for owner, local in sorted(_split(full, node) for full in names):
        grouped.setdefault(owner, []).append(local)
    return list(grouped.items())


def _page(groups: list[ParameterGroup], offset: int, limit: int, budget: int) -> list[ParameterGroup]:
    """The groups' names from ``offset`` on: at most ``limit``, and no more than fit ``budget`` characters
    (always at least one)."""
    page: list[ParameterGroup] = []
    skip, room, used = offset, limit, 0
    for owner, names in groups:
        if skip >= len(names):
            skip -= len(names)
            continue
        taken: list[str] = []
        for local in names[skip : skip + room]:
            used += len(local) + 3
            if (taken or page) and used > budget:
                room = 0
                break
            taken.append(local)
        skip = 0
        if taken:
            page.append((owner, taken))
            room -= len(taken)
        if room <= 0:
            break
    return page


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
    ros2 = (await ctx.graph.ros_info()).version == 2
    total = sum(len(names) for _, names in groups)
    wanted = matcher(filter)
    if not ros2:
        full_names = groups[0][1] if groups else []
        groups = _by_namespace([full for full in full_names if wanted(full)] if filter else full_names, name)
    elif filter:
        groups = [
            (owner, kept)
            for owner, names in groups
            if (kept := [local for local in names if wanted(f"{owner}:{local}")])
        ]
    matched = sum(len(names) for _, names in groups)
    # Room for the node headings and the closing note.
    shown = _page(groups, offset, limit, TEXT_BUDGET - 800)
    page = Page([local for _, names in shown for local in names], matched, offset)
    where = f" of {name}" if name else ""
    if shown:
        lines = [f"{matched} parameters{where}, by node:"]
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
        separator=":" if ros2 else "/",
        count=matched,
        offset=offset,
        more=page.more,
        nodes=[NodeParameters.model_construct(node=owner, names=names) for owner, names in shown],
    )
    return ToolAnswer(text=text, data=data)
