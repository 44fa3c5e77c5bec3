"""What a diagnosis says: the areas and focuses, a :class:`Finding` with the :class:`Step`\\ s to look at
next, the whole :class:`Diagnosis`, and which steps' names may go into a call (:func:`checked_steps`)."""

from __future__ import annotations

import enum
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from typing import Any, Final, Literal

from rosbridge_mcp_server.errors import Advice, Advised
from rosbridge_mcp_server.robot.text import NAME_CHARS, is_frame_name, is_graph_name, shown

__all__ = [
    "AREAS",
    "FOCUSES",
    "MAX_LOG_FINDINGS",
    "MAX_STATUS_FINDINGS",
    "WINDOW",
    "Diagnosis",
    "Finding",
    "Look",
    "Step",
    "UnknownFocusError",
    "areas_for",
    "checked_steps",
    "shown_names",
]

#: Seconds the streams, tf and diagnostics are listened to.
WINDOW: Final = 1.0
AREAS: Final = ("graph", "lifecycle", "diagnostics", "streams", "tf", "logs", "arm")
#: What a ``focus`` narrows to: areas, and for ``navigation`` and ``sensors`` the kinds of streams.
FOCUSES: Final[dict[str, tuple[tuple[str, ...], frozenset[str] | None]]] = {
    "navigation": (("graph", "lifecycle", "streams", "tf", "logs"), frozenset({"scan", "odom", "tf"})),
    "sensors": (("diagnostics", "streams"), None),
    **{area: ((area,), None) for area in AREAS},
    "arm": (("arm", "streams"), frozenset({"joints"})),
}
MAX_LOG_FINDINGS: Final = 5
MAX_STATUS_FINDINGS: Final = 20


class UnknownFocusError(Advised, ValueError):
    """A ``focus`` that is no area, no focus word and no node of the graph."""


class Look(enum.Enum):
    """What to look at next about a finding; the diagnose tool says which call does it."""

    #: A node's log, from info up (names: the node).
    NODE_LOG = enum.auto()
    #: The whole log, from info up (instead of a node's, when the node's name cannot go into a call).
    LOG = enum.auto()
    #: The nodes of the graph.
    NODES = enum.auto()
    #: Who publishes and reads a topic (names: the topic).
    TOPIC = enum.auto()
    #: How a lifecycle node is activated, in words: an act on the robot, never a call built from its name.
    ACTIVATE = enum.auto()
    #: One node's topics and services (names: the node; none: the node named before).
    NODE = enum.auto()
    #: One message of a topic (names: the topic).
    ONE_MESSAGE = enum.auto()
    #: A message of a topic, waiting a while for it (names: the topic).
    WAIT_MESSAGE = enum.auto()
    #: A topic's stamps over a few seconds (names: the topic).
    STAMPS = enum.auto()
    #: One transform (names: target frame, source frame).
    TRANSFORM = enum.auto()
    #: One transform, waiting a while for it (names: target frame, source frame).
    TRANSFORM_WAIT = enum.auto()
    #: A diagnostics topic's messages until every status on it has come round (names: the topic, how many
    #: statuses it carries): publishers take turns on one topic, so one message is most likely another's OK.
    STATUSES = enum.auto()
    #: The arm: its joints, limits, state and controllers.
    ARM = enum.auto()
    #: Activate a controller through its controller manager (names: the manager, the controller).
    ACTIVATE_CONTROLLER = enum.auto()


@dataclass(frozen=True)
class Step:
    """One thing to look at next: what, the names it involves, and why (said after it, may be empty)."""

    look: Look
    names: tuple[str, ...] = ()
    why: str = ""


@dataclass(frozen=True)
class Finding:
    """One thing wrong: a problem or a warning, its area, what it is about (a topic, frame pair, node or
    status name), one sentence, what to look at next, the nodes it concerns, and details."""

    severity: Literal["problem", "warning"]
    area: str
    subject: str
    summary: str
    next: tuple[Step, ...]
    nodes: tuple[str, ...] = ()
    details: dict[str, Any] = field(default_factory=dict)


@dataclass
class Diagnosis:
    """The findings, the worst first, what each area checked (or why it could not), and how long it took."""

    findings: list[Finding]
    checked: dict[str, str]
    unavailable: dict[str, str]
    seconds: float
    streams: dict[str, float | None] = field(default_factory=dict)
    frames: list[str] = field(default_factory=list)
    #: How many more of an area's things were left out of its findings: "diagnostics" statuses not OK,
    #: "logs" groups of warnings and errors (the tool says where to read them).
    left_out: dict[str, int] = field(default_factory=dict)

    @property
    def problems(self) -> int:
        return sum(1 for f in self.findings if f.severity == "problem")

    @property
    def warnings(self) -> int:
        return sum(1 for f in self.findings if f.severity == "warning")


def areas_for(
    focus: str | None, nodes: Iterable[str]
) -> tuple[tuple[str, ...], frozenset[str] | None, str | None]:
    """(areas, stream kinds or None for all, node or None) for *focus*; :class:`UnknownFocusError` names the
    choices."""
    if not focus:
        return AREAS, None, None
    wanted = focus.strip()
    if wanted.lower() in FOCUSES:
        areas, kinds = FOCUSES[wanted.lower()]
        return areas, kinds, None
    node = wanted if wanted.startswith("/") else f"/{wanted}"
    known = set(nodes)
    if node in known:
        return AREAS, None, node
    raise UnknownFocusError(
        f"focus {focus!r} is neither one of {', '.join(FOCUSES)} nor a node of the graph (e.g. "
        f"{', '.join(sorted(known)[:3]) or '/amcl'})"
    ).advise(Advice.NODES)


def shown_names(names: Iterable[str]) -> tuple[str, ...]:
    return tuple(shown(name, NAME_CHARS) for name in names)


#: The looks whose names are graph names (nodes, topics); the transforms' are tf frames.
_FRAME_LOOKS: Final = frozenset({Look.TRANSFORM, Look.TRANSFORM_WAIT})


def checked_steps(finding: Finding, known: set[str]) -> Finding:
    """*finding* with only the steps whose names may go into a call: a graph name the graph has (*known*)
    and that passes the strict check, or a plain frame name. Anyone on the graph writes the names a log line
    or a transform carries; such a name is shown, never made into a call (a node's log then becomes the whole
    log; a step left with nothing becomes ``list_nodes``)."""

    def usable(step: Step) -> bool:
        if step.look in _FRAME_LOOKS:
            return all(is_frame_name(name) for name in step.names)
        if step.look is Look.ACTIVATE_CONTROLLER:  # (the manager, a controller's plain name: said in words)
            manager, controller = step.names
            return is_graph_name(manager) and manager in known and is_graph_name(f"/{controller}")
        if step.look is Look.STATUSES:  # (topic, how many statuses it carries: our count, not robot text)
            topic, count = step.names
            return is_graph_name(topic) and topic in known and count.isdigit()
        return all(is_graph_name(name) and name in known for name in step.names)

    steps = tuple(
        step if usable(step) else Step(Look.LOG, (), step.why) if step.look is Look.NODE_LOG else None
        for step in finding.next
    )
    kept = tuple(step for step in steps if step is not None) or (Step(Look.NODES),)
    return finding if kept == finding.next else replace(finding, next=kept)
