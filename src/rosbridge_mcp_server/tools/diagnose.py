"""``diagnose``: what is wrong with the robot, in one call: a count, the findings worst first (each with the
call to make next), and what each area checked."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable, Sequence
from typing import Annotated, Any, Final

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.diagnosis import (
    FOCUSES,
    MAX_STREAMS,
    Diagnosis,
    Finding,
    Look,
    Step,
    UnknownFocusError,
    diagnose,
)
from rosbridge_mcp_server.robot.wording import counted
from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolFailure, ToolSpec
from rosbridge_mcp_server.tools.namespaces import NamespaceArgument, given_namespace
from rosbridge_mcp_server.tools.paging import FRAME_RESERVE, TEXT_BUDGET
from rosbridge_mcp_server.tools.subscribe_topic import MAX_COUNT

__all__ = ["SPEC", "DiagnoseAnswer", "run"]

#: How long a call made just after connecting waits for the log subscription being opened.
READY_WAIT = 1.0


class FindingModel(BaseModel):
    """One thing wrong."""

    severity: str = Field(description="problem or warning")
    area: str = Field(description="graph, lifecycle, diagnostics, streams, tf, logs or arm")
    subject: str = Field(description="The topic, frame pair, node or status it is about")
    summary: str
    next: str = Field(description="What to call next")
    nodes: list[str]
    details: dict[str, Any]


class DiagnoseAnswer(BaseModel):
    """The findings, worst first, and what was checked."""

    problems: int
    warnings: int
    focus: str | None
    findings: list[FindingModel]
    checked: dict[str, str] = Field(description="What each area looked at")
    unavailable: dict[str, str] = Field(description="Areas the robot does not have, and why")
    streams: dict[str, float | None] = Field(
        description="Hz of each key stream in the window (null: <2 messages)"
    )
    frames: list[str] = Field(description="tf frames seen")
    seconds: float = Field(description="How long the look took")


SPEC = ToolSpec(
    name="diagnose",
    title="Diagnose the robot",
    description=(
        "What is wrong, in one ~1.5 s look (diagnostics, logs, rates, tf, lifecycle, graph, arm): each "
        'problem and what to call next. Read-only. Example: {"focus": "navigation"}'
    ),
    hints=READS_ROBOT,
    needs=frozenset({"robot_log"}),
    output=DiagnoseAnswer,
)


async def run(
    ctx: ToolContext,
    focus: Annotated[
        str | None,
        Field(description=f"An area ({', '.join(list(FOCUSES)[:3])}, ...) or a node, e.g. /amcl"),
    ] = None,
    namespace: NamespaceArgument = None,
) -> ToolAnswer:
    """Look at the robot once."""
    keeper = ctx.robot.keep_logs()
    if not keeper.ready.is_set():
        # Just connected: the log subscription is being opened in the background.
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(keeper.ready.wait(), READY_WAIT)
    try:
        found = await diagnose(
            ctx.client, ctx.graph, keeper, focus=focus, namespace=given_namespace(ctx, namespace)
        )
    except UnknownFocusError as exc:
        raise ToolFailure(f"Unknown {exc}").advise(exc.hint) from None
    data = DiagnoseAnswer(
        problems=found.problems,
        warnings=found.warnings,
        focus=focus,
        findings=[_model(f) for f in found.findings],
        checked=checked_texts(found),
        unavailable=found.unavailable,
        streams={t: None if r is None else round(r, 2) for t, r in found.streams.items()},
        frames=found.frames,
        seconds=round(found.seconds, 2),
    )
    return ToolAnswer(text=_text(found, focus), data=data)


#: Each thing to look at next as the call that does it (robot/diagnosis/ names no tool). The names come from
#: the robot, checked in robot/diagnosis/ (graph names it has, plain frame names); no acting call is ever
#: built from them.
_CALLS: Final[dict[Look, Callable[..., str]]] = {
    Look.NODE_LOG: lambda node: f'read_logs {{"node": "{node}", "level": "info"}}',
    Look.NODES: lambda: "list_nodes",
    Look.TOPIC: lambda topic: f'get_topic_info {{"topic": "{topic}"}}',
    Look.LOG: lambda: 'read_logs {"level": "info"}',
    Look.ACTIVATE: lambda: (
        "activating it acts on the robot (its lifecycle manager's manage_nodes, or its change_state service, "
        "transition 3): ask the user first"
    ),
    Look.NODE: lambda node: f'get_node_info {{"node": "{node}"}}',
    Look.ONE_MESSAGE: lambda topic: f'subscribe_topic {{"topic": "{topic}", "count": 1}}',
    Look.WAIT_MESSAGE: lambda topic: f'subscribe_topic {{"topic": "{topic}", "timeout": 5}}',
    Look.STAMPS: lambda topic: f'plot_topic {{"series": ["{topic} header.stamp.sec"], "duration": 5}}',
    Look.TRANSFORM: lambda target, source, namespace="": (
        f'get_transform {{"target_frame": "{target}", "source_frame": "{source}"{_in(namespace)}}}'
    ),
    Look.TRANSFORM_WAIT: lambda target, source, namespace="": (
        f'get_transform {{"target_frame": "{target}", "source_frame": "{source}", "timeout": 5'
        f"{_in(namespace)}}}"
    ),
    # Two rounds of every status in at most 3 s (diagnostics come at about 1 Hz); the topic's publishers
    # take turns, so one message is most likely another's OK.
    Look.STATUSES: lambda topic, statuses: (
        f'subscribe_topic {{"topic": "{topic}", "count": {min(MAX_COUNT, max(2, 2 * int(statuses)))}, '
        '"duration": 3, "fields": ["status"]} (its publishers take turns: one message is likely another\'s)'
    ),
    Look.ARM: lambda: "view_arm",
    Look.ACTIVATE_CONTROLLER: lambda manager, controller: (
        f"activating {controller} acts on the robot ({manager}/switch_controller, activate_controllers "
        "(ROS 1: start_controllers), if the hardware allows): ask the user first"
    ),
}


def _in(namespace: str) -> str:
    """The ``namespace`` argument of a suggested call, when the finding is a namespaced robot's."""
    return f', "namespace": "{namespace}"' if namespace else ""


