"""Failures in the words a model reads: a tool's error (what went wrong, then what to try) and arguments that
do not fit a tool (one line per wrong argument, instead of pydantic's dump)."""

from __future__ import annotations

import difflib
import reprlib
from typing import Any

from pydantic import ValidationError
from pydantic_core import ErrorDetails

from rosbridge_mcp_server.errors import (
    ActionError,
    ConnectionLostError,
    InvalidMessageError,
    ProtocolError,
    RequestTimeoutError,
    RosbridgeError,
    ServiceError,
)
from rosbridge_mcp_server.robot.text import shown
from rosbridge_mcp_server.server.advice import advised
from rosbridge_mcp_server.tools.arguments import MAX_TEXT_ARGUMENT, parameter_listing
from rosbridge_mcp_server.tools.base import ToolFailure

__all__ = ["arguments_text", "error_text"]


_HINTS: tuple[tuple[type[RosbridgeError], str], ...] = (
    (
        ConnectionLostError,
        "Whether it took effect on the robot is unknown: check the robot's state (e.g. with list_topics) "
        "once the connection is back, before trying again.",
    ),
    (
        RequestTimeoutError,
        "The robot may be busy or the node may not be answering: check it is running (list_services / "
        "list_actions), or try again with a longer timeout. The request may still take effect on the robot "
        "later (a busy node or a frozen bridge runs it when it gets to it): check the robot's state before "
        "repeating one that moves it.",
    ),
    (
        ServiceError,
        "Check the service name and type with list_services and the request fields, then try again.",
    ),
    (ActionError, "Check the action name and type with list_actions and the goal fields, then try again."),
    (InvalidMessageError, "Fix the fields named above and call again; nothing was sent."),
    (
        ProtocolError,
        "The bridge sent something this server does not understand; check the rosbridge version on the "
        "robot.",
    ),
)


#: The longest error that quotes the bridge is shown whole up to this many characters.
_QUOTED_CHARS = 2_000


def error_text(exc: RosbridgeError | ToolFailure) -> str:
    """The sentence a model sees for a failed tool call: the error's own text, plus what to try."""
    text = advised(exc)
    if isinstance(exc, ServiceError | ActionError | ProtocolError):
        # They quote the bridge's (the robot's) own words: robot text, shown escaped and capped.
        text = shown(text, _QUOTED_CHARS)
    text = _sentence(text)
    if isinstance(exc, ConnectionLostError) and exc.goal_cancel is not None:
        return f"{text} Check the robot's state (e.g. with list_actions) before sending the goal again."
    if isinstance(exc, RosbridgeError):
        for kind, hint in _HINTS:
            if isinstance(exc, kind):
                return f"{text} {hint}"
    return text


def _sentence(text: str) -> str:
    """End the text as a sentence: the bridge's own texts (quoted in errors) end without a full stop."""
    stripped = text.rstrip()
    return stripped if not stripped or stripped[-1] in ".!?" else stripped + "."


def arguments_text(tool: str, error: ValidationError, schema: dict[str, Any]) -> str:
    """One sentence for arguments the tool's model refused: the unknown keys first (with the likely meant
    one), then each wrong argument in our words, then what the tool takes (*schema*, as listed)."""
    items = error.errors(include_url=False)
    known = list(schema.get("properties", {}))
    unknown = [str(item["loc"][0]) for item in items if _unknown_argument(item)]
    problems = [_unknown(unknown, known)] if unknown else []
    for item in items:
        if item["type"] == "extra_forbidden" and not _unknown_argument(item):
            # A key an object argument does not take (qos.depht), with the likely meant one.
            where = ".".join(str(part) for part in item["loc"][:-1])
            problems.append(f"{where}: unknown key {_key(str(item['loc'][-1]), _keys_at(schema, item))}")
        elif not _unknown_argument(item):
            problems.append(_problem(item) + _example(item, schema))
    return (
        f"Invalid arguments for {tool}: {'; '.join(problems)}. Nothing was sent. "
        f"It takes: {parameter_listing(schema)}."
    )


