"""Parameters as rosapi sees them, per dialect (rosapi ``params.py`` of each line).

ROS 1: one global parameter server with hierarchical names (``/turtlesim/background_r``); reading a
namespace returns a dictionary. ROS 2: parameters live in nodes and are named ``/node:param``; values are
typed, and a value of another type than the current one is refused (silently, as rosapi reports nothing).
Both take and return values as JSON text.
"""

from __future__ import annotations

import json
from typing import Any

from rosbridge_mcp_server.sim.graph import ServiceFailure

__all__ = ["JSON_REQUIRED", "Ros1Params", "Ros2Params", "parameter_value"]

#: rosapi's own error text for a ``set_param`` value that is not JSON (both lines).
JSON_REQUIRED = (
    "Due to the type flexibility of the ROS parameter server, the value argument to set_param must be a "
    "JSON-formatted string."
)

_YAML_TRUE = {"true", "yes", "on"}
_YAML_FALSE = {"false", "no", "off"}


def parameter_value(text: str) -> Any:
    """What ``rclpy.parameter.get_parameter_value(string_value=text)`` makes of a string (YAML-ish)."""
    lowered = text.strip().lower()
    if lowered in _YAML_TRUE:
        return True
    if lowered in _YAML_FALSE:
        return False
    try:
        value = json.loads(text)
    except ValueError:
        return text
    if isinstance(value, bool | int | float | list):
        return value
    return text


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "double"
    if isinstance(value, list):
        return "array"
    return "string"


class Ros2Params:
    """ROS 2: ``/node:param`` names over the nodes that exist."""

    def __init__(self, store: dict[str, Any], node_exists: Any) -> None:
        self.store = store
        self.node_exists = node_exists

    @staticmethod
    def split(name: str) -> tuple[str, str]:
        """``/turtlesim:background_r`` → (``/turtlesim``, ``background_r``); no ``:`` is malformed."""
        parts = name.split(":")
        if len(parts) != 2:
            raise ValueError(f"Malformed parameter name: {name}; expecting <node_name>:<param_name>")
        node = parts[0] if parts[0].startswith("/") else "/" + parts[0]
        return node, parts[1]

    def get(self, name: str, default: str) -> tuple[str, bool, str]:
        """rosapi ``get_param``: (value JSON, successful, reason)."""
        fallback: Any = default
        if default != "":
            try:
                fallback = json.loads(default)
            except ValueError:
                fallback = default
        try:
            node, param = self.split(name)
        except ValueError as exc:
            return "", False, str(exc)
        key = f"{node}:{param}"
        if key in self.store:
            return json.dumps(self.store[key]), True, ""
        # A missing node or parameter silently yields the default.
        return json.dumps(fallback), True, ""

    def set(self, name: str, value: str) -> tuple[bool, str]:
        """rosapi ``set_param``; a value of a new type for an existing parameter is refused."""
        try:
            node, param = self.split(name)
        except ValueError as exc:
            return False, str(exc)
        try:
            decoded = json.loads(value)
        except ValueError as exc:
            raise ServiceFailure(JSON_REQUIRED) from exc
        new = parameter_value(decoded) if isinstance(decoded, str) else parameter_value(value)
        if isinstance(decoded, dict):
            new = value
        key = f"{node}:{param}"
        if not self.node_exists(node):
            return False, f"Node {node} does not exist"
        if key in self.store and _kind(self.store[key]) != _kind(new):
            return (
                False,
                f"Wrong parameter type, parameter {{{param}}} is of type {{{_kind(self.store[key])}}}",
            )
        self.store[key] = new
        return True, ""

    def has(self, name: str) -> bool:
        """rosapi ``has_param``."""
        try:
            node, param = self.split(name)
        except ValueError:
            return False
        return f"{node}:{param}" in self.store

    def delete(self, name: str) -> tuple[bool, str]:
        """rosapi ``delete_param`` (Jazzy and later; Humble's is broken, see rosapi)."""
        try:
            node, param = self.split(name)
        except ValueError as exc:
            return False, str(exc)
        self.store.pop(f"{node}:{param}", None)
        return True, ""

    def names(self) -> list[str]:
        """rosapi ``get_param_names``: every node's parameters, ``/node:param``."""
        return sorted(k for k in self.store if not k.startswith("/rosapi:"))


