"""``list_services``: the services in the ROS graph with their types, grouped, filtered and paged."""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.graph import ServiceEntry
from rosbridge_mcp_server.robot.known_types import per_node_types, rosapi_types
from rosbridge_mcp_server.robot.wording import counted
from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolSpec
from rosbridge_mcp_server.tools.paging import (
    FRAME_RESERVE,
    TEXT_BUDGET,
    FilterArg,
    OffsetArg,
    limit_arg,
    matcher,
    page_note,
    page_of,
    typed_line,
)

__all__ = ["DEFAULT_LIMIT", "SPEC", "ServiceGroup", "ServiceRow", "ServicesAnswer", "listing_text", "run"]

DEFAULT_LIMIT = 100
#: How much of a group's node list the text spells out.
MAX_GROUP_NODES_CHARS = 1_500


class ServiceRow(BaseModel):
    """One service."""

    name: str
    type: str = Field(description='"" if rosapi could not tell')


class ServiceGroup(BaseModel):
    """Services several nodes offer alike: each node has every one (name = node + "/" + leaf)."""

    nodes: list[str]
    services: list[ServiceRow] = Field(description="Leaf names, e.g. get_parameters")


class ServicesAnswer(BaseModel):
    """One page of the matching services, sorted by name; without a filter the services every node offers
    (parameters, lifecycle, rosapi's) are in groups."""

    count: int = Field(description="Services matching (all of them without a filter)")
    offset: int
    more: int = Field(description="Rows after this page")
    services: list[ServiceRow]
    groups: list[ServiceGroup] = Field(default_factory=list)


SPEC = ToolSpec(
    name="list_services",
    title="List services",
    description=(
        "List the services with their types (those every node has, grouped). Read-only; use before "
        'publish_service. Example: {"filter": "map"}.'
    ),
    hints=READS_ROBOT,
    needs=frozenset({"service_types"}),
    output=ServicesAnswer,
)


def _line(row: ServiceRow) -> str:
    return _pair_line((row.name, row.type))


def _pair_line(row: tuple[str, str]) -> str:
    return typed_line(*row)


async def run(
    ctx: ToolContext,
    filter: FilterArg = None,
    limit: Annotated[int, limit_arg(DEFAULT_LIMIT)] = DEFAULT_LIMIT,
    offset: OffsetArg = 0,
) -> ToolAnswer:
    """Ask rosapi for the services (their types are known once per connection)."""
    services = await ctx.graph.services()
    if not services:
        return ToolAnswer(
            text="The robot offers no services right now.",
            data=ServicesAnswer(count=0, offset=offset, more=0, services=[]),
        )
    total = len(services)
    if filter:
        # Rows are (name, type) pairs until the page is known: a real graph has hundreds.
        wanted = matcher(filter)
        matching = [(s.name, s.type) for s in services if wanted(s.name) or wanted(s.type)]
        page = page_of(matching, offset=offset, limit=limit, line=_pair_line)
        head = (
            f"{counted(len(matching), 'service')}:"
            if page.rows
            else f"No services on this page match {filter!r}."
        )
        body = [head, *map(_pair_line, page.rows)]
        groups: list[ServiceGroup] = []
        count = len(matching)
        shown = [ServiceRow.model_construct(name=name, type=kind) for name, kind in page.rows]
    else:
        version = (await ctx.graph.ros_info()).version
        grouping = _grouped(services, version)
        groups = grouping.groups
        # What the head, the groups and the closing note take; the robot's own services get the rest.
        budget = TEXT_BUDGET - FRAME_RESERVE - sum(len(line) + 1 for line in grouping.group_lines)
        page = page_of(grouping.own, offset=offset, limit=limit, line=_pair_line, budget=max(budget, 1_000))
        body = [grouping.head, *map(_pair_line, page.rows), *grouping.group_lines]
        count = total
        shown = grouping.own_rows[offset : offset + len(page.rows)]
    note = page_note(page, "services", filter, total)
    text = "\n".join([*body, note] if note else body)
    # Built from our own rows and groups: nothing to validate.
    data = ServicesAnswer.model_construct(
        count=count, offset=offset, more=page.more, services=shown, groups=groups
    )
    return ToolAnswer(text=text, data=data)


@dataclass(frozen=True)
class _Grouping:
    """The unfiltered listing's parts: the robot's own rows (as pairs and as rows), the groups, their text
    lines and the head."""

    own: list[tuple[str, str]]
    own_rows: list[ServiceRow]
    groups: list[ServiceGroup]
    group_lines: list[str]
    head: str


