"""Item 4: N slow tool calls at once in one session against N in a row, with the layers below."""

from __future__ import annotations

import asyncio

from benchmarks.harness import (
    SLOW_SERVICE,
    SLOW_SERVICE_SECONDS,
    Context,
    Row,
    Stats,
    ms,
    publish_service_arguments,
    timing_row,
    verdict,
    wall_time,
)

__all__: list[str] = []


async def measure_concurrency(ctx: Context) -> list[Row]:
    """Item 4: N slow tool calls at once in one session vs N in a row, with the layers below as references."""
    slow_type = ctx.bridge.services.get(SLOW_SERVICE)
    if slow_type is None:
        return [Row("4", f"{ctx.plan.parallel_calls} tool calls at once", verdict=f"n/a (no {SLOW_SERVICE})")]
    n, ours, raw, client, sdk = ctx.plan.parallel_calls, ctx.ours, ctx.raw, ctx.client, ctx.reference
    arguments = publish_service_arguments(ours, SLOW_SERVICE, slow_type, {})
    sleep_arguments = {"seconds": SLOW_SERVICE_SECONDS}

    async def tools_at_once() -> None:
        await asyncio.gather(*(ours.tool("publish_service", arguments) for _ in range(n)))

    async def tools_in_a_row() -> None:
        for _ in range(n):
            await ours.tool("publish_service", arguments)

    async def client_at_once() -> None:
        await asyncio.gather(*(client.call_service(SLOW_SERVICE) for _ in range(n)))

    async def sdk_at_once() -> None:
        await asyncio.gather(*(sdk.tool("sleep", sleep_arguments) for _ in range(n)))

    # One of each first, so lanes, imports and caches are warm.
    await ours.tool("publish_service", arguments)
    await client.call_service(SLOW_SERVICE)
    await sdk.tool("sleep", sleep_arguments)
    samples: dict[str, list[float]] = {"raw": [], "client": [], "sdk": [], "parallel": [], "sequential": []}
    for _ in range(ctx.plan.concurrency_rounds):
        samples["raw"].append(await wall_time(lambda: raw.call_parallel(SLOW_SERVICE, n)))
        samples["client"].append(await wall_time(client_at_once))
        samples["sdk"].append(await wall_time(sdk_at_once))
        samples["parallel"].append(await wall_time(tools_at_once))
        samples["sequential"].append(await wall_time(tools_in_a_row))
    ctx.samples.update({f"concurrency_{key}": values for key, values in samples.items()})
    stats = {key: Stats.of(values) for key, values in samples.items()}
    ideal = SLOW_SERVICE_SECONDS
    parallel, sequential = stats["parallel"], stats["sequential"]
    speedup = sequential.median / parallel.median
    sdk_speedup = n * ideal / stats["sdk"].median
    row = timing_row(
        "4a",
        f"{n} × `publish_service {SLOW_SERVICE}` ({ideal * 1e3:.0f} ms) at once, one session",
        parallel,
        versus=f"{speedup:.1f}× faster than in a row",
        target="≥ 20× faster",
        # Fewer calls than 100 cap the speed-up below 20× however fast the server is.
        verdict=verdict(speedup >= 20) if n >= 100 else f"n/a ({n} calls)",
    )
    row.figures["speedup"] = speedup
    return [
        row,
        timing_row("4b", f"{n} × the same, in a row", sequential, versus=f"ideal {ms(n * ideal)}"),
        timing_row(
            "4·",
            f"floor: {n} raw `call_service {SLOW_SERVICE}` at once, one socket",
            stats["raw"],
            verdict="info",
        ),
        timing_row(
            "4·", f"our client: {n} `call_service {SLOW_SERVICE}` at once", stats["client"], verdict="info"
        ),
        timing_row(
            "4·",
            f"SDK reference: {n} × a `sleep({ideal:g})` tool at once, bare `MCPServer`, our stdio",
            stats["sdk"],
            versus=f"{sdk_speedup:.1f}× faster than {n}×{ideal * 1e3:.0f} ms",
            verdict="info",
        ),
    ]