class Ros1Params:
    """ROS 1: one global, hierarchical parameter server."""

    def __init__(self, store: dict[str, Any]) -> None:
        self.store = store

    @staticmethod
    def _norm(name: str) -> str:
        name = name if name.startswith("/") else "/" + name
        return name.rstrip("/") or "/"

    def _lookup(self, name: str) -> tuple[bool, Any]:
        key = self._norm(name)
        if key in self.store:
            return True, self.store[key]
        prefix = "/" if key == "/" else key + "/"
        subtree: dict[str, Any] = {}
        for full, value in self.store.items():
            if full.startswith(prefix):
                node = subtree
                parts = full[len(prefix) :].split("/")
                for part in parts[:-1]:
                    node = node.setdefault(part, {})
                node[parts[-1]] = value
        return (True, subtree) if subtree else (False, None)

    def get(self, name: str, default: str) -> str:
        """rosapi ``get_param``: the value as JSON; a missing name gives the default (``null`` without)."""
        fallback: Any = None
        if default != "":
            try:
                fallback = json.loads(default)
            except ValueError:
                fallback = default
        found, value = self._lookup(name)
        return json.dumps(value if found else fallback)

    def set(self, name: str, value: str) -> None:
        """rosapi ``set_param``; a dictionary sets a namespace."""
        try:
            decoded = json.loads(value)
        except ValueError as exc:
            raise ServiceFailure(JSON_REQUIRED) from exc
        if _holds_none(decoded):
            # rospy hands the value to the master over XML-RPC, which refuses None before anything changes.
            raise ServiceFailure("cannot marshal None unless allow_none is enabled")
        key = self._norm(name)
        self.delete(key)
        self._store_value(key, decoded)

    def _store_value(self, key: str, value: Any) -> None:
        if isinstance(value, dict):
            for child, child_value in value.items():
                self._store_value(f"{key.rstrip('/')}/{child}", child_value)
        else:
            self.store[key] = value

    def has(self, name: str) -> bool:
        """rosapi ``has_param`` (a namespace counts)."""
        return self._lookup(name)[0]

    def delete(self, name: str) -> None:
        """rosapi ``delete_param``: the name or the whole namespace; missing names are ignored."""
        key = self._norm(name)
        self.store.pop(key, None)
        prefix = key.rstrip("/") + "/"
        for full in [k for k in self.store if k.startswith(prefix)]:
            del self.store[full]

    def search(self, name: str, caller_namespace: str = "/rosapi") -> str:
        """rosapi ``search_param`` (rospy semantics from the rosapi node's namespace); ``""`` if not found."""
        if name.startswith("/"):
            return name if self.has(name) else ""
        first = name.split("/", maxsplit=1)[0]
        namespace = caller_namespace.rstrip("/")
        while True:
            candidate = f"{namespace}/{first}"
            if self.has(candidate):
                return f"{namespace}/{name}"
            if not namespace:
                return ""
            namespace = namespace.rsplit("/", 1)[0]

    def names(self) -> list[str]:
        """rosapi ``get_param_names``: every leaf name, in the parameter server's order (not sorted)."""
        return list(self.store)


def _holds_none(value: Any) -> bool:
    """Whether a JSON value is or contains ``null`` (XML-RPC cannot marshal it)."""
    if value is None:
        return True
    if isinstance(value, dict):
        return any(_holds_none(v) for v in value.values())
    if isinstance(value, list):
        return any(_holds_none(v) for v in value)
    return False
