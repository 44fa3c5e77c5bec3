"""Type definitions through rosapi, kept for the connection once described.

* rosapi 2.1.0 writes TypeDef field names as Python slot names (``_linear``); :mod:`..messages` reads both.
* ``message_details`` answers an unknown type with an empty ``typedefs`` list (both lines). rosapi 2.1.0's
  ``service_request_details`` instead ends the rosapi node on a type it cannot load, so it is only ever asked
  about a type rosapi itself reported for a live service.
"""

from __future__ import annotations

import logging
from typing import Any

from rosbridge_mcp_server.client import Dialect, RosInfo
from rosbridge_mcp_server.errors import Advice, RequestTimeoutError, ServiceError, UnknownTypeError
from rosbridge_mcp_server.robot.graph.rosapi import ConnectionKnowledge, Rosapi, is_missing_service, strings
from rosbridge_mcp_server.robot.known_types import ros1_load_failure
from rosbridge_mcp_server.robot.messages import TypeDef, typedefs_from_rosapi

__all__ = ["TypeDefinitions"]

_log = logging.getLogger(__name__)


class TypeDefinitions:
    """rosapi's descriptions of message, service and action types, and the interfaces installed."""

    def __init__(self, rosapi: Rosapi) -> None:
        self._rosapi = rosapi

    @property
    def _known(self) -> ConnectionKnowledge:
        return self._rosapi.known

    async def message_typedefs(self, type_name: str) -> dict[str, TypeDef]:
        """A message type's definition and those of its nested types; :class:`UnknownTypeError` if none."""
        dialect = await self._rosapi.dialect()
        info, bridge_name = dialect.info, dialect.message_type(type_name)
        await self._check_installed(type_name, bridge_name, info)
        typedefs = await self._details("message_details", bridge_name, required=True)
        if typedefs is None:
            return {}  # rosapi loaded the type but could not describe it: rosbridge alone will judge
        if not typedefs:
            raise UnknownTypeError(type_name, _type_hint(info)).advise(Advice.TOPIC_TYPES)
        return typedefs

    async def service_request_typedefs(self, type_name: str) -> dict[str, TypeDef] | None:
        """The request definition of a service type, or ``None`` when rosapi cannot tell."""
        bridge_name = (await self._rosapi.dialect()).service_type(type_name)
        return await self._details("service_request_details", bridge_name) or None

    async def action_goal_typedefs(self, type_name: str) -> dict[str, TypeDef] | None:
        """The goal definition of an action type, or ``None`` when rosapi cannot tell.

        ROS 2: ``action_goal_details`` (Humble 2.0.2 / Jazzy 2.3.0 on). ROS 1: ``message_details`` of
        ``pkg/NameGoal`` (the goal message inside ``pkg/NameActionGoal``).
        """
        info = await self._rosapi.ros_info()
        names = Dialect.action_names(type_name)
        if info.version == 1:
            return await self._details("message_details", names.ros1_parts[0]) or None
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
            values = await self._rosapi.call(service, {"type": bridge_name})
        except ServiceError as exc:
            if is_missing_service(exc):
                if required:
                    raise
                return None
            if (await self._rosapi.ros_info()).version == 1 and not ros1_load_failure(exc.message):
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
        await self._rosapi.ros_info()  # forgets what an earlier connection knew
        if fresh or not self._known.interfaces_asked:
            self._known.interfaces_asked = True
            try:
                values = await self._rosapi.call("interfaces")
            except (ServiceError, RequestTimeoutError):
                self._known.interfaces = None
            else:
                listed = strings(values.get("interfaces"))
                self._known.interfaces = frozenset(listed) if listed else None
        return self._known.interfaces

    async def type_details(self, service: str, bridge_name: str) -> dict[str, Any]:
        """``/rosapi/<service>`` of a type (``message_details``, ``action_goal_details``, ...), kept for the
        connection once it described the type: a type's definition cannot change while the bridge runs."""
        await self._rosapi.ros_info()
        key = (service, bridge_name)
        kept = self._known.details_values.get(key)
        if kept is not None:
            return kept
        values = await self._rosapi.call(service, {"type": bridge_name})
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
            raise UnknownTypeError(type_name, _type_hint(info)).advise(Advice.TOPIC_TYPES)


def _type_hint(info: RosInfo) -> str:
    if info.version == 1:
        return "ROS 1 type names look like `geometry_msgs/Twist`"
    return "ROS 2 type names look like `geometry_msgs/msg/Twist`"
