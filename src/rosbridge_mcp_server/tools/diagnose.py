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
    Diagnosis,
    Finding,
    Look,
    Step,
    UnknownFocusError,
    diagnose,
)
from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolFailure, ToolSpec
from rosbridge_mcp_server.tools.paging import FRAME_RESERVE, TEXT_BUDGET

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
    output=DiagnoseAnswer,
)


async def run(
    ctx: ToolContext,
    focus: Annotated[
        str | None,
        Field(description=f"An area ({', '.join(list(FOCUSES)[:3])}, ...) or a node, e.g. /amcl"),
    ] = None,
) -> ToolAnswer:
    """Look at the robot once."""
    keeper = ctx.robot.keep_logs()
    if not keeper.ready.is_set():
        # Just connected: the log subscription is being opened in the background.
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(keeper.ready.wait(), READY_WAIT)
    try:
        found = await diagnose(ctx.client, ctx.graph, keeper, focus=focus)
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


#: Each thing to look at next as the call that does it (robot/diagnosis.py names no tool).
_CALLS: Final[dict[Look, Callable[..., str]]] = {
    Look.NODE_LOG: lambda node: f'read_logs {{"node": "{node}", "level": "info"}}',
    Look.NODES: lambda: "list_nodes",
    Look.TOPIC: lambda topic: f'get_topic_info {{"topic": "{topic}"}}',
    Look.ACTIVATE: lambda node: (
        f'activate it: publish_service {{"service": "{node}/change_state", "request": '
        '{"transition": {"id": 3}}} (or its lifecycle manager\'s manage_nodes)'
    ),
    Look.NODE: lambda node=None: "get_node_info" if node is None else f'get_node_info {{"node": "{node}"}}',
    Look.ONE_MESSAGE: lambda topic: f'subscribe_topic {{"topic": "{topic}", "count": 1}}',
    Look.WAIT_MESSAGE: lambda topic: f'subscribe_topic {{"topic": "{topic}", "timeout": 5}}',
    Look.STAMPS: lambda topic: f'plot_topic {{"series": ["{topic} header.stamp.sec"], "duration": 5}}',
    Look.TRANSFORM: lambda target, source: (
        f'get_transform {{"target_frame": "{target}", "source_frame": "{source}"}}'
    ),
    Look.TRANSFORM_WAIT: lambda target, source: (
        f'get_transform {{"target_frame": "{target}", "source_frame": "{source}", "timeout": 5}}'
    ),
    Look.ARM: lambda: "view_arm",
    Look.ACTIVATE_CONTROLLER: lambda manager, controller: (
        f'activate it: publish_service {{"service": "{manager}/switch_controller", "service_type": '
        '"controller_manager_msgs/srv/SwitchController", "request": '
        f'{{"activate_controllers": ["{controller}"], "strictness": 2}}}} (if the hardware allows)'
    ),
}


def next_text(steps: Sequence[Step]) -> str:
    """What to look at next, as calls: ``read_logs {"node": "/amcl", "level": "info"}; list_nodes``."""
    return "; ".join(_CALLS[step.look](*step.names) + (f" {step.why}" if step.why else "") for step in steps)


def checked_texts(found: Diagnosis) -> dict[str, str]:
    """What each area checked, with where to read what its findings left out."""
    checked = dict(found.checked)
    if more := found.left_out.get("diagnostics"):
        checked["diagnostics"] += f" ({more} more not OK: subscribe_topic /diagnostics)"
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
    if not found.findings:
        return "No problem found"
    parts = []
    if found.problems:
        parts.append(f"{found.problems} problem{'s' if found.problems != 1 else ''}")
    if found.warnings:
        parts.append(f"{found.warnings} warning{'s' if found.warnings != 1 else ''}")
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
    lines.append(f"Checked in {found.seconds:.1f} s — {checked}.")
    if found.unavailable:
        lines.append("Not checked: " + "; ".join(f"{a}: {why}" for a, why in found.unavailable.items()) + ".")
    return "\n".join(lines)
