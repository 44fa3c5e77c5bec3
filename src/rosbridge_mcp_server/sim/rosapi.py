"""The rosapi node of each dialect (``rosapi/scripts/rosapi_node`` and ``proxy.py`` of rosbridge_suite).

Answers come from the simulated graph. The quirks of the real services are kept on purpose, each marked
with the version that has it. ROS 2 comes as the newest rosapi or as the one of rosbridge_suite 2.1.0
(:class:`RosapiOptions`), which the Jazzy and Kilted labs run.
"""

from __future__ import annotations

import asyncio
import itertools
import json
import logging
import time
from collections.abc import Callable, Coroutine
from dataclasses import dataclass
from typing import Any, Literal

from rosbridge_mcp_server.sim.bridge import Bridge
from rosbridge_mcp_server.sim.graph import ServiceEntry, ServiceFailure, is_hidden, rostopic_type
from rosbridge_mcp_server.sim.interfaces import InterfaceError
from rosbridge_mcp_server.sim.params import JSON_REQUIRED, Ros1Params, Ros2Params

__all__ = [
    "PARAM_NODE_WAIT",
    "ROSAPI_NODE",
    "ROSAPI_PARAMS",
    "ROSAPI_RELEASES",
    "Rosapi",
    "RosapiOptions",
    "ros1_action_servers",
    "ros2_action_servers",
]

log = logging.getLogger("rosbridge_mcp_server.sim")

ROSAPI_NODE = "/rosapi"
#: ROS 2 rosapi's helper node (it asks other nodes for their parameters).
ROSAPI_PARAMS = "/rosapi_params"
ROSAPI_RELEASES = ("newest", "2.1.0")
#: rosapi 2.1.0 waits this long for a node's parameter service before it gives up.
PARAM_NODE_WAIT = 5.0
#: What rosapi 2.1.0 does not offer yet.
_NEWER_THAN_2_1 = (
    "interfaces",
    "action_type",
    "action_goal_details",
    "action_result_details",
    "action_feedback_details",
)


@dataclass(frozen=True)
class RosapiOptions:
    """Which rosapi, and how fast it answers."""

    #: ``"newest"``, or ``"2.1.0"``: TypeDef field names with a leading underscore (rclpy slot names), no
    #: ``interfaces``/``action_type``/``action_*_details``, no hidden names in ``node_details``, parameters
    #: set only when declared, one call at a time, and the calls that kill it (``get_param_names``,
    #: ``has_param`` of an undeclared parameter, ``service_*_details`` of a type it cannot load: no answer,
    #: and every rosapi service is gone) or hang it (a parameter of rosapi itself).
    release: Literal["newest", "2.1.0"] = "newest"
    #: Seconds each rosapi call takes, one call at a time, the values taken in turn (``(0.005,)``: 5 ms each;
    #: ``(0.005, 0.005, 0.005, 0.09)``: every fourth call 90 ms, as the slow mode of a real ROS 2 rosapi).
    #: Empty or all 0: at once, side by side.
    latency: tuple[float, ...] = ()


_Handler = Callable[[dict[str, Any]], Coroutine[Any, Any, dict[str, Any]]]


def ros1_action_servers(topics: list[str]) -> list[str]:
    """ROS 1 rosapi 0.11.17 ``filter_action_servers``, quirk included.

    The "all five leaves seen" check runs after every topic, not only when a namespace changes, so a
    namespace is reported again for each later topic until another namespace with ≥ 2 components starts
    (e.g. ``/fibonacci`` is listed again for ``/rosout`` and ``/rosout_agg``).
    """
    leaves = ["cancel", "feedback", "goal", "result", "status"]
    servers: list[str] = []
    current = ""
    seen = [0, 0, 0, 0, 0]
    for topic in sorted(topics):
        parts = topic.split("/")
        if len(parts) >= 3:
            leaf = parts.pop()
            namespace = "/".join(parts)
            if current != namespace:
                current = namespace
                seen = [0, 0, 0, 0, 0]
            if leaf in leaves:
                seen[leaves.index(leaf)] = 1
        if all(seen):
            servers.append(current)
    return servers


