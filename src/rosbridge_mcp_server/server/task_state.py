"""One task's state as ``server/tasks.py`` keeps it, and how it is shown: ``tasks/get`` in either dialect,
the line a stop or an end leaves, the answer of a task a stop voided."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import TYPE_CHECKING, Any

import anyio

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.gate import SendGate, Ticket

__all__ = ["POLL_MS", "TERMINAL", "TaskState", "ended_text", "voided"]

#: How often a client is asked to poll.
POLL_MS = 500
TERMINAL = frozenset({"completed", "failed", "cancelled"})


@dataclass
class TaskState:
    """A task: what it runs, whose it is, where it is, and its answer once it ended."""

    task_id: str
    tool: str
    caller: str | None
    modern: bool
    created: float = field(default_factory=time.time)
    updated: float = field(default_factory=time.time)
    status: str = "working"
    message: str | None = None
    result: dict[str, Any] | None = None
    error: dict[str, Any] | None = None
    input_requests: dict[str, Any] = field(default_factory=dict)
    answers: dict[str, Any] = field(default_factory=dict)
    answered: anyio.Event = field(default_factory=anyio.Event)
    done: anyio.Event = field(default_factory=anyio.Event)
    scope: anyio.CancelScope | None = None
    ended_at: float | None = None
    ended_wall: float | None = None
    cancelled_by: str | None = None
    #: The send gates of the robots an acting task runs on, with their stop counts when it began.
    gates: list[tuple[SendGate, Ticket]] = field(default_factory=list)

    def stopped_by(self) -> str | None:
        """Who stopped the robot since this task began (``stop_robot``, the console's E-STOP), or ``None``."""
        stopped = [gate.stopped_by for gate, ticket in self.gates if gate.ticket().stops != ticket.stops]
        return stopped[-1] if stopped else None

    def asking(self, question: str | None) -> None:
        """A question sent to the person mid-run (2025-11-25) and, with ``None``, its answer come."""
        if self.status in TERMINAL:
            return
        if question is not None:
            self.change("input_required", question)
        else:
            self.change("working", f"{self.tool}: answered, going on")

    def change(self, status: str, message: str | None) -> None:
        self.status, self.message, self.updated = status, message, time.time()

    def end(self, status: str, message: str | None) -> None:
        self.change(status, message)
        self.input_requests = {}
        self.ended_at = time.monotonic()
        self.ended_wall = time.time()
        self.done.set()

    def view(self, keep: float, *, modern: bool) -> dict[str, Any]:
        """The task as ``tasks/get`` shows it in the caller's dialect."""
        # Kept *keep* seconds after the end: while running, that many from now.
        until = (self.ended_wall if self.ended_wall is not None else time.time()) + keep
        ttl = int((until - self.created) * 1000)
        shown: dict[str, Any] = {
            "taskId": self.task_id,
            "status": self.status,
            "createdAt": iso(self.created),
            "lastUpdatedAt": iso(self.updated),
        }
        if self.message:
            shown["statusMessage"] = self.message
        if not modern:
            return {**shown, "ttl": ttl, "pollInterval": POLL_MS}
        shown.update(ttlMs=ttl, pollIntervalMs=POLL_MS)
        if self.status == "completed" and self.result is not None:
            shown["result"] = self.result
        elif self.status == "failed" and self.error is not None:
            shown["error"] = self.error
        elif self.status == "input_required":
            shown["inputRequests"] = self.input_requests
        return shown


def voided(who: str) -> dict[str, Any]:
    """The answer of a task a stop voided while the person was asked (the send gate's words)."""
    text = (
        f"Stopped: {who} stopped this call before it was sent, so nothing of it went to the robot. Do not "
        "send it again unless the user asks you to."
    )
    return {"content": [{"type": "text", "text": text}], "isError": True}


def ended_text(tool: str, result: Mapping[str, Any], stopped: str | None) -> str:
    """The status line of an ended task: who stopped it, when a stop came during it; its answer's first
    line."""
    first = ""
    for block in result.get("content", []):
        if isinstance(block, Mapping) and block.get("type") == "text":
            first = str(block.get("text", "")).split("\n", 1)[0]
            break
    first = first if len(first) <= 200 else first[:197] + "..."
    if stopped is not None:
        return f"Stopped by {stopped}: {tool} ended. {first}".rstrip()
    failed = " (failed)" if result.get("isError") else ""
    return f"{tool} ended{failed}: {first}".rstrip(": ")


def iso(stamp: float) -> str:
    return datetime.fromtimestamp(stamp, UTC).isoformat().replace("+00:00", "Z")
