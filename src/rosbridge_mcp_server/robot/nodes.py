"""Nodes of the ROS graph and what each one publishes, subscribes and serves, with types.

``/rosapi/nodes`` lists full node names on both lines. ``/rosapi/node_details`` of an unknown node: ROS 1
(0.11.17) answers empty lists; rosbridge-server-rs never answers (each call is a task of its own there, so
the silence holds nothing up); rosbridge_suite's ROS 2 rosapi fails in its handler (2.1.0's rosapi dies), so
where the client says that is unsafe (``node_details_of_unknown_safe``) a node is looked up in a node list
first, and on the others only to word an unknown node's error.

A node list or topic list this connection saw within the last :data:`RECENT_SECONDS` is reused: rosapi 2.1.0
answers one call at a time (5-90 ms each on the Jazzy lab), so a listing saved is a call's time saved, and a
model asking about several nodes one after another (or right after ``list_nodes``) pays for one listing. A
node the recent list does not hold is looked up in a fresh list, so a node never listed never reaches
``node_details``.
"""

from __future__ import annotations

import asyncio
import contextlib
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import Advice, NotOnRobotError, RequestTimeoutError, ServiceError
from rosbridge_mcp_server.robot.known_types import infrastructure_types
from rosbridge_mcp_server.robot.names import did_you_mean
from rosbridge_mcp_server.robot.text import NAME_CHARS, shown

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.graph import RosGraph, TopicEntry

__all__ = [
    "RECENT_SECONDS",
    "UNANSWERED_SECONDS",
    "NodeDetails",
    "UnknownNodeError",
    "node_details",
    "node_names",
]

# rosapi 0.11 answers one look-up at a time anyway; ROS 2 nodes offer ~7 services each.
_LOOKUPS_AT_ONCE = 8
#: rosbridge-server-rs answers node_details in milliseconds (3-15 ms on the lab), and never for an unknown
#: node: after this long without an answer the node list is asked, so an unknown node is an error in well
#: under a second, while a known node's details are still awaited.
UNANSWERED_SECONDS = 0.5
#: How old a node list or topic list this connection saw may be to be reused for one node's details.
RECENT_SECONDS = 1.0


class UnknownNodeError(NotOnRobotError):
    """The node is not in the graph; carries the names that are, and says which of them were likely meant."""

    def __init__(self, node: str, known: list[str]) -> None:
        self.node = node
        self.known = known
        super().__init__(f"Node {node} is not running.{did_you_mean(node, known)}")
        self.advise(Advice.RUNNING_NODES)


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
    names = sorted(set(_strings(values.get("nodes"))))
    graph.saw_nodes(names)
    return names


async def node_details(graph: RosGraph, node: str) -> NodeDetails:
    """What ``node`` publishes, subscribes and serves; :class:`UnknownNodeError` when it is not running.

    One round trip on the happy path where the bridge's answer for an unknown node is harmless: ROS 1 answers
    it with empty lists, rosbridge-server-rs with silence; the node list is asked only then, to word the
    error. rosbridge_suite's ROS 2 rosapi must never be asked about an unknown node (it kills rosapi 2.1.0),
    so there a node list comes first: one seen within :data:`RECENT_SECONDS` if it holds the node, else a
    fresh one. The topics' types come from a topic list seen as recently, or a fresh one.
    """
    info = await graph.ros_info()
    listed_first = not (await graph.capabilities()).node_details_of_unknown_safe
    if listed_first:
        recent = graph.recent_nodes(RECENT_SECONDS)
        if recent is None or node not in recent:
            known = await node_names(graph)
            if node not in known:
                raise UnknownNodeError(node, known)
        details, (topics, reused) = await asyncio.gather(
            graph.rosapi("node_details", {"node": node}), _topics(graph)
        )
    else:
        details, (topics, reused) = await _details_or_unknown(graph, node)
    publishes = sorted(_strings(details.get("publishing")))
    subscribes = sorted(_strings(details.get("subscribing")))
    served = sorted(set(_strings(details.get("services"))))
    if not listed_first and not (publishes or subscribes or served):
        # ROS 1's answer for an unknown node (a running ROS 2 node always has /rosout at least).
        known = await node_names(graph)
        if node not in known:
            raise UnknownNodeError(node, known)
    topic_types = {entry.name: entry.type for entry in topics}
    if reused and any(_listed(name) and name not in topic_types for name in (*publishes, *subscribes)):
        # A topic newer than the recent list: its type is in a fresh one.
        topic_types = {entry.name: entry.type for entry in await graph.topics()}
    service_types = await _service_types(graph, served, info.version)
    return NodeDetails(
        name=node,
        publishes=tuple((name, topic_types.get(name, "")) for name in publishes),
        subscribes=tuple((name, topic_types.get(name, "")) for name in subscribes),
        services=tuple(zip(served, service_types, strict=True)),
    )


