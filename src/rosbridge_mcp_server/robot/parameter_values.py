"""ROS parameter values: rcl_interfaces' ``ParameterValue`` both ways, and how a value read back compares with
the one sent. Pure; :mod:`.parameters` does the asking."""

from __future__ import annotations

import json
from typing import Any

from rosbridge_mcp_server.errors import NotOnRobotError

__all__ = [
    "VALUE_FIELDS",
    "ParameterError",
    "from_parameter_value",
    "kind_of",
    "like",
    "same",
    "to_parameter_value",
]


class ParameterError(NotOnRobotError):
    """A parameter request that cannot be answered; ``str()`` says why and what exists."""


def same(after: Any, wanted: Any) -> bool:
    if isinstance(after, bool) or isinstance(wanted, bool):
        return after is wanted
    if isinstance(after, int | float) and isinstance(wanted, int | float):
        return float(after) == float(wanted)
    return bool(after == wanted)


def like(before: Any, value: Any) -> Any:
    """A value given as JSON text for a parameter that is not text (models often send "2.0") is decoded."""
    if isinstance(value, str) and before is not None and not isinstance(before, str):
        try:
            return json.loads(value)
        except ValueError:
            return value
    return value


# rcl_interfaces/msg/ParameterType: the field of ParameterValue that holds each type's value.
VALUE_FIELDS = {
    1: "bool_value",
    2: "integer_value",
    3: "double_value",
    4: "string_value",
    5: "byte_array_value",
    6: "bool_array_value",
    7: "integer_array_value",
    8: "double_array_value",
    9: "string_array_value",
}


def from_parameter_value(value: dict[str, Any]) -> Any:
    kind = value.get("type")
    field = VALUE_FIELDS.get(kind) if isinstance(kind, int) else None
    return value.get(field) if field is not None else None


def to_parameter_value(value: Any, before: Any) -> dict[str, Any]:
    """A ParameterValue for ``value``, typed like ``before`` where they fit (a whole number for a double)."""
    if isinstance(value, bool):
        kind = 1
    elif isinstance(value, int):
        kind = 3 if isinstance(before, float) else 2
        value = float(value) if kind == 3 else value
    elif isinstance(value, float):
        kind = 3
    elif isinstance(value, str):
        kind = 4
    elif isinstance(value, list) and all(isinstance(v, bool) for v in value):
        kind = 6
    elif isinstance(value, list) and all(isinstance(v, int) and not isinstance(v, bool) for v in value):
        doubles = isinstance(before, list) and any(isinstance(v, float) for v in before)
        kind = 8 if doubles else 7
        value = [float(v) for v in value] if doubles else value
    elif isinstance(value, list) and all(
        isinstance(v, int | float) and not isinstance(v, bool) for v in value
    ):
        kind, value = 8, [float(v) for v in value]
    elif isinstance(value, list) and all(isinstance(v, str) for v in value):
        kind = 9
    else:
        raise ParameterError(
            "A ROS 2 parameter holds a bool, an integer, a double, a string, or a list of one of these; "
            f"{json.dumps(value)[:80]} is none of them."
        )
    return {"type": kind, VALUE_FIELDS[kind]: value}


def kind_of(value: Any) -> str:
    if isinstance(value, bool):
        return "a bool"
    if isinstance(value, int):
        return "an integer"
    if isinstance(value, float):
        return "a double"
    if isinstance(value, str):
        return "a string"
    return "a list"
