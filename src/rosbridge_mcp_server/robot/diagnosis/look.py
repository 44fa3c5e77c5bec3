"""One look at the robot (:func:`diagnose`): what to listen to, listening and asking side by side, then each
area's judgement of what was heard."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Final

from rosbridge_mcp_server.robot.diagnosis.arm import ARM_TOPICS, Controllers, arm_findings, read_controllers
from rosbridge_mcp_server.robot.diagnosis.findings import (
    AREAS,
    WINDOW,
    Diagnosis,
    Finding,
    areas_for,
    checked_steps,
)
from rosbridge_mcp_server.robot.diagnosis.graph import (
    graph_findings,
    lifecycle_findings,
    lifecycle_states,
    topic_details,
)
from rosbridge_mcp_server.robot.diagnosis.reports import log_findings, status_findings
from rosbridge_mcp_server.robot.diagnosis.streams import (
    AGAIN,
    TWISTS,
    Heard,
    key_streams,
    listening,
    others,
    short_type,
    stream_findings,
    tf_namespaces,
)
from rosbridge_mcp_server.robot.diagnosis.tf import tf_trees
from rosbridge_mcp_server.robot.diagnostics import StatusBoard
from rosbridge_mcp_server.robot.log_keeper import DIAGNOSTICS_TOPICS
from rosbridge_mcp_server.robot.nodes import node_names
from rosbridge_mcp_server.robot.text import NAME_CHARS, shown

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph
    from rosbridge_mcp_server.robot.log_keeper import LogKeeper

__all__ = ["diagnose"]


@dataclass
class _Gathered:
    """What one look is after and what it found out; each area's judgement adds to *checked*,
    *unavailable*, *left_out* and *frames*."""

    keeper: LogKeeper | None
    topics: dict[str, str]
    nodes: list[str]
    areas: tuple[str, ...]
    ros2: bool
    window: float
    namespace: str | None
    #: Whether a focus was asked for (an area missing is then said).
    asked: bool
    tf_spaces: list[str] = field(default_factory=list)
    streams: dict[str, str] = field(default_factory=dict)
    heard: dict[str, Heard] = field(default_factory=dict)
    pubsub: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = field(default_factory=dict)
    states: dict[str, str] | None = None
    arm: Controllers = None
    checked: dict[str, str] = field(default_factory=dict)
    unavailable: dict[str, str] = field(default_factory=dict)
    left_out: dict[str, int] = field(default_factory=dict)
    frames: set[str] = field(default_factory=set)


async def diagnose(
    client: RosbridgeClient,
    graph: RosGraph,
    keeper: LogKeeper | None,
    *,
    focus: str | None = None,
    window: float = WINDOW,
    namespace: str | None = None,
) -> Diagnosis:
    """Look at the robot once (see the package docstring); :class:`UnknownFocusError` for a bad *focus*.

    *namespace* (``""``: the root) narrows the streams and tf to one robot of several on the bridge."""
    began = time.monotonic()
    dialect = await graph.dialect()
    entries, listed = await asyncio.gather(graph.topics(), node_names(graph))
    # Names the robot's graph gives are robot text: shown escaped and capped (a real name is unchanged).
    topics = {shown(e.name, NAME_CHARS): shown(e.type, NAME_CHARS) for e in entries}
    nodes = [shown(node, NAME_CHARS) for node in listed]
    #: The names a suggested call may use: those of the graph, now or at the last look.
    known = {*nodes, *topics, *(keeper.nodes_seen or () if keeper is not None else ())}
    areas, kinds, focus_node = areas_for(focus, nodes)
    look = _Gathered(
        keeper, topics, nodes, areas, dialect.version == 2, window, namespace, asked=focus is not None
    )
    look.tf_spaces = [s for s in tf_namespaces(topics) if namespace is None or s == namespace]
    look.streams = _measured_streams(look, kinds)
    await _gather(look, client, graph, focus_node)
    findings = [finding for area in AREAS if area in areas for finding in _JUDGES[area](look)]
    if focus_node is not None:
        findings = [f for f in findings if focus_node in f.nodes or f.subject == focus_node]
    findings = [checked_steps(f, known) for f in findings]
    order = {area: i for i, area in enumerate(AREAS)}
    findings.sort(key=lambda f: (f.severity != "problem", order.get(f.area, 99)))
    rates = {t: look.heard[t].rate if t in look.heard else None for t in look.streams}
    return Diagnosis(
        findings,
        look.checked,
        look.unavailable,
        time.monotonic() - began,
        streams=rates,
        frames=sorted(look.frames),
        left_out=look.left_out,
    )


def _measured_streams(look: _Gathered, kinds: frozenset[str] | None) -> dict[str, str]:
    """topic → kind of the key streams to measure: under the namespace when one is given; only ``/tf`` when
    the streams area is not looked at but tf is."""
    if "streams" not in look.areas and "tf" not in look.areas:
        return {}
    streams_of = look.topics
    if look.namespace:
        streams_of = {t: ty for t, ty in look.topics.items() if t.startswith(f"{look.namespace}/")}
    streams = key_streams(streams_of, kinds, look.left_out)
    if "streams" not in look.areas:
        look.left_out.pop("streams", None)
        return {t: k for t, k in streams.items() if k == "tf"}
    return streams


def _to_listen(look: _Gathered) -> dict[str, tuple[str, bool]]:
    """topic → (type, keep its messages): the key streams (``/tf``'s messages kept), and what the tf,
    diagnostics and arm areas read."""
    listened = {t: (look.topics[t], k == "tf") for t, k in look.streams.items()}
    read: list[str] = []
    if "tf" in look.areas:
        read += [topic for space in look.tf_spaces for topic in (f"{space}/tf", f"{space}/tf_static")]
    if "diagnostics" in look.areas:
        read += DIAGNOSTICS_TOPICS
    if "arm" in look.areas:
        read += ARM_TOPICS
    listened.update({topic: (look.topics[topic], True) for topic in read if topic in look.topics})
    return listened


async def _nothing() -> None:
    return None


async def _gather(look: _Gathered, client: RosbridgeClient, graph: RosGraph, focus_node: str | None) -> None:
    """Listen for the window while asking who reads ``cmd_vel``, the lifecycle states and the controllers."""
    drives = [
        t for t, ty in look.topics.items() if t.rsplit("/", 1)[-1] == "cmd_vel" and short_type(ty) in TWISTS
    ]
    lifecycle = "lifecycle" in look.areas and look.ros2
    # Who publishes and reads a stream is asked only of the silent ones, after the look (a healthy robot's
    # look costs no more rosapi calls than the cmd_vel topics'; ROS 1 would open a lane for each). A silent
    # one with a publisher is heard again before it is judged (AGAIN).
    async with listening(client, _to_listen(look)) as ears:
        look.heard = ears.heard
        _, look.pubsub, look.states, look.arm = await asyncio.gather(
            ears.hear(look.window),
            topic_details(graph, drives if "graph" in look.areas else []),
            lifecycle_states(client, graph, focus_node, look.window) if lifecycle else _nothing(),
            read_controllers(client, graph, look.window) if "arm" in look.areas else _nothing(),
        )
        silent = [t for t in look.streams if t in look.heard and not look.heard[t].times]
        if silent and ("graph" in look.areas or "streams" in look.areas):
            look.pubsub = {**look.pubsub, **await topic_details(graph, silent)}
            silent = [t for t in silent if others(look.pubsub.get(t, ((), ()))[0])]
        # A rate needs two messages: one that sent only one (a busy machine) is heard again with the silent.
        thin = [t for t in look.streams if t in look.heard and len(look.heard[t].times) == 1]
        if silent or thin:
            await ears.hear(AGAIN, only=silent + thin)


# --- each area's judgement of what was gathered ------------------------------------------------------------


def _graph(look: _Gathered) -> list[Finding]:
    return graph_findings(
        look.keeper,
        nodes=look.nodes,
        topics=look.topics,
        pubsub=look.pubsub,
        streams=look.streams,
        checked=look.checked,
    )


def _lifecycle(look: _Gathered) -> list[Finding]:
    if not look.ros2:
        look.unavailable["lifecycle"] = "ROS 1 has no lifecycle nodes"
    elif not look.states:
        look.unavailable["lifecycle"] = "no node offers lifecycle services (get_state)"
    else:
        return lifecycle_findings(look.states, look.checked)
    return []


def _diagnostics(look: _Gathered) -> list[Finding]:
    board = look.keeper.board if look.keeper is not None else StatusBoard()
    for topic in DIAGNOSTICS_TOPICS:
        if topic in look.heard:
            for at, msg in zip(look.heard[topic].times, look.heard[topic].messages, strict=True):
                board.add_message(msg, topic, time.time() - (time.monotonic() - at))
    if not any(t in look.topics for t in DIAGNOSTICS_TOPICS):
        look.unavailable["diagnostics"] = "the robot has no /diagnostics topic"
        return []
    return status_findings(board, look.checked, look.left_out)


def _streams(look: _Gathered) -> list[Finding]:
    return stream_findings(
        look.keeper,
        streams=look.streams,
        heard=look.heard,
        pubsub=look.pubsub,
        window=look.window,
        checked=look.checked,
    )


def _tf(look: _Gathered) -> list[Finding]:
    if not look.tf_spaces and look.namespace:
        look.unavailable["tf"] = f"the robot has no {look.namespace}/tf or {look.namespace}/tf_static topic"
        return []
    if not look.tf_spaces:
        look.unavailable["tf"] = "the robot has no /tf or /tf_static topic, at the root or under a namespace"
        return []
    findings: list[Finding] = []
    look.frames = tf_trees(
        look.heard,
        topics=look.topics,
        namespaces=look.tf_spaces,
        window=look.window,
        checked=look.checked,
        findings=findings,
    )
    return findings


def _logs(look: _Gathered) -> list[Finding]:
    keeper = look.keeper
    if keeper is None or keeper.absent:
        look.unavailable["logs"] = "the robot has no /rosout topic"
    elif keeper.source is None:
        look.unavailable["logs"] = (
            "the log subscription is not open yet (the server connects in the background)"
        )
    else:
        return log_findings(keeper, look.checked, look.left_out)
    return []


def _arm(look: _Gathered) -> list[Finding]:
    return arm_findings(look.arm, look.heard, look.checked, look.unavailable, asked=look.asked)


#: Each area's judgement, run in the order of :data:`AREAS` (the graph's first: it updates the nodes seen).
_JUDGES: Final[dict[str, Callable[[_Gathered], list[Finding]]]] = {
    "graph": _graph,
    "lifecycle": _lifecycle,
    "diagnostics": _diagnostics,
    "streams": _streams,
    "tf": _tf,
    "logs": _logs,
    "arm": _arm,
}
