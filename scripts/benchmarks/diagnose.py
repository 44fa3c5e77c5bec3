"""Item 13: ``diagnose`` on the simulated Nav2 world, and the log ring under a flood of /rosout lines."""

from __future__ import annotations

import asyncio
import contextlib
import json
import time
from typing import Any

from websockets.asyncio.client import connect

from benchmarks.harness import (
    MIB,
    Context,
    Row,
    Stats,
    our_server_command,
    raw_pipe_client,
    serve_mcp,
    simulated_robot,
    timing_row,
    verdict,
)

__all__: list[str] = []

DIAGNOSE_TARGET = 1.5
#: A look that finds a silent stream hears it for AGAIN (1 s) more before naming it (robot/diagnosis/).
SILENT_TARGET = 2.5
LOG_FLOOD_RATE = 10_000
LOG_FLOOD_SECONDS = 10


async def measure_diagnose(ctx: Context) -> list[Row]:
    """Item 13: ``diagnose`` on the simulated Nav2 world (healthy, then scan-stopped + log-errors), its p50
    against 1.5 s (2.5 s with a silent stream, heard again before it is named); the log ring under a flood of
    /rosout lines."""
    rows: list[Row] = []
    full = ctx.plan.name == "full"
    calls = 10 if full else 2
    cases = (
        (("13a", "", DIAGNOSE_TARGET), ("13b", "scan-stopped,log-errors", SILENT_TARGET))
        if full
        else (("13a", "", DIAGNOSE_TARGET),)
    )
    for item, faults, target in cases:
        async with contextlib.AsyncExitStack() as stack:
            url = await stack.enter_async_context(simulated_robot(ctx.errlog, world="nav2", faults=faults))
            ours = await stack.enter_async_context(raw_pipe_client(our_server_command(url), ctx.errlog, {}))
            answer = await ours.tool("diagnose", {})  # the first look also waits for the connection
            samples = []
            for _ in range(calls):
                began = time.perf_counter()
                answer = await ours.tool("diagnose", {})
                samples.append(time.perf_counter() - began)
            text = answer["result"]["content"][0]["text"]
            stats = Stats.of(samples)
            what = "healthy" if not faults else f"--fault {faults}"
            row = timing_row(
                item,
                f"`diagnose` on the Nav2 world, {what}: {text.splitlines()[0]}",
                stats,
                target=f"p50 ≤ {target:g} s",
            )
            row.verdict = verdict(stats.median <= target)
            row.figures.update(first_line=text.splitlines()[0], text_chars=len(text))
            rows.append(row)
    rows.append(await _log_flood_row(ctx))
    return rows


#: The lines the server's log ring keeps (``read_logs``' description says it: "5,000 lines").
RING_LINES = 5_000
LOG_TYPE = "rcl_interfaces/msg/Log"
#: The flood checks every FLOW_TICKS ticks of 10 ms that the server is at most FLOW_WINDOW lines behind: with
#: the lines sent until the next check, fewer than the simulated bridge's 1,000 queued for one subscriber.
FLOW_TICKS = 5
FLOW_WINDOW = 400


async def _log_flood_row(ctx: Context) -> Row:
    """10,000 /rosout lines a second for 10 s (quick: 1 s), published by a raw socket on a simulated robot of
    their own, into our server's log ring: every line received, the ring holding exactly the newest it keeps
    (read back with ``read_logs``), and the server's RSS sampled every half second."""
    seconds = LOG_FLOOD_SECONDS if ctx.plan.name == "full" else 1
    rss: list[float] = []
    async with contextlib.AsyncExitStack() as stack:
        url = await stack.enter_async_context(simulated_robot(ctx.errlog))
        served = await stack.enter_async_context(serve_mcp(our_server_command(url), ctx.errlog))
        publisher = await stack.enter_async_context(connect(url, max_size=None, compression=None))

        async def logs(**arguments: Any) -> dict[str, Any]:
            result = await served.tool("read_logs", {"level": "debug", "limit": 1, **arguments})
            return result.structured_content or {}

        def total(answer: dict[str, Any]) -> int:
            return int(answer.get("lines", 0)) + int(answer.get("dropped", 0))

        before = total(await logs())  # also starts the server's log keeper and waits for it
        await publisher.send(
            json.dumps({"op": "advertise", "id": "flood", "topic": "/rosout", "type": LOG_TYPE})
        )

        async def sample() -> None:
            while True:
                rss.append(served.rss())
                await asyncio.sleep(0.5)

        sampler = asyncio.create_task(sample())
        began = time.monotonic()
        sent = 0
        per_tick = LOG_FLOOD_RATE // 100
        for tick in range(seconds * 100):
            await asyncio.sleep(max(0.0, began + tick / 100 - time.monotonic()))
            if tick % FLOW_TICKS == 0:
                # The simulated bridge, as rosbridge, drops a subscriber's oldest messages beyond a queue of
                # 1,000: the flood waits while the server is that far behind, so what is lost is the server's.
                # (In the benchmark's own process, as before, the flood could not outrun the reader either.)
                while sent - (total(await logs()) - before) > FLOW_WINDOW:  # noqa: ASYNC110
                    await asyncio.sleep(0.01)
            for _ in range(per_tick):
                sent += 1
                line = {"level": 30, "name": "flood", "msg": f"line {sent:07d}.", "file": "", "function": ""}
                await publisher.send(json.dumps({"op": "publish", "topic": "/rosout", "msg": line}))
        sent_in = time.monotonic() - began
        deadline = time.monotonic() + 120
        # The ring has no event a client can wait on; a bounded poll of read_logs reads it.
        while total(await logs()) - before < sent and time.monotonic() < deadline:  # noqa: ASYNC110
            await asyncio.sleep(0.25)
        received_in = time.monotonic() - began
        sampler.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await sampler
        received = total(await logs()) - before
        flood = await logs(node="/flood")
        oldest = sent - RING_LINES + 1
        # Exactly the newest RING_LINES in order: all of them /flood's, the newest last, the oldest kept there
        # and the one before it gone.
        groups = flood.get("groups", [])
        exact = (
            flood.get("lines") == RING_LINES
            and len(groups) == 1
            and groups[0]["text"] == f"line {sent:07d}."
            and (await logs(text=f"line {oldest:07d}.")).get("lines") == 1
            and (await logs(text=f"line {oldest - 1:07d}.")).get("lines") == 0
        )
        kept = int(flood.get("lines", 0))
        await publisher.send(json.dumps({"op": "unadvertise", "id": "flood", "topic": "/rosout"}))
    settled = rss[len(rss) // 4 :] or rss
    growth = (max(settled) - min(settled)) / MIB
    row = Row(
        "13c",
        f"log ring: {LOG_FLOOD_RATE:,} /rosout lines/s for {seconds} s ({sent:,} sent in {sent_in:.1f} s, "
        f"received by {received_in:.1f} s), the server's RSS",
        n=sent,
        median=f"{received:,} received",
        p90=f"{kept:,} kept",
        versus=f"RSS {min(rss) / MIB:.0f}-{max(rss) / MIB:.0f} MiB, {growth:+.1f} MiB after the ring filled",
        target="nothing lost; the newest 5,000 kept in order; RSS flat (≤ 8 MiB)",
    )
    row.verdict = verdict(received == sent and exact and growth <= 8)
    row.figures.update(sent=sent, received=received, kept=kept, exact=exact, rss_growth_mib=growth)
    return row
