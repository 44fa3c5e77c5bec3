"""Action servers and their types.

* ROS 1 (rosapi 0.11) has no ``get_ros_version``, ``action_type`` or ``interfaces``; ``action_servers`` may
  list a namespace several times; the type of an action is only visible as the type of its ``<ns>/goal``
  topic (``pkg/NameActionGoal``).
* ROS 2 ``action_type`` exists from Humble 2.0.2 / Jazzy 2.4.0 / Kilted 3.0.0. rosapi 2.1.0 has none and hides
  the hidden ``<ns>/_action/...`` names from every look-up; the bridge itself names the type when it refuses
  a probe call to ``<ns>/_action/send_goal``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

from rosbridge_mcp_server.errors import RequestTimeoutError, ServiceError
from rosbridge_mcp_server.robot.graph.rosapi import (
    ConnectionKnowledge,
    Rosapi,
    bounded_map,
    is_missing_service,
    strings,
)
from rosbridge_mcp_server.robot.graph.topics import Topics
from rosbridge_mcp_server.robot.known_types import PROBE_FIELD, action_type_from_refusal
from rosbridge_mcp_server.robot.names import absolute, did_you_mean

__all__ = ["ActionEntry", "Actions"]

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ActionEntry:
    """An action server and its type (``None`` when it cannot be known on this bridge)."""

    name: str
    type: str | None


class Actions:
    """Action look-ups through rosapi, the ``<ns>/goal`` topic (ROS 1) or a probe call (ROS 2)."""

    def __init__(self, rosapi: Rosapi, topics: Topics) -> None:
        self._rosapi = rosapi
        self._client = rosapi.client
        self._topics = topics

    @property
    def _known(self) -> ConnectionKnowledge:
        return self._rosapi.known

    async def action_names(self) -> list[str]:
        """Every action server name, once each, sorted."""
        values = await self._rosapi.call("action_servers")
        # ROS 1 rosapi 0.11 lists a namespace twice when other topics sort after `status` in it.
        return sorted({absolute(name) for name in strings(values.get("action_servers"))})

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
        info = await self._rosapi.ros_info()
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
        types = await bounded_map(self._action_type_or_none, names)
        return [ActionEntry(name, found) for name, found in zip(names, types, strict=True)]

    async def _ros1_action_type(self, action: str) -> str | None:
        goal_type = await self._topics.topic_type(f"{action.rstrip('/')}/goal")
        # actionlib: `<ns>/goal` carries `pkg/NameActionGoal`; the action is `pkg/NameAction`.
        if goal_type.endswith("ActionGoal"):
            return goal_type[: -len("Goal")]
        return None

    async def _ros2_action_type(self, action: str) -> str | None:
        found: str | None = None
        if not self._known.no_action_type_service:
            try:
                values = await self._rosapi.call("action_type", {"action": action})
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
