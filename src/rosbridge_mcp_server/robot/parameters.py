"""ROS parameters through rosapi, in each dialect's naming.

* ROS 1: one global parameter server; names are graph names (``/turtlesim/background_r``). rosapi's
  ``get_param_names``, ``has_param``, ``get_param`` (``name``, ``default``) and ``set_param`` all work.
* ROS 2: parameters live in nodes; rosapi names them ``/node:name``. Three rosapi calls are unusable on a
  real 2.1.0 bridge: ``get_param_names`` kills rosapi, ``has_param`` of a missing parameter never answers (and
  on an in-order bridge blocks the connection), and ``get_param`` of a missing one answers its default. So
  names come from the node's own ``<node>/list_parameters`` service, and existence is checked against it.
  Values are read and set through the node's own ``get_parameters`` / ``set_parameters`` services too:
  rosapi 2.1.0's ``get_param`` of a parameter of the rosapi node itself deadlocks rosapi for good (its
  handler waits on its own blocked executor), and ``set_parameters`` says why a value was refused.
  A set is confirmed by reading the value back (rosapi's ``set_param`` answers nothing useful before 2.2.0).

Values travel as JSON text both ways.
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import NotSentError, RequestTimeoutError, ServiceError
from rosbridge_mcp_server.robot.graph import is_missing_service
from rosbridge_mcp_server.robot.names import did_you_mean, parameter_name
from rosbridge_mcp_server.robot.nodes import UnknownNodeError, node_names
from rosbridge_mcp_server.robot.parameter_values import (
    ParameterError,
    from_parameter_value,
    kind_of,
    like,
    same,
    to_parameter_value,
)
from rosbridge_mcp_server.robot.text import NAME_CHARS, shown

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = [
    "ParameterError",
    "ParameterGroup",
    "ParameterName",
    "PlannedSet",
    "SetOutcome",
    "apply_set",
    "get_parameter",
    "parameter_groups",
    "parse_name",
    "plan_set",
]

#: Nodes asked for their parameter names at once: a few when each call needs a connection of its own (an
#: in-order bridge: lanes), all of a Nav2-size graph when calls share the connection (each is then only a
#: message on it, as the raw floor sends them).
_LOOKUPS_AT_ONCE = 8
_LOOKUPS_AT_ONCE_SHARED = 64


@dataclass(frozen=True)
class ParameterName:
    """A parameter's full name in the dialect's form, and (ROS 2) its node and name within the node."""

    full: str
    node: str | None = None
    local: str | None = None


@dataclass(frozen=True)
class SetOutcome:
    """What a set did: the value before, the value read back after, and whether it now equals the request."""

    name: str
    before: Any
    after: Any
    applied: bool
    reason: str
    sent: Any = None


def parse_name(name: str, version: int) -> ParameterName:
    """``/turtlesim:background_r`` (ROS 2) or ``/turtlesim/background_r`` (ROS 1), checked and canonical
    (:func:`~rosbridge_mcp_server.robot.names.parameter_name`: ``/turtlesim//:background_r`` is
    ``/turtlesim:background_r``)."""
    try:
        full = parameter_name(name, version)
    except NotSentError as exc:
        raise ParameterError.carrying(exc) from None
    if version == 1:
        return ParameterName(full)
    node, _, local = full.partition(":")
    return ParameterName(full, node, local)


#: One node's parameter names, sorted and relative to it. ROS 1 parameters belong to namespaces, not nodes:
#: there the group is the first namespace (or the node asked for; ``""`` for the top level). The full name is
#: the node, the dialect's separator (ROS 2 ``:``, ROS 1 ``/``) and the name.
ParameterGroup = tuple[str, list[str]]


async def parameter_groups(
    graph: RosGraph, client: RosbridgeClient, node: str | None
) -> list[ParameterGroup]:
    """Every parameter name (of ``node`` only, when given), by node, nodes and names sorted: ``[(node, names
    relative to it), ...]`` for the nodes that have any (:data:`ParameterGroup`)."""
    info = await graph.ros_info()
    if info.version == 1:
        return _by_namespace(await _ros1_names(graph, node), node)
    if node is not None:
        # Asked directly: the graph is consulted only to word a failure.
        try:
            local_names = await _node_parameter_names(client, node)
        except ServiceError as exc:
            if not is_missing_service(exc):
                raise
            raise ParameterError(_no_parameter_service(node, nodes=await node_names(graph))) from None
        return [(node, sorted(local_names))] if local_names else []
    if (await graph.capabilities()).get_param_names_safe:
        # rosbridge-server-rs's built-in rosapi answers get_param_names safely (it kills rosapi 2.1.0):
        # one call instead of one per node.
        try:
            values = await graph.rosapi("get_param_names")
        except (ServiceError, RequestTimeoutError):
            pass
        else:
            listed = values.get("names") if isinstance(values, dict) else None
            if isinstance(listed, list):
                by_node: dict[str, set[str]] = {}
                for full in _names(listed):
                    if isinstance(full, str):
                        owner, sep, local = full.partition(":")
                        by_node.setdefault(owner if sep else "", set()).add(local if sep else full)
                return [(owner, sorted(by_node[owner])) for owner in sorted(by_node)]
    return await _every_nodes_names(graph, client)


async def _ros1_names(graph: RosGraph, node: str | None) -> list[str]:
    """ROS 1: every parameter's full name (under ``node``'s namespace only, when given), sorted."""
    values = await graph.rosapi("get_param_names")
    names = sorted(set(_names(values.get("names"))))
    if node is None:
        return names
    prefix = node.rstrip("/") + "/"
    found = [n for n in names if n.startswith(prefix)]
    if not found:
        # ROS 1 parameters belong to namespaces, not nodes: suggest the namespaces that have some.
        spaces = sorted({"/".join(n.split("/")[:2]) for n in names if n.count("/") >= 2})
        raise ParameterError(f"No parameters under {prefix}.{did_you_mean(node, spaces, cutoff=0.7)}")
    return found


def _by_namespace(names: list[str], node: str | None) -> list[ParameterGroup]:
    """ROS 1's full names grouped under ``node`` or, without one, by their first namespace."""
    grouped: dict[str, list[str]] = {}
    for owner, local in sorted(_split_ros1(full, node) for full in names):
        grouped.setdefault(owner, []).append(local)
    return list(grouped.items())


