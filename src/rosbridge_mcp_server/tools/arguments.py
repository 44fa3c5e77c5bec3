"""A tool's arguments: one strict model per tool, validated once, and the types its parameters use.

The model is made from the parameters of the tool's ``run`` (``server/adapter.py``: ``arguments_model``)
with :data:`ARGUMENTS_CONFIG`, so one validation does every check:

* strict types: ``true`` is no number and ``"5"`` no number (a JSON client sends numbers as numbers);
* a key the tool does not take is an error naming it (the input schemas say ``additionalProperties: false``);
* bounded work: a plain string argument (a name, an id) has at most :data:`MAX_TEXT_ARGUMENT` characters,
  and a message, request or goal at most :data:`~rosbridge_mcp_server.client.frame_limits.MAX_NESTING` levels
  and what rosbridge takes in one frame (:func:`~rosbridge_mcp_server.client.frame_limits.payload_problem`).

Models often send an object as JSON text: :data:`JsonObject` (a message, a request, a goal) takes either
and is the object; :data:`JsonValue` (a value of any type: a parameter's value, navigate_to's goal) reads
text that holds an object, a list or ``null``; :data:`FROM_JSON_TEXT` lets a list or an object parameter
take JSON text. What each refuses names the argument and the limit (``server/failures.py`` words the whole
refusal).
"""

from __future__ import annotations

import json
from typing import Annotated, Any

from pydantic import AfterValidator, BeforeValidator, ConfigDict, WithJsonSchema
from pydantic_core import PydanticCustomError

from rosbridge_mcp_server.client.frame_limits import nesting_text, payload_problem

__all__ = [
    "ARGUMENTS_CONFIG",
    "FROM_JSON_TEXT",
    "MAX_TEXT_ARGUMENT",
    "NO_FIELDS",
    "JsonObject",
    "JsonValue",
    "parameter_listing",
]

#: Longest plain string argument: names and ids are far shorter (a ROS name has at most 247 characters).
MAX_TEXT_ARGUMENT = 1000

#: The configuration of every tool's arguments model.
ARGUMENTS_CONFIG = ConfigDict(
    strict=True, extra="forbid", str_max_length=MAX_TEXT_ARGUMENT, arbitrary_types_allowed=True
)


def _read(text: str) -> Any:
    """*text* read as JSON; a refusal saying why it cannot be."""
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise PydanticCustomError(
            "json_text", "is not valid JSON ({why} at character {at})", {"why": exc.msg, "at": exc.pos}
        ) from None
    except RecursionError:
        raise PydanticCustomError("json_nesting", nesting_text()) from None


def _object_from_text(value: Any) -> Any:
    """JSON text given for an object, read: empty text is ``{}``; text holding anything but an object is
    refused, saying what it holds."""
    if not isinstance(value, str):
        return value
    if not value.strip():
        return {}
    read = _read(value)
    if not isinstance(read, dict):
        raise PydanticCustomError(
            "json_object",
            "expected a JSON object; the text {text} holds {kind}",
            {"text": _quoted(value), "kind": _kind(read)},
        )
    return read


def _from_text(value: Any) -> Any:
    """JSON text holding an object, a list or ``null``, read; any other value or text as it is (a place
    name, a string parameter's value)."""
    if not isinstance(value, str) or value.strip()[:1] not in ("{", "[", "n"):
        return value
    try:
        read = json.loads(value)
    except json.JSONDecodeError:
        return value
    except RecursionError:
        raise PydanticCustomError("json_nesting", nesting_text()) from None
    return read if read is None or isinstance(read, dict | list) else value


def _fits_a_frame(value: Any) -> Any:
    """*value* when it can be sent (nesting, size, text); otherwise a refusal naming the limit."""
    problem = payload_problem(value)
    if problem is not None:
        raise PydanticCustomError("payload", problem)
    return value


#: Lets a list or object parameter take JSON text for it (``"[\"/odom\"]"``).
FROM_JSON_TEXT = BeforeValidator(_from_text)

#: A message, request or goal: a JSON object, or JSON text holding one; within what one frame may hold.
JsonObject = Annotated[
    dict[str, Any],
    BeforeValidator(_object_from_text),
    AfterValidator(_fits_a_frame),
    WithJsonSchema({"type": "object"}),
]

#: A value of any JSON type (JSON text holding an object, a list or null is read); within one frame.
JsonValue = Annotated[Any, FROM_JSON_TEXT, AfterValidator(_fits_a_frame)]

#: The default of a :data:`JsonObject` parameter (pydantic gives every call a copy of its own).
NO_FIELDS: dict[str, Any] = {}


def parameter_listing(schema: dict[str, Any]) -> str:
    """``topic, message_type, message (optional)``: the parameters a tool takes."""
    properties = schema.get("properties", {})
    required = set(schema.get("required", []))
    listing = ", ".join(f"{name}{'' if name in required else ' (optional)'}" for name in properties)
    return listing or "no arguments ({})"


def _quoted(text: str) -> str:
    return repr(text) if len(text) <= 40 else repr(text[:37]) + "..."


def _kind(value: Any) -> str:
    """What a JSON value is, in words."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true or false"
    if isinstance(value, int | float):
        return "a number"
    if isinstance(value, list):
        return "a list"
    return "a string"
