"""The domain's view of the robot's graph: rosapi look-ups with the dialects' quirks handled.

:class:`RosGraph` is the one object the rest of the code holds; each of its look-ups is one part's:

* :mod:`.rosapi`: ``/rosapi/...`` calls on the client, and what the current connection has learnt (one object,
  replaced whole on a new connection);
* :mod:`.topics`: topics, their types, publishers and subscribers, and what this connection publishes;
* :mod:`.services`: services and their types (rosapi, or the type a ROS 2 bridge names refusing a probe);
* :mod:`.actions`: action servers and their types (the ``<ns>/goal`` topic on ROS 1, a probe on ROS 2);
* :mod:`.definitions`: type definitions, and the interfaces installed.

docs/rosbridge-behaviour.md has what was verified on which bridge release.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from rosbridge_mcp_server.robot.graph.actions import ActionEntry, Actions
from rosbridge_mcp_server.robot.graph.definitions import TypeDefinitions
from rosbridge_mcp_server.robot.graph.rosapi import ROSAPI_HINT, Rosapi, is_missing_service
from rosbridge_mcp_server.robot.graph.services import ServiceEntry, Services
from rosbridge_mcp_server.robot.graph.topics import TopicDetails, TopicEntry, Topics

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient

__all__ = [
    "ROSAPI_HINT",
    "ActionEntry",
    "RosGraph",
    "ServiceEntry",
    "TopicDetails",
    "TopicEntry",
    "is_missing_service",
]


class RosGraph:
    """rosapi look-ups on one client, with what each connection learnt kept until the next connection.

    The methods are the parts' own, bound here: the parts share one :class:`~.rosapi.Rosapi`, so what one
    learns about the connection (its ROS version, a new connection) the others see.
    """

    def __init__(self, client: RosbridgeClient, *, clock: Callable[[], float] = time.monotonic) -> None:
        rosapi = Rosapi(client, clock=clock)
        topics = Topics(rosapi)
        services = Services(rosapi)
        actions = Actions(rosapi, topics)
        definitions = TypeDefinitions(rosapi)

        self.ros_info = rosapi.ros_info
        self.dialect = rosapi.dialect
        self.capabilities = rosapi.capabilities
        self.saw_nodes = rosapi.saw_nodes
        self.recent_nodes = rosapi.recent_nodes
        self.rosapi = rosapi.call

        self.topics = topics.topics
        self.topic_type = topics.topic_type
        self.publishing_type = topics.publishing_type
        self.unknown_topic = topics.unknown_topic
        self.remember_publishing = topics.remember_publishing
        self.topic_details = topics.topic_details
        self.subscribers = topics.subscribers
        self.recent_subscribers = topics.recent_subscribers
        self.recent_topics = topics.recent_topics

        self.service_names = services.service_names
        self.service_names_seen = services.service_names_seen
        self.service_type = services.service_type
        self.forget_service = services.forget_service
        self.services = services.services
        self.learn_service_types = services.learn_service_types

        self.action_names = actions.action_names
        self.missing_action = actions.missing_action
        self.action_type = actions.action_type
        self.known_action_type = actions.known_action_type
        self.actions = actions.actions

        self.message_typedefs = definitions.message_typedefs
        self.service_request_typedefs = definitions.service_request_typedefs
        self.action_goal_typedefs = definitions.action_goal_typedefs
        self.installed_interfaces = definitions.installed_interfaces
        self.type_details = definitions.type_details
