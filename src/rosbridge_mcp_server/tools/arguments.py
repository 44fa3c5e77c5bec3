"""Checks every tool's arguments get first, before they are converted to the tool's parameters.

The MCP SDK converts arguments leniently: it ignores keys a tool does not take (a typo such as ``mesage``
published an empty message) and takes ``true`` for the number 1. Here, before that:

* a key the tool does not take is an error naming it (the input schemas say ``additionalProperties: false``);
* a boolean given for a number is an error;
* bounded work: a plain string argument (a name, an id) has at most :data:`MAX_TEXT_ARGUMENT` characters,
  and a message, request or goal at most :data:`~rosbridge_mcp_server.client.frames.MAX_NESTING` levels
  and what rosbridge takes in one frame (:func:`~rosbridge_mcp_server.client.frames.payload_problem`).

Each refusal names the argument and the limit.
"""

from __future__ import annotations

import difflib
from typing import Any

from rosbridge_mcp_server.tools.base import payload_problem

__all__ = ["MAX_TEXT_ARGUMENT", "argument_problem", "parameter_listing"]

#: Longest plain string argument: names and ids are far shorter (a ROS name has at most 247 characters).
MAX_TEXT_ARGUMENT = 1000


def argument_problem(tool: str, arguments: dict[str, Any], schema: dict[str, Any]) -> str | None:
    """The sentence refusing ``arguments`` for ``tool`` (its input ``schema`` at hand), or ``None``."""
    properties: dict[str, Any] = schema.get("properties", {})
    unknown = [key for key in arguments if key not in properties]
    if unknown:
        shown = ", ".join(_key(key, list(properties)) for key in unknown[:5])
        more = ", ..." if len(unknown) > 5 else ""
        return (
            f"Invalid arguments for {tool}: unknown argument{'s' if len(unknown) > 1 else ''} {shown}{more}; "
            f"nothing was sent. It takes: {parameter_listing(schema)}."
        )
    problems: list[str] = []
    for key, value in arguments.items():
        problem = _value_problem(value, properties[key])
        if problem is not None:
            problems.append(f"{key}: {problem}")
    if problems:
        return f"Invalid arguments for {tool}: {'; '.join(problems)}. Nothing was sent."
    return None


def parameter_listing(schema: dict[str, Any]) -> str:
    """``topic, message_type, message (optional)``: the parameters a tool takes."""
    properties = schema.get("properties", {})
    required = set(schema.get("required", []))
    listing = ", ".join(f"{name}{'' if name in required else ' (optional)'}" for name in properties)
    return listing or "no arguments ({})"


def _value_problem(value: Any, prop: dict[str, Any]) -> str | None:
    kinds = _kinds(prop)
    if isinstance(value, bool):
        if "boolean" not in kinds and kinds & {"number", "integer"}:
            return f"expected a number, got {str(value).lower()} (a boolean is not a number)"
        return None
    if isinstance(value, str) and kinds and kinds <= {"string", "null"}:
        if len(value) > MAX_TEXT_ARGUMENT:
            return (
                f"{len(value)} characters, more than the {MAX_TEXT_ARGUMENT} this argument may have (names "
                "and ids are far shorter)"
            )
        return None
    if isinstance(value, dict | list | str):
        return payload_problem(value)
    return None


def _kinds(prop: dict[str, Any]) -> set[str]:
    kinds: set[str] = set()
    kind = prop.get("type")
    if isinstance(kind, str):
        kinds.add(kind)
    elif isinstance(kind, list):
        kinds.update(k for k in kind if isinstance(k, str))
    for arm in prop.get("anyOf", []) + prop.get("oneOf", []):
        if isinstance(arm, dict):
            kinds |= _kinds(arm)
    return kinds


def _key(key: str, known: list[str]) -> str:
    shown = repr(key) if len(key) <= 40 else repr(key[:37]) + "..."
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.7) if len(key) <= 100 else []
    return f"{shown} (did you mean {close[0]}?)" if close else shown
