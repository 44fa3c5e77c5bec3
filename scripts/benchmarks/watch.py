"""Item 9: the watch tools against the raw socket, a publish stream as received, tools/list sizes."""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import json
import math
import statistics
import time
from typing import Any

from websockets.asyncio.client import connect

from benchmarks.harness import (
    CAMERA_SIZE,
    CAMERA_TOPIC,
    CHATTER,
    CMD_VEL,
    FULL_HD,
    Context,
    Metronome,
    RawBridge,
    Row,
    Served,
    ms,
    our_server_command,
    phase_locked,
    ratio_row,
    raw_first_message,
    serve_mcp,
    simulated_robot,
    verdict,
)

__all__: list[str] = []


async def measure_watch(ctx: Context) -> list[Row]:
    """Item 9: the watch tools against the raw socket, a publish stream as received, tools/list sizes."""
    trials = 20 if ctx.plan.name == "full" else 3
    rows: list[Row] = []
    camera_type = ctx.bridge.topics.get(CAMERA_TOPIC)
    async with contextlib.AsyncExitStack() as stack:
        if camera_type is None:
            rows.append(Row("9a", f"`get_image` {CAMERA_TOPIC}", verdict=f"n/a (no {CAMERA_TOPIC})"))
        else:
            size = CAMERA_SIZE.replace("x", "×") if ctx.bridge.simulated else "the bridge's"
            rows.append(
                await _image_row(
                    ctx,
                    stack,
                    item="9a",
                    served=ctx.ours,
                    url=ctx.bridge.url,
                    camera_type=camera_type,
                    size=size,
                    trials=trials,
                )
            )
        if ctx.bridge.simulated:
            url = await stack.enter_async_context(simulated_robot(ctx.errlog, camera_size=FULL_HD))
            hd = await stack.enter_async_context(serve_mcp(our_server_command(url), ctx.errlog))
            rows.append(
                await _image_row(
                    ctx,
                    stack,
                    item="9b",
                    served=hd,
                    url=url,
                    camera_type=camera_type or "sensor_msgs/msg/Image",
                    size="1920×1080",
                    trials=trials,
                )
            )
        else:
            rows.append(
                Row("9b", "`get_image` on a 1920×1080 rgb8 camera", verdict="n/a (simulated robot only)")
            )
    chatter_type = ctx.bridge.topics.get(CHATTER)
    if chatter_type is None:
        rows.append(Row("9c", f"`subscribe_topic` {CHATTER}", verdict=f"n/a (no {CHATTER})"))
    else:
        async with (
            connect(ctx.bridge.url, max_size=None, compression=None) as ws,
            Metronome(ws, CHATTER, chatter_type) as metronome,
        ):
            arguments = {"topic": CHATTER}
            stats = await phase_locked(
                metronome,
                trials,
                {
                    "raw": lambda: raw_first_message(ctx.raw, CHATTER, chatter_type),
                    "tool": lambda: ctx.ours.tool("subscribe_topic", arguments),
                },
            )
        rows.append(
            ratio_row("9c", f"`subscribe_topic` {CHATTER} count 1 (10 Hz)", stats["tool"], stats["raw"], 1.2)
        )
    rows.append(await _stream_row(ctx))
    rows += await _tools_list_rows(ctx)
    return rows


async def _image_row(
    ctx: Context,
    stack: contextlib.AsyncExitStack,
    *,
    item: str,
    served: Served,
    url: str,
    camera_type: str,
    size: str,
    trials: int,
) -> Row:
    ws = await stack.enter_async_context(connect(url, max_size=None, compression=None))
    raw = RawBridge(await stack.enter_async_context(connect(url, max_size=None, compression=None)))
    arguments = {"topic": CAMERA_TOPIC, "timeout": 10}
    async with Metronome(ws, CAMERA_TOPIC, camera_type) as metronome:
        stats = await phase_locked(
            metronome,
            trials,
            {
                "raw": lambda: raw_first_message(raw, CAMERA_TOPIC, camera_type),
                "tool": lambda: served.tool("get_image", arguments),
            },
        )
    return ratio_row(
        item, f"`get_image` {CAMERA_TOPIC} {size} rgb8 → JPEG 800 px", stats["tool"], stats["raw"], 1.3
    )