def _split_ros1(name: str, node: str | None) -> tuple[str, str]:
    """(namespace, name relative to it) of a ROS 1 parameter's full name."""
    if node is not None and name.startswith(node.rstrip("/") + "/"):
        return node.rstrip("/"), name[len(node.rstrip("/")) + 1 :]
    parts = name.split("/")
    return ("/" + parts[1], "/".join(parts[2:])) if len(parts) > 2 else ("", name.lstrip("/"))


_PARAMETER_SERVICE = "/list_parameters"


def _offering(service_names: Iterable[str]) -> list[str]:
    """The nodes that offer ``<node>/list_parameters`` (every ROS 2 node with parameters), sorted."""
    cut = len(_PARAMETER_SERVICE)
    return sorted(name[:-cut] for name in service_names if name.endswith(_PARAMETER_SERVICE))


async def _every_nodes_names(graph: RosGraph, client: RosbridgeClient) -> list[ParameterGroup]:
    """Every ROS 2 node's parameter names: the service list says which nodes to ask.

    The nodes the last listing on this connection named are asked while the new listing is on its way (one
    round trip instead of two while the graph stays the same); the new listing decides: a node it no longer
    names is not waited for and its answer not used, a node new in it is asked then. Each node's names are
    sorted as they come, while the others are still on their way.
    """
    shared = client.calls_share_connection
    gate = asyncio.Semaphore(_LOOKUPS_AT_ONCE_SHARED if shared else _LOOKUPS_AT_ONCE)

    async def one(name: str) -> list[str]:
        async with gate:
            try:
                return sorted(await _node_parameter_names(client, name))
            except (ServiceError, RequestTimeoutError):
                return []  # a node that does not answer does not hide the others

    seen = await graph.service_names_seen()
    asked = {name: asyncio.ensure_future(one(name)) for name in _offering(seen or ())}
    try:
        offering = _offering(await graph.service_names())
        for name in offering:
            if name not in asked:
                asked[name] = asyncio.ensure_future(one(name))
        per_node = await asyncio.gather(*(asked[name] for name in offering))
    finally:
        for task in asked.values():
            task.cancel()  # a node the new listing no longer names (or every one, when the listing failed)
        # Retrieve what an abandoned call ended with (a lost connection), so nothing is logged as unretrieved.
        await asyncio.gather(*asked.values(), return_exceptions=True)
    return [(name, names) for name, names in zip(offering, per_node, strict=True) if names]


