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

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.config import Config
    from rosbridge_mcp_server.ros import RosGraph

__all__ = [
    "ACTS_ON_ROBOT",
    "READS_ROBOT",
    "ProgressReporter",
    "ToolAnswer",
    "ToolContext",
    "ToolFailure",
    "ToolHints",
    "ToolImage",
    "ToolSpec",
    "absolute_name",
    "compact_json",
    "did_you_mean",
    "parse_json_object",
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
class ToolImage:
    """A picture in an answer (e.g. a camera frame): encoded bytes and their MIME type."""

    data: bytes
    mime_type: str


@dataclass(frozen=True)
class ToolAnswer:
    """A tool's answer: short readable text for the model and the same facts as structured data.

    ``images`` follow the text as MCP image content (the structured data describes them, never holds them).
    """

    text: str
    data: BaseModel
    images: tuple[ToolImage, ...] = ()


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
    if not isinstance(parsed, dict):
        raise ToolFailure(f"The {what} must be a JSON object, e.g. {example}; got {compact_json(parsed)}.")
    return parsed


def absolute_name(name: str, what: str) -> str:
    """A ROS graph name with its leading slash (rosapi and rosbridge match names exactly)."""
    # ROS names never end in "/" nor hold "//"; either would make rosapi's exact-name look-ups miss. rospy
    # resolves "//a//b/" to "/a/b" (a real 0.11.17 bridge answers for it), so we do the same on both lines.
    text = _SLASHES.sub("/", name.strip()).rstrip("/")
    if not text:
        raise ToolFailure(f"The {what} name is empty; give a name such as /turtle1/cmd_vel.")
    if any(ch.isspace() for ch in text):
        raise ToolFailure(f"The {what} name {name!r} contains whitespace; ROS names never do.")
    return text if text.startswith("/") else "/" + text


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