async def _details_or_unknown(
    graph: RosGraph, node: str
) -> tuple[dict[str, Any], tuple[list[TopicEntry], bool]]:
    """``node_details`` and the topics side by side; when the details have not come after
    :data:`UNANSWERED_SECONDS` (rosbridge-server-rs says nothing for an unknown node), the node list decides
    whether to wait on or to raise :class:`UnknownNodeError`."""
    asking = asyncio.ensure_future(graph.rosapi("node_details", {"node": node}))
    listing = asyncio.ensure_future(_topics(graph))
    try:
        done, _ = await asyncio.wait({asking}, timeout=UNANSWERED_SECONDS)
        if not done:
            known = await node_names(graph)
            if node not in known:
                raise UnknownNodeError(node, known)
        return await asking, await listing
    finally:
        for task in (asking, listing):
            if not task.done():
                task.cancel()
        # Retrieve what a failed or abandoned task holds, so nothing is logged as never retrieved.
        await asyncio.gather(asking, listing, return_exceptions=True)


async def _topics(graph: RosGraph) -> tuple[list[TopicEntry], bool]:
    """The topic list this connection saw within :data:`RECENT_SECONDS` (and True), else a fresh one."""
    recent = graph.recent_topics(RECENT_SECONDS)
    return (recent, True) if recent is not None else (await graph.topics(), False)


async def _service_types(graph: RosGraph, services: list[str], version: int) -> list[str]:
    """Each service's type: told by its name (the services every node offers, an action's hidden services
    whose action type this connection knows) or looked up side by side, a few at a time; ``""`` where the
    look-up failed."""
    fixed = infrastructure_types(services, version)
    gate = asyncio.Semaphore(_LOOKUPS_AT_ONCE)
    # An action's hidden services are typed from the action's type, which is learnt once per connection;
    # rosapi's service_type does not know them (it answers "", which is never kept, so it was asked anew on
    # every call).
    untold = {
        action
        for service in services
        if (action := _hidden_action(service)) and graph.known_action_type(action) is None
    }

    async def learn(action: str) -> None:
        # On failure rosapi is asked about the service, as before.
        async with gate:
            with contextlib.suppress(ServiceError, RequestTimeoutError):
                await graph.action_type(action)

    await asyncio.gather(*(learn(action) for action in sorted(untold)))

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


def _hidden_action(service: str) -> str:
    """The action whose ``send_goal`` or ``get_result`` service this is, or ``""``."""
    action, marker, leaf = service.rpartition("/_action/")
    return action if marker and leaf in _ACTION_SERVICES else ""


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


def _listed(topic: str) -> bool:
    """Whether rosapi's topic list names *topic*: it leaves hidden topics out (a part starting with ``_``,
    such as an action's ``/_action/feedback``), which newer rosapi's ``node_details`` names."""
    return not any(part.startswith("_") for part in topic.split("/"))


def _strings(value: Any) -> list[str]:
    # Names as the graph gives them: robot text, shown escaped and capped (robot/text.py).
    if not isinstance(value, list):
        return []
    return [shown(item, NAME_CHARS) for item in value if isinstance(item, str)]