async def get_parameter(graph: RosGraph, client: RosbridgeClient, name: str) -> tuple[ParameterName, Any]:
    """The parameter's value (decoded JSON); :class:`ParameterError` when it does not exist.

    One call on the happy path (ROS 2: the node's ``get_parameters``; ROS 1: ``get_param`` with a default no
    parameter holds); what exists is asked only to word the error when the value is not there.
    """
    info = await graph.ros_info()
    parsed = parse_name(name, info.version)
    return parsed, await _read_existing(graph, client, parsed, info.version)


async def _read_existing(
    graph: RosGraph, client: RosbridgeClient, parsed: ParameterName, version: int
) -> Any:
    """The value of a parameter that must exist; the error says what exists when it does not."""
    try:
        value = await _read(graph, client, parsed, version, missing=_MISSING)
    except _NotDeclared:
        value = _MISSING
    except ServiceError as exc:
        if version == 1 or not is_missing_service(exc):
            raise
        value = _MISSING  # the node offers no get_parameters (or is not running)
    if value is _MISSING:
        await _require_existing(graph, client, parsed, version)
        raise ParameterError(f"Parameter {parsed.full} does not exist.")
    return value


@dataclass(frozen=True)
class PlannedSet:
    """A checked parameter set, not yet sent: the name, the value before, and the value to send."""

    name: ParameterName
    before: Any
    value: Any


async def plan_set(graph: RosGraph, client: RosbridgeClient, name: str, value: Any) -> PlannedSet:
    """Check the name (and on ROS 2 that the node has the parameter) and read the value before."""
    info = await graph.ros_info()
    parsed = parse_name(name, info.version)
    if info.version == 2:
        # A ROS 2 node only has the parameters it declared; rosapi cannot add one.
        before = await _read_existing(graph, client, parsed, info.version)
    else:
        before = await _read(graph, client, parsed, info.version)
    return PlannedSet(parsed, before, like(before, value))


async def apply_set(
    graph: RosGraph,
    client: RosbridgeClient,
    planned: PlannedSet,
    value: Any,
    *,
    before_write: Callable[[], None] | None = None,
) -> SetOutcome:
    """Send the set, then read the value back; ``applied`` says whether the robot took it.

    *before_write* (the send gate) is called right before the write; what it raises ends it unsent.
    """
    info = await graph.ros_info()
    parsed = planned.name
    if info.version == 1:
        if before_write is not None:
            before_write()
        values = await graph.rosapi("set_param", {"name": parsed.full, "value": json.dumps(value)})
        given = values.get("reason")
        reason = given if isinstance(given, str) else ""
    else:
        reason = await _ros2_set(client, parsed, value, planned.before, before_write)
        if reason and planned.before is not None:
            reason += f" ({parsed.full} holds {kind_of(planned.before)}; send one of those)"
    after = await _read(graph, client, parsed, info.version)
    applied = same(after, value)
    if not applied and not reason:
        reason = (
            "the node kept its value (a ROS 2 parameter keeps its type: send a value of the same type, "
            "e.g. 2.0 for a double)"
            if info.version == 2
            else "reading it back gave another value"
        )
    return SetOutcome(parsed.full, planned.before, after, applied, reason, value)


class _NotDeclared(ParameterError):
    """A ROS 2 node answered no value: it has not declared the name."""


#: What ROS 1 ``get_param`` answers for a missing name when asked with this default (JSON text): no
#: parameter holds it, so one call both reads a value and tells that it is missing.
_ABSENT_TEXT = json.dumps("\u2400 rosbridge-mcp-server: no such parameter")
_MISSING: Any = object()