def _example(item: ErrorDetails, schema: dict[str, Any]) -> str:
    """What an object argument given in the wrong form takes, as its listed description says (with an
    example); nothing for any other problem."""
    if item["type"] not in _FORM_KINDS or len(item["loc"]) != 1:
        return ""
    described = schema.get("properties", {}).get(str(item["loc"][0]), {})
    description = described.get("description") if isinstance(described, dict) else None
    return f" (it takes: {description})" if isinstance(description, str) else ""


def _unknown_argument(item: ErrorDetails) -> bool:
    return item["type"] == "extra_forbidden" and len(item["loc"]) == 1


def _keys_at(schema: dict[str, Any], item: ErrorDetails) -> list[str]:
    """The keys the object holding the unknown one takes, as the listed schema says."""
    node: Any = schema
    for part in item["loc"][:-1]:
        node = node.get("properties", {}).get(str(part), {}) if isinstance(node, dict) else {}
    return list(node.get("properties", {})) if isinstance(node, dict) else []


def _meant(key: str, known: list[str]) -> str:
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.7) if len(key) <= 100 else []
    return f" (did you mean {close[0]}?)" if close else ""


def _unknown(keys: list[str], known: list[str]) -> str:
    shown = ", ".join(_key(key, known) for key in keys[:5])
    more = ", ..." if len(keys) > 5 else ""
    return f"unknown argument{'s' if len(keys) > 1 else ''} {shown}{more}"


def _key(key: str, known: list[str]) -> str:
    return (repr(key) if len(key) <= 40 else repr(key[:37]) + "...") + _meant(key, known)


def _problem(item: ErrorDetails) -> str:
    """One wrong argument: where (``qos.depth``), then what is wrong with it."""
    where = ".".join(str(part) for part in item["loc"]) or "(arguments)"
    kind, given = item["type"], item.get("input")
    if kind == "missing":
        return f"{where}: required but missing"
    if kind == "string_too_long" and isinstance(given, str):
        limit = item.get("ctx", {}).get("max_length", MAX_TEXT_ARGUMENT)
        return (
            f"{where}: {len(given)} characters, more than the {limit} this argument may have (names and ids "
            "are far shorter)"
        )
    if isinstance(given, bool) and kind in _NUMBER_KINDS:
        return f"{where}: expected a number, got {str(given).lower()} (a boolean is not a number)"
    if kind in _OURS:
        return f"{where}: {item['msg']}"  # already our words, and the value may be large
    message = item["msg"][:1].lower() + item["msg"][1:]
    return f"{where}: {_WORDS.get(kind, message)} (got {_short(given)})"


#: pydantic's error types for a value that should have been a number.
_NUMBER_KINDS = frozenset({"float_type", "int_type", "int_from_float", "float_parsing", "int_parsing"})
#: A JSON object given in the wrong form: the refusal says what the argument takes, with its example.
_FORM_KINDS = frozenset({"json_text", "json_object", "dict_type"})
#: Refusals worded by tools/arguments.py.
_OURS = frozenset({"json_text", "json_nesting", "json_object", "payload"})
#: pydantic's words for a wrong kind of value, in ours.
_WORDS = {
    "dict_type": "expected a JSON object",
    "model_type": "expected a JSON object",
    "list_type": "expected a list",
    "string_type": "expected a string",
    "bool_type": "expected true or false",
    "float_type": "expected a number",
    "int_type": "expected an integer",
}


#: A value shown in a refusal: a few levels and characters of it, whatever its size or nesting.
_SHORT = reprlib.Repr()
_SHORT.maxlevel, _SHORT.maxstring, _SHORT.maxother, _SHORT.maxdict, _SHORT.maxlist = 2, 40, 40, 4, 4


def _short(value: Any) -> str:
    text = _SHORT.repr(value)
    return text if len(text) <= 60 else text[:57] + "..."