async def _stream_row(ctx: Context) -> Row:
    """A 10 Hz publish_topic stream as a raw subscriber on the robot side receives it."""
    rate, duration = 10, 5.0 if ctx.plan.name == "full" else 1.0
    expected = round(rate * duration)
    what = f"`publish_topic` {CMD_VEL} at {rate} Hz for {duration:g} s, as received"
    twist_type = ctx.bridge.topics.get(CMD_VEL)
    if twist_type is None:
        return Row("9d", what, verdict=f"n/a (no {CMD_VEL})")
    arrivals: list[tuple[float, dict[str, Any]]] = []
    stopped = asyncio.Event()
    async with connect(ctx.bridge.url, max_size=None, compression=None) as ws:
        await ws.send(json.dumps({"op": "subscribe", "id": "stream", "topic": CMD_VEL, "type": twist_type}))

        async def listen() -> None:
            async for frame in ws:
                message = json.loads(frame)
                if message.get("op") == "publish":
                    arrivals.append((time.perf_counter(), message["msg"]))
                    if message["msg"]["linear"]["x"] == 0:
                        stopped.set()

        listener = asyncio.create_task(listen())
        await asyncio.sleep(0.3)  # the subscription reaches the bridge before the stream starts
        await ctx.ours.tool(
            "publish_topic",
            {
                "topic": CMD_VEL,
                "message_type": twist_type,
                "message": {"linear": {"x": 0.1}},
                "rate_hz": rate,
                "duration": duration,
            },
        )
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(stopped.wait(), 2)
        listener.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await listener
    moving = [at for at, message in arrivals if message["linear"]["x"] != 0]
    zero = bool(arrivals) and arrivals[-1][1]["linear"]["x"] == 0
    errors = sorted(abs((later - earlier) - 1 / rate) for earlier, later in itertools.pairwise(moving))
    p99 = errors[max(0, math.ceil(0.99 * len(errors)) - 1)] if errors else float("inf")
    met = abs(len(moving) - expected) <= 1 and p99 <= 0.010 and zero
    return Row(
        "9d",
        what,
        n=len(moving),
        median=ms(statistics.median(errors)) if errors else "",
        p90=ms(errors[max(0, math.ceil(0.9 * len(errors)) - 1)]) if errors else "",
        versus=f"{len(moving)} received (+{'1 zero' if zero else 'no zero'}); interval error p99 {ms(p99)}",
        target=f"{expected} ± 1, p99 interval error ≤ 10 ms",
        verdict=verdict(met),
        figures={"received": len(moving), "zero": zero, "p99_interval_error_s": p99},
    )


async def _tools_list_rows(ctx: Context) -> list[Row]:
    """The size of tools/list (compact JSON, what a host pays per session): all tools, the first eight."""
    sizes: dict[str, int] = {}
    for spec in ("all", "original"):
        command = [*our_server_command(ctx.bridge.url), "--tools", spec]
        async with serve_mcp(command, ctx.errlog) as served:
            dumped = [
                tool.model_dump(mode="json", by_alias=True, exclude_none=True)
                for tool in served.tools.values()
            ]
            sizes[spec] = len(json.dumps(dumped, separators=(",", ":")))
            count = len(served.tools)
        sizes[f"{spec}_count"] = count
    return [
        Row(
            "9e",
            f"`tools/list` size, all {sizes['all_count']} tools",
            versus=f"{sizes['all'] / sizes['original']:.2f}× the original eight",
            median=f"{sizes['all']} B",
            target=f"≤ {sizes['all_count'] * 1_000:,} B, 1 KB a tool (a test holds it)".replace(",", " "),
            verdict=verdict(sizes["all"] <= sizes["all_count"] * 1_000),
            figures={"bytes": sizes["all"]},
        ),
        Row(
            "9f",
            f"`tools/list` size, --tools original ({sizes['original_count']} tools)",
            median=f"{sizes['original']} B",
            target="≤ 9 216 B (a test holds it)",
            verdict=verdict(sizes["original"] <= 9_216),
            figures={"bytes": sizes["original"]},
        ),
    ]
