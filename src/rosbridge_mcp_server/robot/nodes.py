"""Nodes of the ROS graph and what each one publishes, subscribes and serves, with types.

``/rosapi/nodes`` lists full node names on both lines. ``/rosapi/node_details`` answers an unknown node with
empty lists on ROS 1, and not at all on ROS 2 (its handler fails), so a node is looked up in the list first.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import NotOnRobotError, RequestTimeoutError, ServiceError
from rosbridge_mcp_server.robot.names import did_you_mean

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["NodeDetails", "UnknownNodeError", "node_details", "node_names"]

# rosapi 0.11 answers one look-up at a time anyway; ROS 2 nodes offer ~7 services each.
_LOOKUPS_AT_ONCE = 8


class UnknownNodeError(NotOnRobotError):
    """The node is not in the graph; carries the names that are, and says which of them were likely meant."""

    def __init__(self, node: str, known: list[str]) -> None:
        self.node = node
        self.known = known
        super().__init__(
            f"Node {node} is not running.{did_you_mean(node, known)} Call list_nodes to see the nodes."
        )


@dataclass(frozen=True)
class NodeDetails:
    """A node's topics and services as (name, type) pairs; the type is ``""`` where rosapi could not tell."""

    name: str
    publishes: tuple[tuple[str, str], ...]
    subscribes: tuple[tuple[str, str], ...]
    services: tuple[tuple[str, str], ...]


async def node_names(graph: RosGraph) -> list[str]:
    """Every node, sorted, once."""
    values = await graph.rosapi("nodes")
    return sorted(set(_strings(values.get("nodes"))))


async def node_details(graph: RosGraph, node: str) -> NodeDetails:
    """What ``node`` publishes, subscribes and serves; :class:`UnknownNodeError` when it is not running."""
    known = await node_names(graph)
    if node not in known:
        raise UnknownNodeError(node, known)
    details, topics = await asyncio.gather(graph.rosapi("node_details", {"node": node}), graph.topics())
    topic_types = {entry.name: entry.type for entry in topics}
    publishes = sorted(_strings(details.get("publishing")))
    subscribes = sorted(_strings(details.get("subscribing")))
    served = sorted(set(_strings(details.get("services"))))
    service_types = await _service_types(graph, served)
    return NodeDetails(
        name=node,
        publishes=tuple((name, topic_types.get(name, "")) for name in publishes),
        subscribes=tuple((name, topic_types.get(name, "")) for name in subscribes),
        services=tuple(zip(served, service_types, strict=True)),
    )


async def _service_types(graph: RosGraph, services: list[str]) -> list[str]:
    """Each service's type, looked up side by side (a few at a time); ``""`` where the look-up failed."""
    gate = asyncio.Semaphore(_LOOKUPS_AT_ONCE)

    async def one(service: str) -> str:
        async with gate:
            try:
                return await graph.service_type(service, cached=True)
            except (ServiceError, RequestTimeoutError):
                return ""

    return list(await asyncio.gather(*(one(service) for service in services)))


def _strings(value: Any) -> list[str]:
    if not isinstance(value, list):
        return []
    return [item for item in value if isinstance(item, str)]
