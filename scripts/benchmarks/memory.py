"""Item 7: RSS growth over many tool calls, against the bare server's over as many ``tools/list``."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Awaitable, Callable

from benchmarks.harness import (
    MIB,
    Context,
    Row,
    Served,
    bare_server_command,
    mib,
    our_server_command,
    serve_mcp,
    verdict,
)

__all__: list[str] = []


async def churn(served: Served, calls: int, batch: int, call: Callable[[], Awaitable[object]]) -> list[int]:
    """Make ``calls`` requests, ``batch`` at a time; RSS at the start, halfway and at the end."""
    marks = [served.rss()]
    done = 0
    for checkpoint in (calls // 2, calls):
        while done < checkpoint:
            size = min(batch, checkpoint - done)
            await asyncio.gather(*(call() for _ in range(size)))
            done += size
        marks.append(served.rss())
    return marks


async def measure_memory(ctx: Context) -> list[Row]:
    """Item 7: RSS growth over N cheap requests: ours (``list_topics``), the bare server (``tools/list``)."""
    calls, batch = ctx.plan.memory_calls, ctx.plan.memory_batch
    async with serve_mcp(bare_server_command(), ctx.errlog) as bare:
        began = time.perf_counter()
        bare_marks = await churn(bare, calls, batch, bare.session.list_tools)
        bare_elapsed = time.perf_counter() - began
    async with serve_mcp(our_server_command(ctx.bridge.url), ctx.errlog) as ours:
        began = time.perf_counter()
        our_marks = await churn(ours, calls, batch, lambda: ours.tool("list_topics", {}))
        our_elapsed = time.perf_counter() - began
    ctx.samples["memory_rss_bare"] = [float(mark) for mark in bare_marks]
    ctx.samples["memory_rss_ours"] = [float(mark) for mark in our_marks]
    # Growth in the second half is the leak signal; the first half also holds one-off warm-up (caches).
    noise = max(bare_marks[2] - bare_marks[1], 0) + 1 * MIB
    late_growth = our_marks[2] - our_marks[1]

    def growth(marks: list[int]) -> str:
        return f"{(marks[2] - marks[0]) / MIB:+.1f} MiB (second half {(marks[2] - marks[1]) / MIB:+.1f})"

    return [
        Row(
            "7·",
            f"bare `MCPServer`: RSS after {calls} `tools/list`, {batch} at a time",
            n=calls,
            median=mib(bare_marks[2]),
            versus=f"{growth(bare_marks)}; {calls / bare_elapsed:.0f} calls/s",
            verdict="info",
            figures={"rss_bytes": bare_marks, "elapsed_s": bare_elapsed},
        ),
        Row(
            "7b",
            f"`rosbridge-mcp-server`: RSS after {calls} `list_topics`, {batch} at a time",
            n=calls,
            median=mib(our_marks[2]),
            versus=f"{growth(our_marks)}; {calls / our_elapsed:.0f} calls/s",
            target="second-half growth ≤ bare's + 1 MiB",
            verdict=verdict(late_growth <= noise),
            figures={"rss_bytes": our_marks, "elapsed_s": our_elapsed},
        ),
    ]
