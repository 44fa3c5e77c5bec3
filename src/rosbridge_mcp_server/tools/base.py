"""What every tool module shares: its spec, its answer, and the context it runs in.

A tool module never imports ``mcp`` and never touches a socket: it gets a :class:`ToolContext` (the rosbridge
client, the configuration, a graph helper and a progress callback) and returns a :class:`ToolAnswer`.
``server.py`` turns these into MCP tools.
"""

from __future__ import annotations

import difflib
import json
import math
import re
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel

from rosbridge_mcp_server.wire.protocol import BRIDGE_MAX_FRAME_BYTES

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.config import Config
    from rosbridge_mcp_server.ros import RosGraph

__all__ = [
    "ACTS_ON_ROBOT",
    "MAX_NAME_CHARS",
    "MAX_NESTING",
    "MAX_PAYLOAD_CHARS",
    "READS_ROBOT",
    "ProgressReporter",
    "ToolAnswer",
    "ToolContext",
    "ToolFailure",
    "ToolHints",
    "ToolSpec",
    "absolute_name",
    "check_name_for_ros",
    "compact_json",
    "did_you_mean",
    "parse_json_object",
    "payload_problem",
]


@dataclass(frozen=True)
class ToolHints:
    """The MCP tool annotations, in our own words (``server.py`` maps them to ``ToolAnnotations``)."""

    read_only: bool
    destructive: bool
    idempotent: bool
    # Every tool talks to a robot: an open world that changes on its own.
    open_world: bool = True


READS_ROBOT = ToolHints(read_only=True, destructive=False, idempotent=True)
ACTS_ON_ROBOT = ToolHints(read_only=False, destructive=True, idempotent=False)


@dataclass(frozen=True)
class ToolSpec:
    """Name, title, description (with an example) and hints of one tool.

    ``output`` is the pydantic model of the structured content of a successful answer; ``server.py`` publishes
    its JSON schema as the tool's output schema. Answers carry an instance of it, so they fit by construction.
    """

    name: str
    title: str
    description: str
    hints: ToolHints
    output: type[BaseModel]


@dataclass(frozen=True)
class ToolAnswer:
    """A tool's answer: short readable text for the model and the same facts as structured data."""

    text: str
    data: BaseModel


_SLASHES = re.compile(r"/{2,}")

ProgressReporter = Callable[[float, float | None, str | None], Awaitable[None]]


async def _no_progress(progress: float, total: float | None, message: str | None) -> None:
    """Default reporter: the caller did not ask for progress."""


@dataclass
class ToolContext:
    """What a tool may use: the client, the configuration, graph look-ups, and a progress callback."""

    client: RosbridgeClient
    config: Config
    graph: RosGraph
    report_progress: ProgressReporter = field(default=_no_progress)


class ToolFailure(Exception):
    """A tool could not do what was asked (an unknown topic, a malformed argument, a goal that timed out).

    ``str()`` is a sentence saying what happened and what to try. ``server.py`` turns it into an ``isError``
    result, like a :class:`~rosbridge_mcp_server.errors.RosbridgeError`.
    """


def parse_json_object(value: dict[str, Any] | str | None, what: str, example: str) -> dict[str, Any]:
    """A JSON object given as a dict or as JSON text (models sometimes send strings); ``None`` is ``{}``."""
    if value is None:
        return {}
    if isinstance(value, dict):
        return value
    text = value.strip()
    if not text:
        return {}
    try:
        parsed = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ToolFailure(
            f"The {what} is not valid JSON ({exc.msg} at character {exc.pos}). Send a JSON object, e.g. "
            f"{example}."
        ) from None
    except RecursionError:
        raise ToolFailure(f"The {what} {_nesting_text()}. Nothing was sent.") from None
    if not isinstance(parsed, dict):
        raise ToolFailure(f"The {what} must be a JSON object, e.g. {example}; got {compact_json(parsed)}.")
    problem = payload_problem(parsed)
    if problem is not None:
        raise ToolFailure(f"The {what} {problem}. Nothing was sent.")
    return parsed


#: Deepest nesting of objects and arrays in a message, request or goal. ROS messages nest a handful of levels
#: (a nav_msgs/Path: 6); the bound keeps checking and encoding one bounded, well inside the recursion limits
#: of every JSON parser on the way.
MAX_NESTING = 64
#: The most text a message, request or goal may hold: what rosbridge accepts in one frame.
MAX_PAYLOAD_CHARS = BRIDGE_MAX_FRAME_BYTES
_SURROGATE = re.compile("[\ud800-\udfff]")


def _nesting_text() -> str:
    return f"nests deeper than {MAX_NESTING} levels, the limit (ROS messages nest a handful of levels)"


