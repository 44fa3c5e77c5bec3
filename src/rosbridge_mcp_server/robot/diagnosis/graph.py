"""The ``graph`` and ``lifecycle`` areas: nodes gone since the last look, a ``cmd_vel`` nobody reads, a key
stream read but not published (:func:`graph_findings`); lifecycle nodes not active (:func:`lifecycle_states`,
:func:`lifecycle_findings`); who publishes and reads a topic (:func:`topic_details`)."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Mapping
from typing import TYPE_CHECKING

from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.diagnosis.findings import Finding, Look, Step, shown_names
from rosbridge_mcp_server.robot.diagnosis.streams import TWISTS, PubSub, others, short_type
from rosbridge_mcp_server.robot.lifecycle import get_state_service, node_state
from rosbridge_mcp_server.robot.text import is_graph_name, shown
from rosbridge_mcp_server.robot.wording import counted

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph
    from rosbridge_mcp_server.robot.log_keeper import LogKeeper

__all__ = ["graph_findings", "lifecycle_findings", "lifecycle_states", "topic_details"]


async def topic_details(
    graph: RosGraph, wanted: list[str]
) -> dict[str, tuple[tuple[str, ...], tuple[str, ...]]]:
    """topic → (its publishers, its subscribers), for the *wanted* topics rosapi could answer for."""
    found = await asyncio.gather(*(graph.topic_details(t) for t in wanted), return_exceptions=True)
    out = {}
    for topic, got in zip(wanted, found, strict=True):
        if not isinstance(got, BaseException):
            out[topic] = (shown_names(got.publishers), shown_names(got.subscribers))
    return out


async def lifecycle_states(
    client: RosbridgeClient, graph: RosGraph, focus_node: str | None, window: float
) -> dict[str, str]:
    """node → its state (``active``, another label, or why it did not answer), for every node offering
    ``get_state`` (only *focus_node*'s when given)."""
    services = await graph.service_names()
    getters = [s for s in services if s.endswith("/get_state") and is_graph_name(s)]
    if focus_node is not None:
        getters = [s for s in getters if s == get_state_service(focus_node)]
    nodes = [s.removesuffix("/get_state") for s in getters]

    async def state(node: str) -> str:
        try:
            found = await node_state(client, node, timeout=window + 1.0)
        except RosbridgeError as exc:
            return f"no answer ({shown(exc, 300)})"
        if found is None:
            return "unknown"
        if found.active:
            return "active"
        return shown(found.label or found.id or "unknown", 60)

    states = await asyncio.gather(*(state(node) for node in nodes))
    return dict(zip(nodes, states, strict=True))


def graph_findings(
    keeper: LogKeeper | None,
    *,
    nodes: list[str],
    topics: Mapping[str, str],
    pubsub: PubSub,
    streams: Mapping[str, str],
    checked: dict[str, str],
) -> list[Finding]:
    out: list[Finding] = []
    now = set(nodes)
    if keeper is not None and keeper.nodes_seen is not None:
        since = time.strftime("%H:%M:%S", time.localtime(keeper.nodes_seen_at or time.time()))
        for node in sorted(keeper.nodes_seen - now):
            out.append(
                Finding(
                    "problem",
                    "graph",
                    node,
                    f"Node {node} is gone: in the graph at {since}, not now (crashed? stopped?).",
                    (Step(Look.NODE_LOG, (node,), "for its last words"), Step(Look.NODES)),
                    nodes=(node,),
                    details={"seen_at": since},
                )
            )
        keeper.nodes_seen, keeper.nodes_seen_at = now, time.time()
    for topic, (pubs, subs) in pubsub.items():
        if topic.rsplit("/", 1)[-1] == "cmd_vel" and short_type(topics.get(topic, "")) in TWISTS:
            if not others(subs):
                out.append(
                    Finding(
                        "problem",
                        "graph",
                        topic,
                        f"Nothing reads {topic}: no node would drive the robot (is the base driver or "
                        "twist_mux running?).",
                        (Step(Look.TOPIC, (topic,)),),
                        nodes=others(pubs),
                    )
                )
        elif topic in streams and not others(pubs) and others(subs):
            readers = others(subs)
            out.append(
                Finding(
                    "problem",
                    "graph",
                    topic,
                    f"Nobody publishes {topic}, which {', '.join(readers[:4])} read.",
                    (Step(Look.TOPIC, (topic,)), Step(Look.NODES)),
                    nodes=readers,
                )
            )
    checked["graph"] = f"{counted(len(nodes), 'node')}, {counted(len(topics), 'topic')}"
    return out


def lifecycle_findings(states: Mapping[str, str], checked: dict[str, str]) -> list[Finding]:
    out = []
    for node, state in sorted(states.items()):
        if state == "active":
            continue
        summary = (
            f"Lifecycle node {node} did not answer get_state: {state.removeprefix('no answer (')[:-1]}"
            if state.startswith("no answer (")
            else f"Lifecycle node {node} is {state}, not active: it does none of its work."
        )
        out.append(
            Finding(
                "problem",
                "lifecycle",
                node,
                summary,
                (Step(Look.NODE_LOG, (node,), "for why"), Step(Look.ACTIVATE)),
                nodes=(node,),
                details={"state": state},
            )
        )
    active = sum(1 for s in states.values() if s == "active")
    checked["lifecycle"] = f"{active} of {len(states)} lifecycle nodes active"
    return out
