"""The ROS graph of the simulated robot: nodes, topics, services and action servers.

This is what ROS 1's master or ROS 2's graph would know, and what rosapi reports. The world's own nodes
register here, and so does the rosbridge node on behalf of its clients (their advertisements and
subscriptions show as publishers/subscribers of ``/rosbridge_websocket``, as on a real robot).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

__all__ = [
    "ROSBRIDGE_NODE",
    "ActionEntry",
    "Graph",
    "HandlerReturnedNone",
    "LocalSubscriber",
    "NodeInfo",
    "ServiceEntry",
    "ServiceFailure",
    "ServiceHandler",
    "canonical_name",
    "is_hidden",
    "resolve_name",
    "rostopic_type",
]

#: The node that owns every client's advertisements and subscriptions.
ROSBRIDGE_NODE = "/rosbridge_websocket"

#: A service implementation: gets the request (converted, defaults filled in) and returns the response in
#: JSON form; missing fields take their defaults.
ServiceHandler = Callable[[dict[str, Any]], Awaitable[dict[str, Any]]]

#: A world node's subscription callback: (message after conversion, connection id or 0 for the world).
LocalSubscriber = Callable[[dict[str, Any], int], None]


class ServiceFailure(Exception):
    """The service implementation failed.

    ROS 1 (rospy) reports this to the caller; a ROS 2 service has no error channel, so the caller never
    gets an answer and rosbridge runs into its timeout.
    """


def resolve_name(name: str) -> str:
    """The graph name of a topic/service name as a node in the root namespace resolves it."""
    return name if name.startswith("/") else "/" + name


class HandlerReturnedNone(ServiceFailure):
    """rospy's handler gave no response: a client-hosted service unadvertised while a call was pending."""


def canonical_name(name: str, node: str = "/rosbridge_websocket") -> str:
    """rospy's ``resolve_name`` for a node in the root namespace (ROS 1).

    ``""`` is the node's namespace (``/``), ``~x`` is private (``/<node>/x``), a relative name goes under
    ``/``, and the result is canonical: repeated and trailing slashes removed (``//a/`` → ``/a``).
    """
    if not name:
        return "/"
    if name.startswith("~"):
        name = f"{node}/{name[1:]}"
    return "/" + "/".join(part for part in name.split("/") if part)


def rostopic_type(topic_types: dict[str, str], topic: str) -> str | None:
    """rostopic's ``get_topic_type`` (ROS 1): the exact name, else a topic the name is a field path of.

    rosbridge 0.11.17 infers types with it and rosapi answers ``topic_type`` with it, so ``/chatter/`` and
    ``/chatter/data`` both find ``/chatter``; ``chatter`` (relative) finds nothing.
    """
    found = topic_types.get(topic)
    if found is not None:
        return found
    for name, msg_type in topic_types.items():
        if topic.startswith(name + "/"):
            return msg_type
    return None


def is_hidden(name: str) -> bool:
    """ROS 2 hides names with a component starting with ``_`` (e.g. ``/fibonacci/_action/status``)."""
    return any(part.startswith("_") for part in name.split("/"))


class ActionEntry(Protocol):
    """An action server as the graph knows it (ROS 2): its name, its type, and a way to take it out."""

    name: str
    type: str

    def remove(self) -> None:
        """Take the server out of the graph; goals still running end ABORTED."""


@dataclass
class NodeInfo:
    """What one node publishes, subscribes and serves (reference-counted: rosbridge shares one node)."""

    name: str
    publishes: Counter[str] = field(default_factory=Counter)
    subscribes: Counter[str] = field(default_factory=Counter)
    services: set[str] = field(default_factory=set)


@dataclass
class ServiceEntry:
    """A service in the graph."""

    name: str
    type: str
    node: str
    handler: ServiceHandler
    #: The connection id of the client that advertised it, or 0 for the world's own services.
    owner: int = 0