def payload_problem(value: Any) -> str | None:
    """What makes ``value`` (a message, request or goal) unfit to send, or ``None``; bounded work.

    Too deep (:data:`MAX_NESTING`), too large for one rosbridge frame, or text that is not text (an unpaired
    UTF-16 surrogate, which cannot be encoded as UTF-8). Stops at the first problem.
    """
    size = 0
    stack: list[tuple[Any, int]] = [(value, 0)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict | list):
            if depth >= MAX_NESTING:
                return _nesting_text()
            size += 2
            if isinstance(item, dict):
                for key, inner in item.items():
                    if isinstance(key, str):
                        size += len(key) + 3
                        if _SURROGATE.search(key):
                            return _surrogate_text(key)
                    stack.append((inner, depth + 1))
            else:
                stack.extend((inner, depth + 1) for inner in item)
        elif isinstance(item, str):
            size += len(item) + 3
            if _SURROGATE.search(item):
                return _surrogate_text(item)
        else:
            size += 8
        if size > MAX_PAYLOAD_CHARS:
            return (
                f"is larger than {MAX_PAYLOAD_CHARS // (1024 * 1024)} MiB, the most rosbridge accepts in one "
                "frame (a larger frame makes it drop the connection)"
            )
    return None


def _surrogate_text(text: str) -> str:
    found = _SURROGATE.search(text)
    code = ord(found.group()) if found is not None else 0
    return f"holds an unpaired UTF-16 surrogate (\\u{code:04x}), which is not text and cannot be sent"


def absolute_name(name: str, what: str) -> str:
    """A ROS graph name with its leading slash (rosapi and rosbridge match names exactly).

    Held to the naming rules both ROS lines share (``[A-Za-z0-9_]`` tokens separated by ``/``, at most
    :data:`MAX_NAME_CHARS` characters); :func:`check_name_for_ros` adds what only ROS 2 refuses. A bridge
    acts on a name it cannot use by logging it and answering nothing, so an invalid name is refused here.
    """
    # ROS names never end in "/" nor hold "//"; either would make rosapi's exact-name look-ups miss. rospy
    # resolves "//a//b/" to "/a/b" (a real 0.11.17 bridge answers for it), so we do the same on both lines.
    if len(name) > MAX_NAME_CHARS * 2:
        raise ToolFailure(_too_long(what, len(name)))
    text = _SLASHES.sub("/", name.strip()).rstrip("/")
    if not text:
        raise ToolFailure(f"The {what} name is empty; give a name such as /turtle1/cmd_vel.")
    if any(ch.isspace() for ch in text):
        raise ToolFailure(f"The {what} name {_shown(name)} contains whitespace; ROS names never do.")
    if text.startswith("~"):
        raise ToolFailure(
            f"The {what} name {_shown(name)} is a private name (~), which only means something inside a "
            "node; give the full name, e.g. /turtle1/cmd_vel."
        )
    text = text if text.startswith("/") else "/" + text
    if len(text) > MAX_NAME_CHARS:
        raise ToolFailure(_too_long(what, len(text)))
    bad = _NAME_BAD_CHAR.search(text)
    if bad is not None:
        raise ToolFailure(
            f"The {what} name {_shown(text)} has {bad.group()!r} at position {bad.start()}; ROS names use "
            "only the letters A-Z and a-z, digits, _ and / (e.g. /turtle1/cmd_vel)."
        )
    return text


def check_name_for_ros(name: str, what: str, ros_version: int) -> None:
    """What only ROS 2 refuses in an absolute name from :func:`absolute_name`: a token led by a digit.

    ROS 1 allows ``/camera/2d``; ROS 2 (rcl and rmw name validation) does not, and rosbridge 2.x then
    only logs the failure.
    """
    if ros_version == 2:
        token = _DIGIT_TOKEN.search(name)
        if token is not None:
            raise ToolFailure(
                f"The {what} name {_shown(name)} has a part starting with a digit ({token.group(1)!r}); "
                "ROS 2 names do not allow that. Check the name with list_topics / list_services / "
                "list_actions."
            )


def _too_long(what: str, length: int) -> str:
    return (
        f"The {what} name is {length} characters long, more than the {MAX_NAME_CHARS} a ROS name can have "
        "(ROS 2's limit; ROS 1 names never come near it). Check the name with list_topics / list_services / "
        "list_actions."
    )


def _shown(name: str) -> str:
    return repr(name) if len(name) <= 80 else repr(name[:77]) + "..."


#: A ROS 2 name has at most 247 characters (rmw's limit: 255 less room for a DDS prefix).
MAX_NAME_CHARS = 247
_NAME_BAD_CHAR = re.compile(r"[^A-Za-z0-9_/]")
_DIGIT_TOKEN = re.compile(r"/([0-9][A-Za-z0-9_]*)")


def compact_json(value: Any, limit: int = 600) -> str:
    """One-line JSON for the answer text, cut at ``limit`` characters."""
    text = json.dumps(_finite(value), separators=(", ", ": "), ensure_ascii=False, default=str)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _finite(value: Any) -> Any:
    # ROS 2 can send NaN in fixed-size float arrays; strict JSON has no NaN, so show it as null.
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value


def did_you_mean(name: str, known: list[str]) -> str:
    """`` Did you mean /a or /b?`` for the names closest to a misspelt one, or ``""``."""
    close = difflib.get_close_matches(name, known, n=3, cutoff=0.8)
    return f" Did you mean {' or '.join(close)}?" if close else ""
