"""Failures in the words a model reads: a tool's error (what went wrong, then what to try) and arguments that
do not fit a tool (one line per wrong argument, instead of pydantic's dump)."""

from __future__ import annotations

from typing import Any

from pydantic import ValidationError

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
from rosbridge_mcp_server.tools.arguments import parameter_listing
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
    problems: list[str] = []
    union_kinds: dict[str, list[str]] = {}
    union_inputs: dict[str, Any] = {}
    for item in error.errors(include_url=False):
        loc = [str(part) for part in item["loc"]]
        where = loc[0] if loc else "(arguments)"
        if item["type"] == "missing":
            problems.append(f"{where}: required but missing")
        elif len(loc) == 2 and loc[1] in _UNION_KINDS:
            # pydantic reports each arm of `dict | str` separately, named by its type; say it once.
            if where not in union_kinds:
                problems.append(where)
            union_kinds.setdefault(where, []).append(_UNION_KINDS[loc[1]])
            union_inputs[where] = item.get("input")
        else:
            problems.append(
                f"{'.'.join(loc) or where}: {item['msg'].lower()} (got {_short(item.get('input'))})"
            )
    for where, kinds in union_kinds.items():
        index = problems.index(where)
        problems[index] = f"{where}: expected {' or '.join(kinds)} (got {_short(union_inputs[where])})"
    return f"Invalid arguments for {tool}: {'; '.join(problems)}. It takes: {parameter_listing(schema)}."


_UNION_KINDS = {"dict[str,any]": "a JSON object", "str": "a string", "float": "a number", "int": "an integer"}


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."