async def _read(
    graph: RosGraph, client: RosbridgeClient, parsed: ParameterName, version: int, *, missing: Any = None
) -> Any:
    """The value; ``missing`` (ROS 1) when the name is not set, :class:`_NotDeclared` (ROS 2)."""
    if version == 2:
        return await _ros2_read(client, parsed)
    args = {"name": parsed.full, "default": _ABSENT_TEXT if missing is not None else ""}
    values = await graph.rosapi("get_param", args)
    if missing is not None and values.get("value") == _ABSENT_TEXT:
        return missing
    if values.get("successful") is False:
        raise ParameterError(
            f"rosapi could not read {parsed.full}: {values.get('reason') or 'no reason given'}."
        )
    text = values.get("value")
    if not isinstance(text, str):
        return None
    try:
        return json.loads(text)
    except ValueError:
        return text


async def _require_existing(
    graph: RosGraph, client: RosbridgeClient, parsed: ParameterName, version: int
) -> None:
    if version == 1:
        values = await graph.rosapi("has_param", {"name": parsed.full})
        if values.get("exists") is True:
            return
        names = await _ros1_names(graph, None)
        raise ParameterError(
            f"Parameter {parsed.full} does not exist.{did_you_mean(parsed.full, names, cutoff=0.7)}"
        )
    assert parsed.node is not None
    assert parsed.local is not None
    services = set(await graph.service_names())
    if f"{parsed.node.rstrip('/')}/list_parameters" not in services:
        raise ParameterError(_no_parameter_service(parsed.node, nodes=await node_names(graph)))
    names = await _node_parameter_names(client, parsed.node)
    if parsed.local not in names:
        shown = ", ".join(sorted(names)) or "none"
        raise ParameterError(
            f"Node {parsed.node} has no parameter {parsed.local!r}; its parameters: {shown}."
        )


async def _node_parameter_names(client: RosbridgeClient, node: str) -> list[str]:
    reply = await client.call_service(f"{node.rstrip('/')}/list_parameters", {"prefixes": [], "depth": 0})
    if not isinstance(reply, dict):
        return []
    result = reply.get("result")
    return _names(result.get("names") if isinstance(result, dict) else None)


def _names(listed: Any) -> list[str]:
    """The parameter names a reply lists: robot text, shown escaped and capped (``robot/text.py``)."""
    if not isinstance(listed, list):
        return []
    names = [name for name in listed if isinstance(name, str)]
    # The usual reply (printable names within the cap) is checked in one pass: shown() would return each as
    # it is. A node lists dozens of names, a Nav2 graph over a thousand.
    if "".join(names).isprintable() and all(len(name) <= NAME_CHARS for name in names):
        return names
    return [shown(name, NAME_CHARS) for name in names]


def _no_parameter_service(node: str, *, nodes: list[str]) -> str:
    if node not in nodes:
        return str(UnknownNodeError(node, nodes))
    return f"Node {node} offers no parameter services (it has no parameters to read or set)."


async def _ros2_read(client: RosbridgeClient, parsed: ParameterName) -> Any:
    assert parsed.node is not None
    reply = await client.call_service(f"{parsed.node.rstrip('/')}/get_parameters", {"names": [parsed.local]})
    values = reply.get("values") if isinstance(reply, dict) else None
    if not isinstance(values, list) or not values or not isinstance(values[0], dict):
        # rclpy answers an empty list when a name is not declared.
        raise _NotDeclared(f"Node {parsed.node} has no parameter {parsed.local!r}.")
    return from_parameter_value(values[0])


async def _ros2_set(
    client: RosbridgeClient,
    parsed: ParameterName,
    value: Any,
    before: Any,
    before_write: Callable[[], None] | None = None,
) -> str:
    """Set through the node's ``set_parameters``; the node's reason when it refused, "" when it took it."""
    assert parsed.node is not None
    parameter = {"name": parsed.local, "value": to_parameter_value(value, before)}
    reply = await client.call_service(
        f"{parsed.node.rstrip('/')}/set_parameters", {"parameters": [parameter]}, check=before_write
    )
    results = reply.get("results") if isinstance(reply, dict) else None
    first = results[0] if isinstance(results, list) and results else None
    if isinstance(first, dict) and first.get("successful") is False:
        reason = first.get("reason")
        return reason if isinstance(reason, str) and reason else "the node refused the value"
    return ""