@dataclass
class Graph:
    """Nodes, topic types, services and action servers, with the rosbridge node's reference counts."""

    nodes: dict[str, NodeInfo] = field(default_factory=dict)
    topic_types: dict[str, str] = field(default_factory=dict)
    services: dict[str, ServiceEntry] = field(default_factory=dict)
    #: ROS 2 action servers by action name (ROS 1 actions are plain topics).
    actions: dict[str, ActionEntry] = field(default_factory=dict)
    local_subscribers: dict[str, list[LocalSubscriber]] = field(default_factory=dict)
    #: Topics whose last message is kept for late subscribers (latched / transient local).
    latched: dict[str, Any] = field(default_factory=dict)
    #: Every topic type ever registered, in registration order: the ROS 1 master never forgets one
    #: (rostopic type look-ups, rosapi ``topic_type``/``topics_for_type`` still find dead topics).
    known_types: dict[str, str] = field(default_factory=dict)

    def node(self, name: str) -> NodeInfo:
        """The node called ``name``, created on first use."""
        info = self.nodes.get(name)
        if info is None:
            info = self.nodes[name] = NodeInfo(name)
        return info

    def add_publisher(self, node: str, topic: str, msg_type: str) -> None:
        """Count one publisher of ``topic`` on ``node``; the caller has checked the type."""
        self.topic_types.setdefault(topic, msg_type)
        self.known_types.setdefault(topic, msg_type)
        self.node(node).publishes[topic] += 1

    def remove_publisher(self, node: str, topic: str) -> None:
        """Drop one publisher count; the topic leaves the graph when nobody uses it."""
        self._decrement(self.node(node).publishes, topic)

    def add_subscriber(
        self, node: str, topic: str, msg_type: str, callback: LocalSubscriber | None = None
    ) -> None:
        """Count one subscriber of ``topic`` on ``node`` (a world node passes its callback)."""
        self.topic_types.setdefault(topic, msg_type)
        self.known_types.setdefault(topic, msg_type)
        self.node(node).subscribes[topic] += 1
        if callback is not None:
            self.local_subscribers.setdefault(topic, []).append(callback)

    def remove_subscriber(self, node: str, topic: str) -> None:
        """Drop one subscriber count."""
        self._decrement(self.node(node).subscribes, topic)

    def _decrement(self, counter: Counter[str], topic: str) -> None:
        counter[topic] -= 1
        if counter[topic] <= 0:
            del counter[topic]
        if not self.topic_in_use(topic):
            self.topic_types.pop(topic, None)
            self.latched.pop(topic, None)

    def topic_in_use(self, topic: str) -> bool:
        """Whether any node publishes or subscribes ``topic``."""
        return any(topic in n.publishes or topic in n.subscribes for n in self.nodes.values())

    def add_service(self, entry: ServiceEntry) -> None:
        """Offer a service (replacing one of the same name)."""
        old = self.services.get(entry.name)
        if old is not None:
            self.node(old.node).services.discard(old.name)
        self.services[entry.name] = entry
        self.node(entry.node).services.add(entry.name)

    def remove_service(self, name: str) -> ServiceEntry | None:
        """Withdraw a service; returns it, or ``None`` if it was not offered."""
        entry = self.services.pop(name, None)
        if entry is not None:
            self.node(entry.node).services.discard(name)
        return entry

    def node_names(self, *, sort: bool = True) -> list[str]:
        """Every node that exists (a node with nothing left still exists, like a running process).

        ``sort=False`` gives registration order, as the ROS 1 master lists them.
        """
        return sorted(self.nodes) if sort else list(self.nodes)

    def topics(self, *, include_hidden: bool = True, sort: bool = True) -> list[tuple[str, str]]:
        """(topic, type) of every topic with a publisher or subscriber, sorted by name or (``sort=False``)
        in registration order."""
        pairs = [(t, ty) for t, ty in self.topic_types.items() if include_hidden or not is_hidden(t)]
        return sorted(pairs) if sort else pairs

    def publishers_of(self, topic: str, *, sort: bool = True) -> list[str]:
        """Nodes publishing ``topic``."""
        names = [n.name for n in self.nodes.values() if topic in n.publishes]
        return sorted(names) if sort else names

    def subscribers_of(self, topic: str, *, sort: bool = True) -> list[str]:
        """Nodes subscribing ``topic``."""
        names = [n.name for n in self.nodes.values() if topic in n.subscribes]
        return sorted(names) if sort else names
