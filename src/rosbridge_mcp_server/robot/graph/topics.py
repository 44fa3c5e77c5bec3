"""Topics: their types, publishers and subscribers, the topics this connection publishes, and the "not in the
graph" sentence with the likely meant names."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import dataclass

from rosbridge_mcp_server.robot.graph.rosapi import ConnectionKnowledge, Rosapi, strings
from rosbridge_mcp_server.robot.names import did_you_mean

__all__ = ["TopicDetails", "TopicEntry", "Topics"]


@dataclass(frozen=True)
class TopicEntry:
    """A topic and its type (``""`` when the graph does not know it)."""

    name: str
    type: str


@dataclass(frozen=True)
class TopicDetails:
    """A topic's type and the nodes that publish and subscribe it."""

    name: str
    type: str
    publishers: tuple[str, ...]
    subscribers: tuple[str, ...]


class Topics:
    """Topic look-ups through rosapi."""

    def __init__(self, rosapi: Rosapi) -> None:
        self._rosapi = rosapi

    @property
    def _known(self) -> ConnectionKnowledge:
        return self._rosapi.known

    async def topics(self) -> list[TopicEntry]:
        """Every topic the graph knows, sorted by name, with its type."""
        values = await self._rosapi.call("topics")
        names = strings(values.get("topics"))
        types = strings(values.get("types"))
        entries = {name: (types[i] if i < len(types) else "") for i, name in enumerate(names)}
        listed = [TopicEntry(name, entries[name]) for name in sorted(entries)]
        self._known.topics_seen = (self._rosapi.clock(), tuple((e.name, e.type) for e in listed))
        return listed

    def recent_topics(self, max_age: float) -> list[TopicEntry] | None:
        """The topic list this connection saw within the last *max_age* seconds, or None."""
        seen = self._known.topics_seen
        if seen is None or self._rosapi.clock() - seen[0] > max_age:
            return None
        return [TopicEntry(name, type_) for name, type_ in seen[1]]

    async def topic_type(self, topic: str) -> str:
        """The type of ``topic``, or ``""`` when it is not in the graph."""
        values = await self._rosapi.call("topic_type", {"topic": topic})
        found = values.get("type")
        return found if isinstance(found, str) else ""

    async def publishing_type(self, topic: str) -> str:
        """The type of a topic about to be published on: ``topic_type``, skipped for a topic we publish.

        Once this connection has advertised a topic, rosbridge keeps the publisher (and so the topic's type)
        for as long as the connection lives, so the answer cannot have changed.
        """
        await self._rosapi.ros_info()  # forgets what an earlier connection published
        known = self._known.publishing.get(topic)
        return known if known is not None else await self.topic_type(topic)

    async def unknown_topic(
        self, topic: str, why: str = "", among: Callable[[str], bool] | None = None
    ) -> tuple[str, list[str]]:
        """``Topic /x is not in the ROS graph<why>.`` and the likely meant names, with the topics considered
        (those whose type *among* accepts; every topic without it)."""
        known = [entry.name for entry in await self.topics() if among is None or among(entry.type)]
        return f"Topic {topic} is not in the ROS graph{why}.{did_you_mean(topic, known)}", known

    def remember_publishing(self, topic: str, msg_type: str) -> None:
        """Note that this connection now publishes ``topic`` as ``msg_type``."""
        self._known.publishing[topic] = msg_type

    async def subscribers(self, topic: str) -> tuple[str, ...]:
        """The nodes subscribed to ``topic`` now (none for a topic not in the graph)."""
        values = await self._rosapi.call("subscribers", {"topic": topic})
        found = tuple(strings(values.get("subscribers")))
        if found:
            self._known.subscribers_seen[topic] = (self._rosapi.clock(), found)
        else:
            self._known.subscribers_seen.pop(topic, None)
        return found

    def recent_subscribers(self, topic: str, max_age: float) -> tuple[str, ...] | None:
        """The subscribers this connection saw on ``topic`` within *max_age* seconds, if it saw any."""
        seen = self._known.subscribers_seen.get(topic)
        if seen is None or self._rosapi.clock() - seen[0] > max_age:
            return None
        return seen[1]

    async def topic_details(self, topic: str) -> TopicDetails:
        """Type, publishers and subscribers of ``topic`` (all empty when it is not in the graph)."""
        topic_type, publishers, subscribers = await asyncio.gather(
            self.topic_type(topic),
            self._rosapi.call("publishers", {"topic": topic}),
            self._rosapi.call("subscribers", {"topic": topic}),
        )
        return TopicDetails(
            name=topic,
            type=topic_type,
            publishers=tuple(strings(publishers.get("publishers"))),
            subscribers=tuple(strings(subscribers.get("subscribers"))),
        )
