"""Item 17: ``tasks/get`` on a running MCP task, against the no-op tool call.

The console script is started as a 2026-07-28 host with the tasks extension starts it (the SDK's ``Client``
over stdio, advertising ``io.modelcontextprotocol/tasks``); a ``subscribe_topic`` on a quiet topic of the
benchmark's own with a duration runs as a task for the whole measurement, and ``tasks/get`` on it is timed
interleaved with the bare server's no-op tool (item 1-3's reference). Target: p50 ≤ +1.5 ms over the no-op.
"""

from __future__ import annotations

import contextlib
from typing import Any, Literal

from mcp.client.extension import ClaimContext, ClientExtension, ResultClaim
from mcp.client.stdio import StdioServerParameters
from mcp.types import (
    CallToolResult,
    CancelTaskRequest,
    CancelTaskRequestParams,
    GetTaskRequest,
    GetTaskRequestParams,
    Result,
)
from pydantic import ConfigDict, TypeAdapter

from benchmarks.harness import (
    REPO,
    Context,
    Row,
    Subject,
    interleave,
    our_server_command,
    timing_row,
    verdict,
)
from mcp import Client

__all__ = ["measure_tasks"]

QUIET = "/bench/tasks_quiet"
TARGET_S = 1.5e-3
_ANY = TypeAdapter(dict[str, Any])


class _Created(Result):
    model_config = ConfigDict(extra="allow")
    result_type: Literal["task"] = "task"
    task_id: str


class _Tasks(ClientExtension):
    identifier = "io.modelcontextprotocol/tasks"

    def claims(self) -> list[ResultClaim[Any]]:
        async def resolve(created: _Created, ctx: ClaimContext) -> CallToolResult:
            raise RuntimeError("the benchmark follows its task itself")

        return [ResultClaim(result_type="task", model=_Created, resolve=resolve)]


async def measure_tasks(ctx: Context) -> list[Row]:
    command = our_server_command(ctx.bridge.url)
    params = StdioServerParameters(command=command[0], args=command[1:], cwd=str(REPO))
    async with Client(params, mode="auto", extensions=[_Tasks()]) as client:
        arguments = {"topic": QUIET, "message_type": "std_msgs/msg/String", "duration": 60, "timeout": 60}
        created = await client.session.call_tool("subscribe_topic", arguments, allow_claimed=True)
        if not isinstance(created, _Created):
            return [
                Row("17", "tasks/get on a running task", verdict="**error**: the call was not made a task")
            ]
        get = GetTaskRequest(params=GetTaskRequestParams(task_id=created.task_id))

        async def get_task() -> None:
            await client.session.send_request(get, _ANY)

        noop = ctx.reference
        subjects = [
            Subject("tasks_get", get_task),
            Subject("noop_for_tasks", lambda: noop.tool("noop", {}), noop.process),
        ]
        try:
            await interleave(subjects, ctx.plan, ctx.bridge_process)
            status = (await client.session.send_request(get, _ANY)).get("status")
        finally:
            cancel = CancelTaskRequest(params=CancelTaskRequestParams(task_id=created.task_id))
            with contextlib.suppress(Exception):
                await client.session.send_request(cancel, _ANY)
    by_key = {subject.key: subject.stats for subject in subjects}
    got, reference = by_key["tasks_get"], by_key["noop_for_tasks"]
    over = got.median - reference.median
    row = timing_row(
        "17",
        f"`tasks/get` on a running task (still {status} at the end)",
        got,
        versus=f"{over * 1e3:+.2f} ms over the no-op tool (p50 {reference.median * 1e3:.2f} ms)",
        target="≤ +1.5 ms over the no-op",
        verdict=verdict(over <= TARGET_S and status == "working"),
    )
    row.figures["over_noop_s"] = over
    return [row]