def next_text(steps: Sequence[Step]) -> str:
    """What to look at next, as calls: ``read_logs {"node": "/amcl", "level": "info"}; list_nodes``.

    A step without names after one with them is about the same node (``Look.NODE`` after ``Look.ACTIVATE``).
    """
    calls = []
    before: tuple[str, ...] = ()
    for step in steps:
        names = before if step.look is Look.NODE and not step.names else step.names
        calls.append(_CALLS[step.look](*names) + (f" {step.why}" if step.why else ""))
        before = step.names
    return "; ".join(calls)


def checked_texts(found: Diagnosis) -> dict[str, str]:
    """What each area checked, with where to read what its findings left out."""
    checked = dict(found.checked)
    if more := found.left_out.get("streams"):
        checked["streams"] += f" ({more} more not measured: at most {MAX_STREAMS} at once)"
    if more := found.left_out.get("diagnostics"):
        every = f'{{"topic": "/diagnostics", "count": {MAX_COUNT}, "duration": 3, "fields": ["status"]}}'
        checked["diagnostics"] += f" ({more} more not OK: subscribe_topic {every})"
    if more := found.left_out.get("logs"):
        # "... (N lines kept)" → "... (N lines kept, M more groups in read_logs)"
        checked["logs"] = f"{checked['logs'].removesuffix(')')}, {more} more groups in read_logs)"
    return checked


def _model(finding: Finding) -> FindingModel:
    return FindingModel(
        severity=finding.severity,
        area=finding.area,
        subject=finding.subject,
        summary=finding.summary,
        next=next_text(finding.next),
        nodes=list(finding.nodes),
        details=finding.details,
    )


def _count(found: Diagnosis) -> str:
    if not found.findings and found.unavailable:
        return f"No problem found in the areas checked (not checked: {', '.join(found.unavailable)})"
    if not found.findings:
        return "No problem found"
    parts = []
    if found.problems:
        parts.append(counted(found.problems, "problem"))
    if found.warnings:
        parts.append(counted(found.warnings, "warning"))
    return ", ".join(parts)


def _text(found: Diagnosis, focus: str | None) -> str:
    head = _count(found) + (f" (focus: {focus})" if focus else "") + (":" if found.findings else ".")
    lines = [head]
    budget = TEXT_BUDGET - FRAME_RESERVE
    used = len(head)
    shown = 0
    for finding in found.findings:
        row = f"{finding.severity.upper()} [{finding.area}] {finding.summary}\n  → {next_text(finding.next)}"
        if shown and used + len(row) + 1 > budget - 600:
            break
        lines.append(row)
        used += len(row) + 1
        shown += 1
    if shown < len(found.findings):
        lines.append(f"{len(found.findings) - shown} more findings in the structured content.")
    checked = "; ".join(f"{area}: {what}" for area, what in checked_texts(found).items())
    lines.append(f"Checked in {found.seconds:.1f} s — {checked or 'nothing'}.")
    if found.unavailable:
        lines.append("Not checked: " + "; ".join(f"{a}: {why}" for a, why in found.unavailable.items()) + ".")
    return "\n".join(lines)