def ros2_action_servers(topics: list[str]) -> list[str]:
    """ROS 2 rosapi ``filter_action_servers``: ``<ns>/_action/{feedback,status}`` both present."""
    servers: list[str] = []
    current = ""
    seen = [0, 0]
    for topic in sorted(topics):
        parts = topic.split("/")
        if len(parts) < 4:
            continue
        leaf = parts.pop()
        if parts.pop() != "_action":
            continue
        namespace = "/".join(parts)
        if current != namespace:
            current = namespace
            seen = [0, 0]
        if leaf in ("feedback", "status"):
            seen[("feedback", "status").index(leaf)] = 1
        if all(seen):
            servers.append(current)
            seen = [0, 0]
    return servers


class Rosapi:
    """Registers every rosapi service of the dialect on the graph."""

    def __init__(self, bridge: Bridge, options: RosapiOptions | None = None) -> None:
        self.bridge = bridge
        self.options = options or RosapiOptions()
        self.legacy = self.options.release == "2.1.0"
        self.ros2 = bridge.config.dialect == "ros2"
        #: A real rosapi answers one call at a time; the newest without latency is modelled answering at once.
        self._latencies = itertools.cycle(self.options.latency) if any(self.options.latency) else None
        self._turn = asyncio.Lock() if self.legacy or self._latencies is not None else None
        #: How long rosapi 2.1.0 waits for a node that has no parameter service (tests shorten it).
        self.param_node_wait = PARAM_NODE_WAIT
        self.dead = False
        #: rosapi 2.1.0 deadlocked (a question about its own parameters): nothing answers any more.
        self.hung = False
        store = bridge.world.params
        self.params2 = Ros2Params(store, lambda node: node in bridge.graph.nodes)
        self.params1 = Ros1Params(store)
        handlers: dict[str, tuple[str, _Handler]] = {
            "topics": ("Topics", self.topics),
            "topics_for_type": ("TopicsForType", self.topics_for_type),
            "topics_and_raw_types": ("TopicsAndRawTypes", self.topics_and_raw_types),
            "topic_type": ("TopicType", self.topic_type),
            "publishers": ("Publishers", self.publishers),
            "subscribers": ("Subscribers", self.subscribers),
            "services": ("Services", self.services),
            "services_for_type": ("ServicesForType", self.services_for_type),
            "service_type": ("ServiceType", self.service_type),
            "service_providers": ("ServiceProviders", self.service_providers),
            "service_node": ("ServiceNode", self.service_node),
            "nodes": ("Nodes", self.nodes),
            "node_details": ("NodeDetails", self.node_details),
            "action_servers": ("GetActionServers", self.action_servers),
            "message_details": ("MessageDetails", self.message_details),
            "service_request_details": ("ServiceRequestDetails", self.service_request_details),
            "service_response_details": ("ServiceResponseDetails", self.service_response_details),
            "get_param": ("GetParam", self.get_param),
            "set_param": ("SetParam", self.set_param),
            "has_param": ("HasParam", self.has_param),
            "delete_param": ("DeleteParam", self.delete_param),
            "get_param_names": ("GetParamNames", self.get_param_names),
            "get_time": ("GetTime", self.get_time),
        }
        if self.ros2:
            handlers |= {
                "get_ros_version": ("GetROSVersion", self.get_ros_version),
                "interfaces": ("Interfaces", self.interfaces),
                "action_goal_details": ("ActionGoalDetails", self.action_goal_details),
                "action_result_details": ("ActionResultDetails", self.action_result_details),
                "action_feedback_details": ("ActionFeedbackDetails", self.action_feedback_details),
                "action_type": ("ActionType", self.action_type),
            }
        else:
            handlers |= {
                "search_param": ("SearchParam", self.search_param),
                "service_host": ("ServiceHost", self.service_host),
            }
        package = "rosapi_msgs" if self.ros2 else "rosapi"
        registry = bridge.registry
        for name, (type_name, handler) in handlers.items():
            if self.legacy and name in _NEWER_THAN_2_1:
                continue
            try:
                service_type = registry.resolve(f"{package}/{type_name}", "srv")
                _, response_type = registry.service_parts(service_type)
                fields = set(registry.field_names(response_type))
            except InterfaceError as exc:
                log.warning("rosapi %s left out: %s", name, exc)
                continue

            bridge.graph.add_service(
                ServiceEntry(f"/rosapi/{name}", service_type, ROSAPI_NODE, self._fitted(handler, fields))
            )

    def _fitted(self, handler: _Handler, fields: set[str]) -> _Handler:
        """Keep only the response fields this rosapi version has (e.g. ``successful`` is Jazzy's), and
        answer one call at a time when rosapi is modelled that way."""

        async def call(request: dict[str, Any]) -> dict[str, Any]:
            if self._turn is None:
                response = await handler(request)
            else:
                async with self._turn:
                    if self.dead or self.hung:
                        # Queued behind the call that killed or deadlocked it: no answer, ever.
                        await asyncio.Event().wait()
                    if self._latencies is not None:
                        await asyncio.sleep(next(self._latencies))
                    response = await handler(request)
            return {k: v for k, v in response.items() if k in fields}

        return call

    async def _die(self, reason: str) -> dict[str, Any]:
        """rosapi 2.1.0's process ends: no answer to this call; its services and nodes leave the graph."""
        log.error("rosapi dies: %s (every /rosapi/* call fails from now on)", reason)
        self.dead = True
        graph = self.bridge.graph
        for name, entry in list(graph.services.items()):
            if entry.node in (ROSAPI_NODE, ROSAPI_PARAMS):
                graph.remove_service(name)
        for node in (ROSAPI_NODE, ROSAPI_PARAMS):
            info = graph.nodes.pop(node, None)
            if info is not None:
                for topic in list(info.publishes):
                    if not graph.topic_in_use(topic):
                        graph.topic_types.pop(topic, None)
        self.bridge.world.notify()
        await asyncio.Event().wait()
        raise AssertionError("unreachable")

    # --- graph ----------------------------------------------------------------------------------------------

    def _topics(self) -> list[tuple[str, str]]:
        # ROS 2 leaves hidden topics out; ROS 1 has no such notion. The ROS 1 master lists in registration
        # order (0.11.17 does not sort), ROS 2 rosapi sorted.
        return self.bridge.graph.topics(include_hidden=not self.ros2, sort=self.ros2)

    def _services(self) -> list[ServiceEntry]:
        entries = list(self.bridge.graph.services.values())
        if self.ros2:
            return sorted((e for e in entries if not is_hidden(e.name)), key=lambda e: e.name)
        return entries

    async def topics(self, request: dict[str, Any]) -> dict[str, Any]:
        pairs = self._topics()
        return {"topics": [t for t, _ in pairs], "types": [ty for _, ty in pairs]}

    async def topics_for_type(self, request: dict[str, Any]) -> dict[str, Any]:
        wanted = request.get("type")
        if self.ros2:
            return {"topics": [t for t, ty in self._topics() if ty == wanted]}
        # 0.11.17 asks the master's getTopicTypes, which remembers dead topics (in registration order).
        return {"topics": [t for t, ty in self.bridge.graph.known_types.items() if ty == wanted]}

    async def topics_and_raw_types(self, request: dict[str, Any]) -> dict[str, Any]:
        pairs = self._topics()
        texts = []
        for _, msg_type in pairs:
            try:
                texts.append(self.bridge.registry.full_text(msg_type))
            except InterfaceError:
                texts.append("")
        return {
            "topics": [t for t, _ in pairs],
            "types": [ty for _, ty in pairs],
            "typedefs_full_text": texts,
        }

    async def topic_type(self, request: dict[str, Any]) -> dict[str, Any]:
        topic = request.get("topic", "")
        if self.ros2:
            return {"type": dict(self._topics()).get(topic, "")}
        # 0.11.17 asks rostopic, which also matches a field path ('/chatter/' is /chatter's type) and
        # uses the master's memory of every type ever registered.
        return {"type": rostopic_type(self.bridge.graph.known_types, topic) or ""}

    async def publishers(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"publishers": self.bridge.graph.publishers_of(request.get("topic", ""), sort=self.ros2)}

    async def subscribers(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"subscribers": self.bridge.graph.subscribers_of(request.get("topic", ""), sort=self.ros2)}

    async def services(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"services": [e.name for e in self._services()]}

    async def services_for_type(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"services": [e.name for e in self._services() if e.type == request.get("type")]}

    async def service_type(self, request: dict[str, Any]) -> dict[str, Any]:
        by_name = {e.name: e.type for e in self._services()}
        return {"type": by_name.get(request.get("service", ""), "")}

    async def service_providers(self, request: dict[str, Any]) -> dict[str, Any]:
        # Quirk of every version: the `service` field is compared with service *types*, not names.
        wanted = request.get("service", "")
        if self.ros2:
            nodes = {e.node for e in self.bridge.graph.services.values() if e.type == wanted}
            return {"providers": sorted(nodes)}
        # 0.11.17 appends the node once per matching service, in registration order (/turtlesim twice
        # for std_srvs/Empty: /reset and /clear).
        return {"providers": [e.node for e in self.bridge.graph.services.values() if e.type == wanted]}

    async def service_node(self, request: dict[str, Any]) -> dict[str, Any]:
        entry = self.bridge.graph.services.get(request.get("service", ""))
        return {"node": entry.node if entry is not None else ""}

    async def service_host(self, request: dict[str, Any]) -> dict[str, Any]:
        # ROS 1: the host part of the service's URI; every simulated node runs on this machine.
        return {"host": "localhost" if request.get("service", "") in self.bridge.graph.services else ""}

    async def nodes(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"nodes": self.bridge.graph.node_names(sort=self.ros2)}

    async def node_details(self, request: dict[str, Any]) -> dict[str, Any]:
        node = self.bridge.graph.nodes.get(request.get("node", ""))
        if node is None:
            if self.ros2:
                # ROS 2 rosapi unpacks None for an unknown node; the service callback fails (no response).
                raise ServiceFailure(
                    f"cannot unpack non-iterable NoneType object (unknown node {request.get('node')})"
                )
            return {"subscribing": [], "publishing": [], "services": []}
        shown: Callable[[str], bool] = (lambda n: not is_hidden(n)) if self.legacy else (lambda n: True)
        # rosapi 2.1.0 asks ros2cli's node API, which leaves hidden names out.
        return {
            "subscribing": sorted(filter(shown, node.subscribes)),
            "publishing": sorted(filter(shown, node.publishes)),
            "services": sorted(filter(shown, node.services)),
        }

    async def action_servers(self, request: dict[str, Any]) -> dict[str, Any]:
        # Both lines compute it from topic names; ROS 2 includes hidden topics for it.
        names = [t for t, _ in self.bridge.graph.topics(include_hidden=True)]
        return {"action_servers": ros2_action_servers(names) if self.ros2 else ros1_action_servers(names)}

    async def action_type(self, request: dict[str, Any]) -> dict[str, Any]:
        server = self.bridge.graph.actions.get(request.get("action", ""))
        return {"type": server.type if server is not None else ""}

    # --- types ----------------------------------------------------------------------------------------------

    async def message_details(self, request: dict[str, Any]) -> dict[str, Any]:
        msg_type = request.get("type", "")
        try:
            if not self.ros2 and ("/" in msg_type or not msg_type):
                # roslib's loader takes pkg/Type only: 'std_msgs/msg/String' is not a valid type string.
                msg_type = self.bridge.registry.resolve(msg_type, "msg")
            return {"typedefs": self._slots(self.bridge.registry.message_typedefs(msg_type))}
        except InterfaceError as exc:
            if self.ros2:
                # ROS 2 objectutils logs the import error and answers with no typedefs.
                log.error(
                    "An error occurred trying to get the type definition for %s: %s", request.get("type"), exc
                )
                return {"typedefs": []}
            raise ServiceFailure(str(exc)) from exc

    def _slots(self, typedefs: list[dict[str, Any]]) -> list[dict[str, Any]]:
        """rosapi 2.1.0 names fields by the message's ``__slots__``: ``_linear``, ``_x``."""
        if not self.legacy:
            return typedefs
        return [{**t, "fieldnames": [f"_{name}" for name in t["fieldnames"]]} for t in typedefs]

    async def _details(
        self, getter: Callable[[str], list[dict[str, Any]]], request: dict[str, Any]
    ) -> dict[str, Any]:
        try:
            if self.legacy:
                self.bridge.registry.service_parts(request.get("type", ""))
            return {"typedefs": self._slots(getter(request.get("type", "")))}
        except InterfaceError as exc:
            if self.legacy:
                # 2.1.0's loader error escapes the service callback and ends rosapi's spin.
                return await self._die(f"service type {request.get('type')!r} does not load: {exc}")
            raise ServiceFailure(str(exc)) from exc

    async def service_request_details(self, request: dict[str, Any]) -> dict[str, Any]:
        return await self._details(self.bridge.registry.service_request_typedefs, request)

    async def service_response_details(self, request: dict[str, Any]) -> dict[str, Any]:
        return await self._details(self.bridge.registry.service_response_typedefs, request)

    async def action_goal_details(self, request: dict[str, Any]) -> dict[str, Any]:
        return await self._details(self.bridge.registry.action_goal_typedefs, request)

    async def action_result_details(self, request: dict[str, Any]) -> dict[str, Any]:
        return await self._details(self.bridge.registry.action_result_typedefs, request)

    async def action_feedback_details(self, request: dict[str, Any]) -> dict[str, Any]:
        return await self._details(self.bridge.registry.action_feedback_typedefs, request)

    async def interfaces(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"interfaces": self.bridge.registry.all_interfaces()}

    async def get_ros_version(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"version": 2, "distro": self.bridge.config.distro}

    async def get_time(self, request: dict[str, Any]) -> dict[str, Any]:
        now = time.time()
        sec = int(now)
        nsec = int((now - sec) * 1e9)
        return {"time": {"sec": sec, "nanosec": nsec} if self.ros2 else {"secs": sec, "nsecs": nsec}}

    # --- parameters -----------------------------------------------------------------------------------------

    async def get_param(self, request: dict[str, Any]) -> dict[str, Any]:
        name = request.get("name", "")
        if self.ros2:
            await self._wait_for_parameter_node(name)
            value, ok, reason = self.params2.get(name, request.get("default_value", ""))
            return {"value": value, "successful": ok, "reason": reason}
        return {"value": self.params1.get(name, request.get("default", ""))}

    async def set_param(self, request: dict[str, Any]) -> dict[str, Any]:
        name, value = request.get("name", ""), request.get("value", "")
        if self.ros2:
            await self._wait_for_parameter_node(name)
            if self.legacy and not self.params2.has(name):
                # 2.1.0 sets through the node's set_parameters: an undeclared parameter stays unset.
                try:
                    json.loads(value)
                except ValueError as exc:
                    raise ServiceFailure(JSON_REQUIRED) from exc
                return {}
            ok, reason = self.params2.set(name, value)
            self.bridge.world.notify()
            return {"successful": ok, "reason": reason}
        self.params1.set(name, value)
        self.bridge.world.notify()
        return {}

    async def has_param(self, request: dict[str, Any]) -> dict[str, Any]:
        name = request.get("name", "")
        if self.ros2 and self.legacy:
            try:
                node, _ = Ros2Params.split(name)
            except ValueError:
                return {"exists": False}
            await self._wait_for_parameter_node(name)
            if f"{node}/get_parameters" in self.bridge.graph.services and not self.params2.has(name):
                # 2.1.0 reads the first value of get_parameters outside its try: rclpy answers an empty
                # list for an undeclared name, and the IndexError ends rosapi.
                return await self._die(f"has_param of {name}, which the node has not declared")
        return {"exists": self.params2.has(name) if self.ros2 else self.params1.has(name)}

    async def delete_param(self, request: dict[str, Any]) -> dict[str, Any]:
        name = request.get("name", "")
        if self.ros2:
            if self.bridge.config.in_order or self.legacy:
                # Humble 2.0.x and 2.1.0 rosapi read `request.node_name`, which DeleteParam does not have.
                raise ServiceFailure("'DeleteParam_Request' object has no attribute 'node_name'")
            ok, reason = self.params2.delete(name)
            self.bridge.world.notify()
            return {"successful": ok, "reason": reason}
        self.params1.delete(name)
        self.bridge.world.notify()
        return {}

    async def get_param_names(self, request: dict[str, Any]) -> dict[str, Any]:
        if self.legacy:
            # 2.1.0 asks every node's list_parameters, /rosapi_params too, which has none: after its 5 s
            # wait the error escapes the service callback and rosapi ends.
            await asyncio.sleep(self.param_node_wait)
            return await self._die(f"{ROSAPI_PARAMS}/list_parameters did not come up")
        return {"names": self.params2.names() if self.ros2 else self.params1.names()}

    async def _wait_for_parameter_node(self, name: str) -> None:
        """rosapi 2.1.0 waits for the node's parameter service; a node that does not exist costs 5 s, and a
        parameter of rosapi itself deadlocks it."""
        if not self.legacy:
            return
        try:
            node, _ = Ros2Params.split(name)
        except ValueError:
            return
        if node == ROSAPI_NODE:
            # It calls its own /rosapi/get_parameters and waits on a future only its blocked executor could
            # complete: this call and every later rosapi call never answer; the process stays alive.
            log.error("rosapi hangs: %s is a parameter of rosapi itself", name)
            self.hung = True
            self.bridge.world.notify()
            await asyncio.Event().wait()
        if f"{node}/get_parameters" not in self.bridge.graph.services:
            await asyncio.sleep(self.param_node_wait)

    async def search_param(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"global_name": self.params1.search(request.get("name", ""))}