#: How many listings' groupings are remembered: a fleet has one listing per robot.
_GROUPINGS_KEPT = 4
#: The groupings remembered, least recently used first: (the listing itself, its ROS version, its grouping).
#: Each listing is held here, so while it is remembered no other tuple can be that object.
_groupings: list[tuple[tuple[ServiceEntry, ...], int, _Grouping]] = []
_groupings_lock = threading.Lock()  # servers on other threads' loops (a test's, an HTTP host's) share it


def _grouped(services: tuple[ServiceEntry, ...], version: int) -> _Grouping:
    """The grouping of the unfiltered listing of ``services``.

    Remembered for the last few listings (a fleet has one per robot), by the listing's identity: while the
    services and their types stay the same the graph hands out the very same tuple
    (``robot/graph/services.py``), so grouping ~400 names (~1 ms) is done once, and finding it again compares
    a few references (hashing the tuple, as a cache keyed on its value would, costs ~60 µs for 392 services).
    Any other tuple, even an equal one, is grouped afresh.
    """
    with _groupings_lock:
        for index, (listing, listed_version, grouping) in enumerate(_groupings):
            if listing is services and listed_version == version:
                if index != len(_groupings) - 1:
                    _groupings.append(_groupings.pop(index))
                return grouping
    grouping = _group(services, version)
    with _groupings_lock:
        _groupings.append((services, version, grouping))
        if len(_groupings) > _GROUPINGS_KEPT:
            del _groupings[0]
    return grouping


def _group(services: tuple[ServiceEntry, ...], version: int) -> _Grouping:
    own, groups = _split([(service.name, service.type) for service in services], version)
    return _Grouping(
        own=own,
        own_rows=[ServiceRow.model_construct(name=name, type=kind) for name, kind in own],
        groups=groups,
        group_lines=[_group_line(group) for group in groups],
        head=_head(len(services), len(own)),
    )


def _split(rows: list[tuple[str, str]], version: int) -> tuple[list[tuple[str, str]], list[ServiceGroup]]:
    """The robot's own services, and the services every node (and rosapi) offers, grouped by their set.

    A ROS 2 node offers seven services of its own (parameters, type description) and a lifecycle node five
    more, so on a real graph most rows are those: grouped, the text stays short, and every name and type can
    still be read from it.
    """
    names = [name for name, _ in rows]
    per_node, rosapi = per_node_types(names, version), rosapi_types(names, version)
    own = [row for row in rows if row[0] not in per_node and row[0] not in rosapi]
    offered: dict[str, list[tuple[str, str]]] = {}
    for name, kind in sorted(per_node.items()):
        node, _, leaf = name.rpartition("/")
        offered.setdefault(node or "/", []).append((leaf, kind))
    nodes_by_set: dict[tuple[tuple[str, str], ...], list[str]] = {}
    for node, leaves in offered.items():
        nodes_by_set.setdefault(tuple(leaves), []).append(node)
    groups = [
        ServiceGroup.model_construct(
            nodes=nodes, services=[ServiceRow.model_construct(name=leaf, type=kind) for leaf, kind in leaves]
        )
        for leaves, nodes in nodes_by_set.items()
    ]
    if rosapi:
        groups.append(
            ServiceGroup.model_construct(
                nodes=["/rosapi"],
                services=[
                    ServiceRow.model_construct(name=name.rpartition("/")[2], type=kind)
                    for name, kind in sorted(rosapi.items())
                ],
            )
        )
    return own, groups


def _head(total: int, own: int) -> str:
    head = _count(total, "service")
    if total - own:
        head += f": the robot's {own}, then {total - own} that every node and rosapi offer, grouped"
    return head + ":"


def _group_line(group: ServiceGroup) -> str:
    if group.nodes == ["/rosapi"]:
        package = group.services[0].type.rpartition("/")[0]
        api = ", ".join(f"{row.name} ({row.type.rpartition('/')[2]})" for row in group.services)
        return f"rosapi's own, /rosapi/<name> ({package}/<Type>): {api}"
    leaves = ", ".join(f"<node>/{row.name} ({row.type})" for row in group.services)
    nodes = ", ".join(group.nodes)
    if len(nodes) > MAX_GROUP_NODES_CHARS:
        # A fleet's node list: the first nodes, then how to see the rest (the structured content has them).
        nodes = nodes[:MAX_GROUP_NODES_CHARS].rpartition(", ")[0]
        shown = nodes.count(", ") + 1
        nodes += f", ... {len(group.nodes) - shown} more (filter by node name lists their services)"
    return f"On {_count(len(group.nodes), 'node')} ({nodes}): {leaves}"


def listing_text(rows: list[ServiceRow], version: int) -> str:
    """The unfiltered listing's text of ``rows`` (all on one page)."""
    own, groups = _split([(row.name, row.type) for row in rows], version)
    return "\n".join([_head(len(rows), len(own)), *map(_pair_line, own), *map(_group_line, groups)])


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"
