"""Checks every tool's arguments get first, before they are converted to the tool's parameters.

Conversion to the parameters is lenient (pydantic's): it would take ``true`` for the number 1, and JSON text
given for an object is read as the object (models often send objects as strings). Here, before that:

* a key the tool does not take is an error naming it (the input schemas say ``additionalProperties: false``);
* a boolean given for a number is an error;
* bounded work: a plain string argument (a name, an id) has at most :data:`MAX_TEXT_ARGUMENT` characters,
  and a message, request or goal at most :data:`~rosbridge_mcp_server.client.frames.MAX_NESTING` levels
  and what rosbridge takes in one frame (:func:`~rosbridge_mcp_server.client.frames.payload_problem`).

Each refusal names the argument and the limit. :func:`read_json_text` then reads JSON text given for an
argument that is not plain text, and checks what it read as it checks an object given as one.
"""

from __future__ import annotations

import difflib
import json
from typing import Any

from pydantic import BaseModel

from rosbridge_mcp_server.robot.wording import full_stop
from rosbridge_mcp_server.tools.base import payload_problem

__all__ = ["MAX_TEXT_ARGUMENT", "argument_problem", "parameter_listing", "read_json_text"]

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


def read_json_text(
    tool: str, arguments: dict[str, Any], model: type[BaseModel]
) -> tuple[dict[str, Any], str | None]:
    """*arguments* with JSON text read, and the sentence refusing what was read (or ``None``).

    A string given for a parameter of *model* that is not plain ``str`` is read as JSON when it holds an
    object, a list or ``null`` (``"request": "null"`` is ``None``, ``"goal": "{...}"`` an object);
    anything else stays the string it was (what the MCP SDK's own tool functions do, kept so that a call
    behaves as it did). An object or list so read is checked like one given as such (nesting, size, text).
    The dict given is left alone.
    """
    read = dict(arguments)
    fields = model.model_fields
    for key, value in arguments.items():
        field = fields.get(key)
        if field is None or not isinstance(value, str) or field.annotation is str:
            continue
        try:
            parsed = json.loads(value)
        except (ValueError, RecursionError):
            continue  # not JSON, or JSON too deep to read: validation takes or refuses the string
        if isinstance(parsed, str | int | float):
            continue  # a number or a boolean (an int) stays the text it was; validation says what it wants
        read[key] = parsed
        if isinstance(parsed, dict | list):
            problem = payload_problem(parsed)
            if problem is not None:
                return read, f"Invalid arguments for {tool}: {key}: {full_stop(problem)} Nothing was sent."
    return read, None


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
