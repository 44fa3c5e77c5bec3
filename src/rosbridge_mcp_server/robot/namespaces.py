"""Robots under a namespace on one bridge (``/robot1``, ``/robot2``, ...): a robot's names, and which
namespace holds a name when none was given.

A namespace is ``""`` (none: the names at the root) or an absolute ROS name such as ``/robot2``; the robot's
topics and actions are under it (``/robot2/map``, ``/robot2/tf``, ``/robot2/navigate_to_pose``). When no
namespace is given (``None``), :func:`find_namespace` keeps the plain name when the graph has it (no extra
question to rosapi on that path), else takes the one namespace that has it, and raises
:class:`SeveralNamespacesError` (naming them all) when several do: it never guesses between robots.

Pure but for :func:`find_namespace`; no MCP.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

from rosbridge_mcp_server.errors import RosbridgeError

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = [
    "Found",
    "SeveralNamespacesError",
    "find_namespace",
    "namespace_name",
    "namespaces_with",
    "under",
]

MAX_NAMESPACE_CHARS = 256
_PART = r"[A-Za-z_][A-Za-z0-9_]*"
_NAMESPACE = re.compile(rf"^(/{_PART})+$")


class SeveralNamespacesError(RosbridgeError):
    """A name not at the root that several namespaces hold: the caller must say which."""

    def __init__(self, name: str, namespaces: list[str]) -> None:
        self.name = name
        self.namespaces = namespaces
        super().__init__(
            f"{name} is not in the graph, but {len(namespaces)} robots' namespaces have it: "
            f"{', '.join(namespaces)}."
        )


@dataclass(frozen=True)
class Found:
    """The namespace to use, and the sentence saying it was found (``None`` when it was given or plain)."""

    namespace: str
    note: str | None = None


def namespace_name(text: str) -> str:
    """*text* as a namespace: ``""`` (none) or ``/a/b``; :class:`ValueError` naming what is wrong."""
    value = text.strip().rstrip("/")
    if not value:
        return ""
    if len(value) > MAX_NAMESPACE_CHARS:
        raise ValueError(f"namespace is {len(value)} characters long; a ROS namespace here is at most 256")
    if not value.startswith("/"):
        value = f"/{value}"
    if not _NAMESPACE.match(value):
        raise ValueError(
            f"namespace {text!r} is not a ROS namespace: give e.g. /robot2 (letters, digits and _, each part "
            'not starting with a digit), or "" for none'
        )
    return value


def under(namespace: str, name: str) -> str:
    """*name* (absolute) under *namespace*, unless it is there already: ``/robot2`` + ``/map``."""
    if not namespace or name == namespace or name.startswith(f"{namespace}/"):
        return name
    return f"{namespace}{name}"


def namespaces_with(names: list[str], plain: str) -> list[str]:
    """The namespaces under which *plain* is among *names* (``/robot2`` for ``/robot2/map``), sorted."""
    found = {
        name[: -len(plain)]
        for name in names
        if name.endswith(plain) and name != plain and _NAMESPACE.match(name[: -len(plain)])
    }
    return sorted(found)


async def find_namespace(
    graph: RosGraph,
    given: str | None,
    plain: str,
    *,
    kind: Literal["topic", "action"],
    present: bool | None = None,
) -> Found:
    """The namespace to use for *plain* (a topic or an action at the root, e.g. ``/map``).

    *given* wins (``""`` is the root). Else the root when *plain* is there (*present*, when the caller
    already knows, saves asking), else the one namespace that has it (said in the note), else the root (the
    caller's own error then says *plain* is missing); several: :class:`SeveralNamespacesError`."""
    if given is not None:
        return Found(namespace_name(given))
    if present is None and kind == "topic":
        present = bool(await graph.topic_type(plain))
    elif present is None:
        present = plain in await graph.action_names()
    if present:
        return Found("")
    if kind == "topic":
        names = [entry.name for entry in await graph.topics()]
    else:
        names = await graph.action_names()
    found = namespaces_with(names, plain)
    if len(found) > 1:
        raise SeveralNamespacesError(plain, found)
    if not found:
        return Found("")
    return Found(found[0], f"Using namespace {found[0]}: {plain} is not in the graph, {found[0]}{plain} is.")
