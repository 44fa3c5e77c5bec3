"""Graph look-ups through rosapi, with the dialect quirks handled (the domain's view of the robot's graph).

Everything here is an ordinary ``call_service`` to a ``/rosapi/...`` service on the shared client. What
differs between bridges (docs/rosbridge-behaviour.md has what was verified on which release):

* ROS 1 (rosapi 0.11) has no ``get_ros_version``, ``action_type`` or ``interfaces``; ``action_servers`` may
  list a namespace several times; the type of an action is only visible as the type of its ``<ns>/goal``
  topic (``pkg/NameActionGoal``).
* ROS 2 ``action_type`` exists from Humble 2.0.2 / Jazzy 2.4.0 / Kilted 3.0.0. rosapi 2.1.0 has none and hides
  the hidden ``<ns>/_action/...`` names from every look-up; the bridge itself names the type when it refuses
  a probe call to ``<ns>/_action/send_goal``.
* rosapi 2.1.0 writes TypeDef field names as Python slot names (``_linear``); :mod:`.messages` reads both.
* ``message_details`` answers an unknown type with an empty ``typedefs`` list (both lines). rosapi 2.1.0's
  ``service_request_details`` instead ends the rosapi node on a type it cannot load, so it is only ever asked
  about a type rosapi itself reported for a live service.

What one connection has learnt (type definitions, the topics it publishes, service and action types) is one
object, replaced whole when the client reports a new connection: a reconnect may be to a robot with other
packages installed.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar

from rosbridge_mcp_server.errors import RequestTimeoutError, ServiceError, UnknownTypeError
from rosbridge_mcp_server.robot.known_types import (
    PROBE_CONCURRENCY,
    PROBE_FIELD,
    PROBE_SECONDS,
    action_type_from_refusal,
    infrastructure_types,
    ros1_load_failure,
    service_type_from_refusal,
)
from rosbridge_mcp_server.robot.messages import TypeDef, typedefs_from_rosapi
from rosbridge_mcp_server.robot.names import absolute, did_you_mean
from rosbridge_mcp_server.wire.dialect import RosInfo, action_type_names, normalize_type

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

_log = logging.getLogger(__name__)

ROSAPI_HINT = (
    "rosapi must be running next to rosbridge: the launch files start it (`ros2 launch rosbridge_server "
    "rosbridge_websocket_launch.xml`, `roslaunch rosbridge_server rosbridge_websocket.launch`); "
    "`rosbridge_websocket` run alone does not."
)

# Type look-ups for many names at once (service types, action types) run a few side by side, not more:
# rosbridge 0.11.17 answered 46 service_type calls in ~0.2 s one after another or four at a time, but took
# ~1.1 s eight or more at a time; rosbridge 2.1.0 left a call unanswered with sixteen connections asking.
_LOOKUP_CONCURRENCY = 4

_T = TypeVar("_T")
_R = TypeVar("_R")


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


@dataclass(frozen=True)
class ServiceEntry:
    """A service and its type (``""`` when rosapi could not tell)."""

    name: str
    type: str


@dataclass(frozen=True)
class ActionEntry:
    """An action server and its type (``None`` when it cannot be known on this bridge)."""

    name: str
    type: str | None


def is_missing_service(error: ServiceError) -> bool:
    """The bridge said the service is not in the graph (rosbridge_suite 0.11 and 2.x, rosbridge-server-rs)."""
    return error.not_in_graph


@dataclass
class _ConnectionKnowledge:
    """What one connection has learnt about the bridge; replaced whole when the connection changes."""

    typedefs: dict[tuple[str, str], dict[str, TypeDef]] = field(default_factory=dict)
    interfaces: frozenset[str] | None = None
    interfaces_asked: bool = False
    details_values: dict[tuple[str, str], dict[str, Any]] = field(default_factory=dict)
    publishing: dict[str, str] = field(default_factory=dict)
    service_types: dict[str, str] = field(default_factory=dict)
    action_types: dict[str, str] = field(default_factory=dict)
    no_action_type_service: bool = False
    # Types the bridge named when refusing a probe call; only listed, never used to ask rosapi for details.
    listed_types: dict[str, str] = field(default_factory=dict)
    refuses_unknown_fields: bool | None = None
    # The last listing whose services were all typed, with its names: the same names list the same entries.
    listing: tuple[tuple[str, ...], list[ServiceEntry]] | None = None


class RosGraph:
    """rosapi look-ups on one client, with type definitions cached per connection."""

    def __init__(self, client: RosbridgeClient) -> None:
        self._client = client
        self._cache_owner: RosInfo | None = None
        self._known = _ConnectionKnowledge()

    async def ros_info(self) -> RosInfo:
        """The bridge's ROS version and distro (detected by the client once per connection)."""
        info = await self._client.ros_info()
        # The client makes one RosInfo per connection, so a new object means a new connection.
        if info is not self._cache_owner:
            self._cache_owner = info
            self._known = _ConnectionKnowledge()
        return info

    async def rosapi(self, name: str, args: dict[str, Any] | None = None) -> dict[str, Any]:
        """Call ``/rosapi/<name>``; a missing rosapi is a :class:`ServiceError` saying how to start it."""
        service = f"/rosapi/{name}"
        try:
            values = await self._client.call_service(service, args or {})
        except ServiceError as exc:
            if is_missing_service(exc):
                raise ServiceError(service, f"{exc.message}. {ROSAPI_HINT}") from exc
            raise
        return values if isinstance(values, dict) else {}

    # --- topics -----------------------------------------------------------------------------------

    async def topics(self) -> list[TopicEntry]:
        """Every topic the graph knows, sorted by name, with its type."""
        values = await self.rosapi("topics")
        names = _strings(values.get("topics"))
        types = _strings(values.get("types"))
        entries = {name: (types[i] if i < len(types) else "") for i, name in enumerate(names)}
        return [TopicEntry(name, entries[name]) for name in sorted(entries)]

    async def topic_type(self, topic: str) -> str:
        """The type of ``topic``, or ``""`` when it is not in the graph."""
        values = await self.rosapi("topic_type", {"topic": topic})
        found = values.get("type")
        return found if isinstance(found, str) else ""

    async def publishing_type(self, topic: str) -> str:
        """The type of a topic about to be published on: ``topic_type``, skipped for a topic we publish.

        Once this connection has advertised a topic, rosbridge keeps the publisher (and so the topic's type)
        for as long as the connection lives, so the answer cannot have changed.
        """
        await self.ros_info()  # forgets what an earlier connection published
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

    async def topic_details(self, topic: str) -> TopicDetails:
        """Type, publishers and subscribers of ``topic`` (all empty when it is not in the graph)."""
        topic_type, publishers, subscribers = await asyncio.gather(
            self.topic_type(topic),
            self.rosapi("publishers", {"topic": topic}),
            self.rosapi("subscribers", {"topic": topic}),
        )
        return TopicDetails(
            name=topic,
            type=topic_type,
            publishers=tuple(_strings(publishers.get("publishers"))),
            subscribers=tuple(_strings(subscribers.get("subscribers"))),
        )

    # --- services ---------------------------------------------------------------------------------

    async def service_names(self) -> list[str]:
        """Every service name, sorted."""
        values = await self.rosapi("services")
        return sorted(set(_strings(values.get("services"))))

    async def service_type(self, service: str, *, cached: bool = False) -> str:
        """The type of ``service``, or ``""`` when rosapi does not know it.

        With ``cached``, a type already seen on this connection is reused, saving a round trip per call;
        callers forget it (:meth:`forget_service`) when the service turns out to be gone, and ask afresh
        when the cached type disagrees with what they expect.
        """
        await self.ros_info()  # forgets what an earlier connection knew
        if cached and (known := self._known.service_types.get(service)):
            return known
        values = await self.rosapi("service_type", {"service": service})
        found = values.get("type")
        found = found if isinstance(found, str) else ""
        if found:
            self._known.service_types[service] = found
        else:
            self._known.service_types.pop(service, None)
        return found

    def forget_service(self, service: str) -> None:
        """Drop the cached type of ``service`` (it went away, or was offered anew)."""
        self._known.service_types.pop(service, None)
        self._known.listing = None

    async def _service_type_or_blank(self, service: str) -> str:
        try:
            return await self.service_type(service)
        except (ServiceError, RequestTimeoutError) as exc:
            _log.info("no type for service %s: %s", service, exc)
            return ""

    async def services(self) -> list[ServiceEntry]:
        """Every service with its type (``""`` where a look-up failed).

        A service's type cannot change while it exists, so each is looked up once per connection and kept
        until the service is gone from the list; the per-node services every ROS node offers are typed from
        their names (:func:`infrastructure_types`) without asking.
        """
        info = await self.ros_info()
        names = await self.service_names()
        if (last := self._known.listing) is not None and last[0] == tuple(names):
            return last[1]
        known, listed = self._known.service_types, self._known.listed_types
        for cache in (known, listed):
            for gone in cache.keys() - set(names):
                del cache[gone]
        fixed = infrastructure_types(names, info.version)
        missing = self._untyped(names, fixed)
        if missing and info.version == 2 and await self._refuses_unknown_fields():
            await _bounded_map(self._listed_type, missing, PROBE_CONCURRENCY)
        elif missing:
            await _bounded_map(self._service_type_or_blank, missing)
        entries = [
            ServiceEntry(name, fixed.get(name) or known.get(name) or listed.get(name, "")) for name in names
        ]
        self._known.listing = (tuple(names), entries) if all(entry.type for entry in entries) else None
        return entries

    async def learn_service_types(self, limit: int = 256) -> int:
        """Ask rosapi, one service at a time, for the types a first listing would look up; how many it learnt.

        Run in the background when a connection opens (:mod:`.warm_up`), so the model's first
        ``list_services`` finds them known, and ``publish_service`` skips its type look-up. One call at a
        time keeps out of the way of the model's own calls (rosapi answers one call at a time; 0.11.17 is
        slower with several), and rosapi's ``service_type`` leaves nothing in the bridge's log, where a probe
        call leaves an error line. A look-up that times out ends it (:class:`RequestTimeoutError`).
        """
        info = await self.ros_info()
        names = await self.service_names()
        learnt = 0
        for name in self._untyped(names, infrastructure_types(names, info.version))[:limit]:
            # Re-checked each time: a listing running meanwhile may have typed it already.
            if name in self._known.service_types or name in self._known.listed_types:
                continue
            # A refusal is passed over; a timeout ends it all (rosapi is stuck: the next would wait as long).
            try:
                if await self.service_type(name):
                    learnt += 1
            except ServiceError as exc:
                _log.info("no type for service %s: %s", name, exc)
        return learnt

    def _untyped(self, names: list[str], fixed: dict[str, str]) -> list[str]:
        """The services among *names* whose type neither their name fixes nor this connection knows."""
        known, listed = self._known.service_types, self._known.listed_types
        return [name for name in names if name not in known and name not in listed and name not in fixed]

    async def _refuses_unknown_fields(self) -> bool:
        """Whether this bridge refuses a request with a field no message has, before calling anything.

        Every rosbridge we know does ("Message type X_Request does not have a field ..."); it is checked once
        per connection on rosapi's harmless ``get_time`` before any other service is probed that way.
        """
        if self._known.refuses_unknown_fields is None:
            try:
                await self._client.call_service("/rosapi/get_time", {PROBE_FIELD: 0}, timeout=PROBE_SECONDS)
            except ServiceError as exc:
                self._known.refuses_unknown_fields = "does not have a field" in exc.message
            except RequestTimeoutError:
                self._known.refuses_unknown_fields = False
            else:
                self._known.refuses_unknown_fields = False
        return self._known.refuses_unknown_fields

    async def _listed_type(self, service: str) -> None:
        """A service's type for the listing, from the bridge's refusal of a probe call; rosapi if none.

        rosbridge 2.1.0 answers such a probe in ~2-12 ms without creating a ROS client, where each rosapi
        ``service_type`` call creates one and about a quarter of them take ~90 ms
        (docs/rosbridge-behaviour.md).
        The type is only shown: checking a request still asks rosapi, so a misread refusal can never make
        rosapi describe a type it cannot load (that ends rosapi 2.1.0).
        """
        try:
            await self._client.call_service(service, {PROBE_FIELD: 0}, timeout=PROBE_SECONDS)
        except ServiceError as exc:
            found = service_type_from_refusal(exc.message)
            if found:
                self._known.listed_types[service] = found
                return
        except RequestTimeoutError:
            pass  # a glob-denied service gets no answer at all; rosapi may still know its type
        await self._service_type_or_blank(service)

    # --- actions ----------------------------------------------------------------------------------

    async def action_names(self) -> list[str]:
        """Every action server name, once each, sorted."""
        values = await self.rosapi("action_servers")
        # ROS 1 rosapi 0.11 lists a namespace twice when other topics sort after `status` in it.
        return sorted({absolute(name) for name in _strings(values.get("action_servers"))})

    async def missing_action(self, action: str) -> str | None:
        """``None`` when *action* is served (or rosapi cannot list actions), else a hint naming close ones.

        The hint is ``""`` or `` Did you mean /a?``, ready to end a sentence saying the action is not served.
        """
        try:
            known = await self.action_names()
        except ServiceError:
            return None  # no usable rosapi action_servers: let the goal or the cancel itself find out
        return None if action in known else did_you_mean(action, known)

    async def action_type(self, action: str) -> str | None:
        """The action's type in the bridge's own spelling, or ``None`` when the bridge cannot tell."""
        info = await self.ros_info()
        known = self._known.action_types.get(action)
        if known:
            return known
        found = await (
            self._ros1_action_type(action) if info.version == 1 else self._ros2_action_type(action)
        )
        if found:
            # Fixed while the action server exists; forgotten when it leaves the list (actions()).
            self._known.action_types[action] = found
        return found

    def known_action_type(self, action: str) -> str | None:
        """The action's type if this connection has learnt it (no round trip), else ``None``."""
        return self._known.action_types.get(action)

    async def _action_type_or_none(self, action: str) -> str | None:
        try:
            return await self.action_type(action)
        except (ServiceError, RequestTimeoutError) as exc:
            _log.info("no type for action %s: %s", action, exc)
            return None

    async def actions(self) -> list[ActionEntry]:
        """Every action server once, with its type where it can be known."""
        names = await self.action_names()
        known = self._known.action_types
        for gone in known.keys() - set(names):
            del known[gone]
        types = await _bounded_map(self._action_type_or_none, names)
        return [ActionEntry(name, found) for name, found in zip(names, types, strict=True)]

    async def _ros1_action_type(self, action: str) -> str | None:
        goal_type = await self.topic_type(f"{action.rstrip('/')}/goal")
        # actionlib: `<ns>/goal` carries `pkg/NameActionGoal`; the action is `pkg/NameAction`.
        if goal_type.endswith("ActionGoal"):
            return goal_type[: -len("Goal")]
        return None

    async def _ros2_action_type(self, action: str) -> str | None:
        found: str | None = None
        if not self._known.no_action_type_service:
            try:
                values = await self.rosapi("action_type", {"action": action})
            except ServiceError as exc:
                # `/rosapi/action_type` arrived in Humble 2.0.2 / Jazzy 2.4.0 / Kilted 3.0.0. Listed yet
                # failing (another bridge's newer rosapi on the graph, called through 2.1.0, which cannot load
                # its type): the other way below still works, so this connection stops asking.
                if not is_missing_service(exc):
                    _log.info("/rosapi/action_type failed (%s); reading action types another way", exc)
                self._known.no_action_type_service = True
            except RequestTimeoutError as exc:
                _log.info("/rosapi/action_type did not answer (%s); reading the type another way", exc)
            else:
                answer = values.get("type")
                found = answer if isinstance(answer, str) and answer else None
        if found is None:
            found = await self._send_goal_type(action)
        return found

    async def _send_goal_type(self, action: str) -> str | None:
        """The action's type as the bridge names it when refusing a call to ``<action>/_action/send_goal``.

        rosapi 2.1.0 hides every hidden name (``service_type`` of ``<action>/_action/send_goal`` is ``""``),
        but the bridge looks the service up itself. Called with a field no request has, it refuses before
        building a request, so nothing reaches the action server; its refusal names the type: "Unable to
        import srv class Fibonacci_SendGoal from package example_interfaces" (2.1.0 cannot load an action's
        services), or "Message type example_interfaces/action/Fibonacci_SendGoal_Request does not have a
        field ..." from a bridge that can.
        """
        service = f"{action.rstrip('/')}/_action/send_goal"
        try:
            await self._client.call_service(service, {PROBE_FIELD: 0})
        except ServiceError as exc:
            return action_type_from_refusal(exc.message)
        return None  # a bridge that took the probe as a request: do not read anything into it

    # --- type definitions -------------------------------------------------------------------------

    async def message_typedefs(self, type_name: str) -> dict[str, TypeDef]:
        """A message type's definition and those of its nested types; :class:`UnknownTypeError` if none."""
        info = await self.ros_info()
        bridge_name = normalize_type(type_name, info.version, "msg")
        await self._check_installed(type_name, bridge_name, info)
        typedefs = await self._details("message_details", bridge_name, required=True)
        if typedefs is None:
            return {}  # rosapi loaded the type but could not describe it: rosbridge alone will judge
        if not typedefs:
            raise UnknownTypeError(type_name, _type_hint(info))
        return typedefs

    async def service_request_typedefs(self, type_name: str) -> dict[str, TypeDef] | None:
        """The request definition of a service type, or ``None`` when rosapi cannot tell."""
        info = await self.ros_info()
        bridge_name = normalize_type(type_name, info.version, "srv")
        return await self._details("service_request_details", bridge_name) or None

    async def action_goal_typedefs(self, type_name: str) -> dict[str, TypeDef] | None:
        """The goal definition of an action type, or ``None`` when rosapi cannot tell.

        ROS 2: ``action_goal_details`` (Humble 2.0.2 / Jazzy 2.3.0 on). ROS 1: ``message_details`` of
        ``pkg/NameGoal`` (the goal message inside ``pkg/NameActionGoal``).
        """
        info = await self.ros_info()
        names = action_type_names(type_name)
        if info.version == 1:
            return await self._details("message_details", f"{names.package}/{names.name}Goal") or None
        return await self._details("action_goal_details", names.ros2) or None

    async def _details(
        self, service: str, bridge_name: str, *, required: bool = False
    ) -> dict[str, TypeDef] | None:
        """TypeDefs from ``/rosapi/<service>``.

        ``{}`` for a type rosapi cannot load; ``None`` when the service does not exist (an older rosapi), or,
        when ``required``, the missing-rosapi error is raised instead. ``None`` also when ROS 1 rosapi failed
        for another reason than loading the type (it cannot describe every type it can load).
        """
        key = (service, bridge_name)
        cached = self._known.typedefs.get(key)
        if cached is not None:
            return cached
        try:
            values = await self.rosapi(service, {"type": bridge_name})
        except ServiceError as exc:
            if is_missing_service(exc):
                if required:
                    raise
                return None
            if (await self.ros_info()).version == 1 and not ros1_load_failure(exc.message):
                # rosapi 0.11.17 loads std_msgs/Char but fails describing its char field ("'int' object has no
                # attribute '__module__'"), though rosbridge publishes it fine: the type exists.
                _log.info("rosapi %s could not describe %s: %s", service, bridge_name, exc.message)
                return None
            # rosapi raised while loading the type (ROS 1 reports the exception text).
            return {}
        except RequestTimeoutError:
            # A ROS 2 service whose handler raised never answers; rosapi does that for types it cannot load.
            _log.info("rosapi %s gave no answer for %s; treating the type as unknown", service, bridge_name)
            return {}
        typedefs = typedefs_from_rosapi(values)
        if typedefs:
            self._known.typedefs[key] = typedefs
        return typedefs

    async def installed_interfaces(self, *, fresh: bool = False) -> frozenset[str] | None:
        """Every interface type the bridge's machine has installed (ROS 2 ``/rosapi/interfaces``, Humble
        2.0.1+), asked once per connection (``fresh`` asks again); ``None`` when rosapi cannot list them.

        What is installed changes only when someone installs a package, so a type missing from the kept list
        is looked up again (``fresh``) before anything is refused for it.
        """
        await self.ros_info()  # forgets what an earlier connection knew
        if fresh or not self._known.interfaces_asked:
            self._known.interfaces_asked = True
            try:
                values = await self.rosapi("interfaces")
            except (ServiceError, RequestTimeoutError):
                self._known.interfaces = None
            else:
                listed = _strings(values.get("interfaces"))
                self._known.interfaces = frozenset(listed) if listed else None
        return self._known.interfaces

    async def type_details(self, service: str, bridge_name: str) -> dict[str, Any]:
        """``/rosapi/<service>`` of a type (``message_details``, ``action_goal_details``, ...), kept for the
        connection once it described the type: a type's definition cannot change while the bridge runs."""
        await self.ros_info()
        key = (service, bridge_name)
        kept = self._known.details_values.get(key)
        if kept is not None:
            return kept
        values = await self.rosapi(service, {"type": bridge_name})
        if values.get("typedefs"):
            self._known.details_values[key] = values
        return values

    async def _check_installed(self, type_name: str, bridge_name: str, info: RosInfo) -> None:
        """On ROS 2, check ``/rosapi/interfaces`` first: rosapi never answers about a type it cannot load."""
        if info.version != 2:
            return
        installed = await self.installed_interfaces()
        if installed is not None and bridge_name not in installed:
            installed = await self.installed_interfaces(fresh=True)
        if installed is not None and bridge_name not in installed:
            raise UnknownTypeError(type_name, _type_hint(info))


def _type_hint(info: RosInfo) -> str:
    if info.version == 1:
        return "ROS 1 type names look like `geometry_msgs/Twist`; list_topics shows the types in use."
    return "ROS 2 type names look like `geometry_msgs/msg/Twist`; list_topics shows the types in use."


def _strings(value: Any) -> list[str]:
    if not isinstance(value, list):
        return []
    return [item for item in value if isinstance(item, str)]


async def _bounded_map(
    func: Callable[[_T], Awaitable[_R]], items: Iterable[_T], limit: int = _LOOKUP_CONCURRENCY
) -> list[_R]:
    semaphore = asyncio.Semaphore(limit)

    async def one(item: _T) -> _R:
        async with semaphore:
            return await func(item)

    # A TaskGroup, not gather: when one look-up fails (the connection dropped) the others are cancelled.
    async with asyncio.TaskGroup() as group:
        tasks = [group.create_task(one(item)) for item in items]
    return [task.result() for task in tasks]
