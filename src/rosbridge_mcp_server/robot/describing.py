"""Describe a message, service or action type through rosapi, in either dialect.

Which rosapi services tell what (both lines unless said):

* a message: ``message_details`` (``pkg/msg/T`` on ROS 2, ``pkg/T`` on ROS 1);
* a service: ``service_request_details`` and ``service_response_details``;
* an action: ROS 2 ``action_goal_details`` / ``action_result_details`` / ``action_feedback_details`` (Humble
  2.0.2, Jazzy 2.3.0 on); ROS 1 has no action interfaces, only actionlib's messages ``pkg/TGoal``,
  ``pkg/TResult``, ``pkg/TFeedback``, described with ``message_details``.

An unknown type comes back as an empty ``typedefs`` list; a ROS 2 handler that raises never answers at all, so
a time-out also means "unknown" here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import (
    Advice,
    NotOnRobotError,
    RequestTimeoutError,
    ServiceError,
    UnknownTypeError,
)
from rosbridge_mcp_server.robot.type_outline import TypeOutline, clean_typedefs, outline_type

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["CannotDescribe", "Description", "Kind", "describe_type"]

Kind = Literal["message", "service", "action"]


class CannotDescribe(NotOnRobotError):
    """This bridge's rosapi cannot describe the type safely; ``str()`` says why and what to use instead."""


@dataclass(frozen=True)
class Description:
    """A type's kind, its name as the bridge spells it, and one outline per part (request, goal, …)."""

    kind: Kind
    type: str
    parts: tuple[tuple[str, TypeOutline], ...]


async def describe_type(graph: RosGraph, type_name: str) -> Description:
    """Look ``type_name`` up as the kind its name says, or (``pkg/T``) as a message, a service, an action."""
    _, category, _ = Dialect.split_type(type_name)
    dialect = await graph.dialect()
    info = dialect.info
    kinds: tuple[Kind, ...]
    if category == "msg":
        kinds = ("message",)
    elif category == "srv":
        kinds = ("service",)
    elif category == "action":
        kinds = ("action",)
    elif info.version == 1 and type_name.strip().endswith("Action"):
        # actionlib's pkg/TAction is also a message (goal/result/feedback wrappers); the action reads better.
        kinds = ("action", "message")
    else:
        kinds = ("message", "service", "action")
    if info.version == 2:
        kinds = await _installed_kinds(graph, type_name, kinds)
    for kind in kinds:
        found = await _describe_as(graph, type_name, kind, dialect)
        if found is not None:
            return found
    hint = (
        "ROS 1 type names look like `geometry_msgs/Twist`; name an action without `Action`, e.g. "
        "`actionlib_tutorials/Fibonacci`."
        if info.version == 1
        else "ROS 2 type names look like `geometry_msgs/msg/Twist`, `std_srvs/srv/SetBool`, "
        "`example_interfaces/action/Fibonacci`."
    )
    raise UnknownTypeError(type_name, hint).advise(Advice.TYPES_IN_USE)


async def _installed_kinds(graph: RosGraph, type_name: str, kinds: tuple[Kind, ...]) -> tuple[Kind, ...]:
    """The kinds it is safe and useful to ask ROS 2's rosapi about.

    ``/rosapi/interfaces`` (Humble 2.0.1 / Jazzy 2.2.0 on) lists every installed type, which spares look-ups
    that never answer. Without it (rosapi 2.1.0) a service type is asked about only when a running service has
    it: ``service_request_details`` of a type rosapi cannot load gets no answer and ends the rosapi node on
    2.1.0. Such a rosapi has no action details either.
    """
    package, _, name = Dialect.split_type(type_name)
    installed = await graph.installed_interfaces()
    if installed is not None:
        folders: dict[Kind, str] = {"message": "msg", "service": "srv", "action": "action"}
        found = tuple(kind for kind in kinds if f"{package}/{folders[kind]}/{name}" in installed)
        if not found:
            # The list is kept per connection: ask again before saying the type is not installed.
            installed = await graph.installed_interfaces(fresh=True) or frozenset()
            found = tuple(kind for kind in kinds if f"{package}/{folders[kind]}/{name}" in installed)
        return found
    safe: list[Kind] = []
    for kind in kinds:
        if kind == "message":
            safe.append(kind)
        elif kind == "service":
            in_use = await graph.rosapi("services_for_type", {"type": f"{package}/srv/{name}"})
            if in_use.get("services"):
                safe.append(kind)
    if "action" in kinds and len(kinds) == 1:
        raise CannotDescribe(
            "This bridge's rosapi cannot describe action types (that needs Humble 2.0.2 / Jazzy 2.3.0 or "
            "later)"
        ).advise(Advice.ACTION_TYPES)
    if "service" in kinds and "service" not in safe and len(kinds) == 1:
        raise CannotDescribe(
            f"No running service has the type {package}/srv/{name}, and this bridge's rosapi (no "
            "/rosapi/interfaces) can only describe service types in use without risk"
        ).advise(Advice.SERVICE_TYPES)
    return tuple(safe)


async def _describe_as(graph: RosGraph, type_name: str, kind: Kind, dialect: Dialect) -> Description | None:
    version = dialect.version
    if kind == "message":
        name = dialect.message_type(type_name)
        part = await _part(graph, "message_details", name, version)
        return Description(kind, name, (("message", part),)) if part else None
    if kind == "service":
        name = dialect.service_type(type_name)
        request = await _part(graph, "service_request_details", name, version)
        if request is None:
            return None
        response = await _part(graph, "service_response_details", name, version)
        parts = [("request", request)] + ([("response", response)] if response else [])
        return Description(kind, name, tuple(parts))
    names = dialect.action_names(type_name)
    if version == 1:
        sections = tuple(zip(("goal", "result", "feedback"), names.ros1_parts, strict=True))
        found = [(title, await _part(graph, "message_details", msg, version)) for title, msg in sections]
        name = names.ros1.action
    else:
        services = (
            ("goal", "action_goal_details"),
            ("result", "action_result_details"),
            ("feedback", "action_feedback_details"),
        )
        found = [(title, await _part(graph, service, names.ros2, version)) for title, service in services]
        name = names.ros2
    if found[0][1] is None:
        return None
    return Description("action", name, tuple((title, part) for title, part in found if part is not None))


async def _part(graph: RosGraph, service: str, bridge_name: str, version: int) -> TypeOutline | None:
    try:
        values = await graph.type_details(service, bridge_name)
    except ServiceError as exc:
        if exc.not_in_graph and service.startswith("action_"):
            raise CannotDescribe(
                "This bridge's rosapi cannot describe action types (that needs Humble 2.0.2 / Jazzy 2.3.0 or "
                "later)"
            ).advise(Advice.ACTION_TYPES) from exc
        if exc.not_in_graph:
            raise
        # rosapi raised while loading the type (ROS 1 sends the exception text): the type is not there.
        return None
    except RequestTimeoutError:
        return None
    raw = clean_typedefs(values)
    if not raw:
        return None
    return outline_type(bridge_name, raw, ros_version=version)
