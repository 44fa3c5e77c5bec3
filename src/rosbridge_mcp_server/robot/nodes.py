"""Nodes of the ROS graph and what each one publishes, subscribes and serves, with types.

``/rosapi/nodes`` lists full node names on both lines. ``/rosapi/node_details`` answers an unknown node with
empty lists on ROS 1, and not at all on ROS 2 (its handler fails), so on ROS 2 a node is looked up in the list
first.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import NotOnRobotError, RequestTimeoutError, ServiceError
from rosbridge_mcp_server.robot.known_types import infrastructure_types
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
    """What ``node`` publishes, subscribes and serves; :class:`UnknownNodeError` when it is not running.

    ROS 1 answers an unknown node with empty lists, so the node list is asked only then, to word the error.
    ROS 2's rosapi never answers for an unknown node (and an in-order bridge would wait on it), so there the
    node list comes first.
    """
    info = await graph.ros_info()
    if info.version == 2:
        known = await node_names(graph)
        if node not in known:
            raise UnknownNodeError(node, known)
    details, topics = await asyncio.gather(graph.rosapi("node_details", {"node": node}), graph.topics())
    publishes = sorted(_strings(details.get("publishing")))
    subscribes = sorted(_strings(details.get("subscribing")))
    served = sorted(set(_strings(details.get("services"))))
    if info.version == 1 and not (publishes or subscribes or served):
        known = await node_names(graph)
        if node not in known:
            raise UnknownNodeError(node, known)
    topic_types = {entry.name: entry.type for entry in topics}
    service_types = await _service_types(graph, served, info.version)
    return NodeDetails(
        name=node,
        publishes=tuple((name, topic_types.get(name, "")) for name in publishes),
        subscribes=tuple((name, topic_types.get(name, "")) for name in subscribes),
        services=tuple(zip(served, service_types, strict=True)),
    )


async def _service_types(graph: RosGraph, services: list[str], version: int) -> list[str]:
    """Each service's type: told by its name (the services every node offers, an action's hidden services
    whose action type this connection knows) or looked up side by side, a few at a time; ``""`` where the
    look-up failed."""
    fixed = infrastructure_types(services, version)
    gate = asyncio.Semaphore(_LOOKUPS_AT_ONCE)

    async def one(service: str) -> str:
        told = fixed.get(service) or _action_service_type(graph, service)
        if told:
            return told
        async with gate:
            try:
                return await graph.service_type(service, cached=True)
            except (ServiceError, RequestTimeoutError):
                return ""

    return list(await asyncio.gather(*(one(service) for service in services)))


_ACTION_SERVICES = {"send_goal": "_SendGoal", "get_result": "_GetResult"}


def _action_service_type(graph: RosGraph, service: str) -> str:
    """The type of a ROS 2 action's hidden service (``<action>/_action/<leaf>``), when it is told."""
    action, marker, leaf = service.rpartition("/_action/")
    if not marker:
        return ""
    if leaf == "cancel_goal":
        return "action_msgs/srv/CancelGoal"
    suffix = _ACTION_SERVICES.get(leaf)
    action_type = graph.known_action_type(action) if suffix else None
    return f"{action_type}{suffix}" if action_type and "/action/" in action_type else ""


def _strings(value: Any) -> list[str]:
    if not isinstance(value, list):
        return []
    return [item for item in value if isinstance(item, str)]
