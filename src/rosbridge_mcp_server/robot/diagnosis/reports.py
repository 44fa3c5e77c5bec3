"""What the robot reports of itself: the ``diagnostics`` area (the latest status per name, ERROR a problem,
WARN and STALE warnings: :func:`status_findings`) and the ``logs`` area (errors and warnings since the server
connected, folded: :func:`log_findings`)."""

from __future__ import annotations

import time
from collections import Counter
from typing import TYPE_CHECKING, Literal

from rosbridge_mcp_server.robot.diagnosis.findings import (
    MAX_LOG_FINDINGS,
    MAX_STATUS_FINDINGS,
    Finding,
    Look,
    Step,
)
from rosbridge_mcp_server.robot.logs import level_rank
from rosbridge_mcp_server.robot.wording import counted

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.diagnostics import StatusBoard
    from rosbridge_mcp_server.robot.log_keeper import LogKeeper

__all__ = ["log_findings", "status_findings"]


def status_findings(board: StatusBoard, checked: dict[str, str], left_out: dict[str, int]) -> list[Finding]:
    out = []
    statuses = board.statuses()
    not_ok = [s for s in statuses if s.level != 0]
    on_topic = Counter(s.topic for s in statuses)
    for status in not_ok[:MAX_STATUS_FINDINGS]:
        severity: Literal["problem", "warning"] = "problem" if status.level == 2 else "warning"
        hardware = f" ({status.hardware_id})" if status.hardware_id else ""
        values = ", ".join(f"{k}: {v}" for k, v in status.values[:3])
        ago = max(0.0, time.time() - status.received)
        out.append(
            Finding(
                severity,
                "diagnostics",
                status.name,
                f"{status.level_name} {status.name}{hardware}: {status.message or '(no message)'}"
                + (f" [{values}]" if values else "")
                + f" ({ago:.0f} s ago)",
                (Step(Look.STATUSES, (status.topic, str(on_topic[status.topic]))),),
                nodes=(_status_node(status.name),),
                details={
                    "level": status.level_name,
                    "hardware_id": status.hardware_id,
                    "message": status.message,
                    "values": dict(status.values),
                },
            )
        )
    if statuses:
        ok = len(statuses) - len(not_ok)
        more = len(not_ok) - MAX_STATUS_FINDINGS
        checked["diagnostics"] = f"{counted(len(statuses), 'status', 'statuses')}, {ok} OK"
        if more > 0:
            left_out["diagnostics"] = more
    else:
        checked["diagnostics"] = "no status has arrived yet"
    return out


def _status_node(name: str) -> str:
    """diagnostic_updater names a status ``node: task``: the node, for a focus on it."""
    node = name.split(":", 1)[0].strip()
    return node if node.startswith("/") else f"/{node}"


def log_findings(keeper: LogKeeper, checked: dict[str, str], left_out: dict[str, int]) -> list[Finding]:
    out = []
    now = time.time()
    folds = keeper.ring.tally.folds()
    for entry in folds[:MAX_LOG_FINDINGS]:
        severity: Literal["problem", "warning"] = (
            "problem" if level_rank(entry.level) >= level_rank("error") else "warning"
        )
        out.append(
            Finding(
                severity,
                "logs",
                entry.node,
                entry.describe(now),
                (Step(Look.NODE_LOG, (entry.node,)),),
                nodes=(entry.node,),
                details={"level": entry.level, "count": entry.count, "text": entry.text},
            )
        )
    since = time.strftime("%H:%M:%S", time.localtime(keeper.listening_since or now))
    errors = sum(f.count for f in folds if level_rank(f.level) >= level_rank("error"))
    warnings = sum(f.count for f in folds if f.level == "warn")
    if len(folds) > MAX_LOG_FINDINGS:
        left_out["logs"] = len(folds) - MAX_LOG_FINDINGS
    checked["logs"] = (
        f"{counted(errors, 'error')}, {counted(warnings, 'warning')} since {since} "
        f"({counted(len(keeper.ring), 'line')} kept)"
    )
    return out
