"""Item 5: the 1 kHz topic raw and through our client, a camera frame as an MCP image, a PNG bomb refused."""

from __future__ import annotations

import base64
import contextlib
import itertools
import struct
import time
import zlib
from collections.abc import Sequence
from typing import Any

import mcp_types
from websockets.asyncio.client import connect

from benchmarks.harness import (
    FAST_TOPIC,
    MIB,
    Context,
    RawBridge,
    Row,
    Stats,
    mib,
    ms,
    peak_reset,
    peak_resettable,
    peak_rss,
    simulated_robot,
    timing_row,
    verdict,
)
from benchmarks.internals import RosbridgeClient

__all__: list[str] = []

# ------------------------------------------------------------------------------------- item 5: throughput


def lost_messages(messages: Sequence[dict[str, Any]]) -> int:
    """Gaps in the fast topic's counter (``data`` counts up by one per message)."""
    counters = [int(message["data"]) for message in messages]
    return sum(max(0, later - earlier - 1) for earlier, later in itertools.pairwise(counters))


async def measure_throughput(ctx: Context) -> list[Row]:
    """Item 5: collect N messages of the 1 kHz topic raw and through our client; count the gaps.

    Against the simulated robot this starts a second one with the 1 kHz topic, and connects to it afresh.
    """
    count = ctx.plan.messages
    async with contextlib.AsyncExitStack() as stack:
        raw, client, fast_type = ctx.raw, ctx.client, ctx.bridge.topics.get(FAST_TOPIC)
        if ctx.bridge.simulated:
            url = await stack.enter_async_context(simulated_robot(ctx.errlog, fast_topic=True))
            raw = RawBridge(await stack.enter_async_context(connect(url, max_size=None, compression=None)))
            client = await stack.enter_async_context(RosbridgeClient(url))
            await client.wait_connected(10)
            fast_type = (await raw.call("/rosapi/topic_type", {"topic": FAST_TOPIC})).get("type") or None
        if fast_type is not None:
            began = time.perf_counter()
            raw_messages = await raw.collect(FAST_TOPIC, fast_type, count)
            raw_elapsed = time.perf_counter() - began
            began = time.perf_counter()
            client_messages: list[dict[str, Any]] = []
            async with client.subscribe(FAST_TOPIC, fast_type) as subscription:
                async for message in subscription:
                    client_messages.append(message)
                    if len(client_messages) >= count:
                        break
            client_elapsed = time.perf_counter() - began
    if fast_type is None:
        rows = [Row("5a", f"{count} messages of {FAST_TOPIC} (1 kHz)", verdict=f"n/a (no {FAST_TOPIC})")]
    else:
        raw_lost, client_lost = lost_messages(raw_messages), lost_messages(client_messages)
        rows = [
            Row(
                "5·",
                f"floor: raw websockets, {count} messages of {FAST_TOPIC} (1 kHz)",
                n=count,
                versus=f"{raw_lost} lost, {count / raw_elapsed:.0f} msg/s",
                verdict="info",
                figures={"lost": raw_lost, "elapsed_s": raw_elapsed},
            ),
            Row(
                "5a",
                f"our client `subscribe`, {count} messages of {FAST_TOPIC} (1 kHz)",
                n=count,
                versus=f"{client_lost} lost, {count / client_elapsed:.0f} msg/s",
                target="0 lost",
                verdict=verdict(client_lost == 0),
                figures={"lost": client_lost, "elapsed_s": client_elapsed},
            ),
        ]
    rows.append(await measure_camera_image(ctx))
    rows.append(await measure_png_bomb(ctx))
    return rows


async def measure_camera_image(ctx: Context) -> Row:
    """One 640×480 rgb8 frame turned into an MCP image by ``get_image``, on a frame already waiting.

    The bench publishes one latched frame of its own, so the time is the tool's work (subscribe, receive,
    decode, resize, JPEG, answer) and not the camera's period.
    """
    what = "`get_image`: one latched 640×480 rgb8 frame as an MCP image (the tool's own work)"
    if "get_image" not in ctx.ours.tools:
        return Row("5b", what, target="≤ 100 ms", verdict="n/a (no get_image tool)")
    topic = "/bench/latched_image"
    width, height = 640, 480
    frame = {
        "header": {"frame_id": "bench"},
        "height": height,
        "width": width,
        "encoding": "rgb8",
        "is_bigendian": 0,
        "step": width * 3,
        "data": base64.b64encode(bytes(range(256)) * (width * height * 3 // 256)).decode(),
    }
    await ctx.raw.publish_latched(topic, "sensor_msgs/msg/Image", frame)
    arguments = {"topic": topic, "max_size": 640}
    samples: list[float] = []
    for index in range(max(3, ctx.plan.block) + 2):
        began = time.perf_counter()
        result = await ctx.ours.tool("get_image", arguments)
        if index >= 2:  # the first two warm up (graph look-ups, the bridge's publisher)
            samples.append(time.perf_counter() - began)
    if not any(isinstance(block, mcp_types.ImageContent) for block in result.content):
        raise RuntimeError("get_image answered without an image")
    await ctx.raw.unadvertise(topic)
    stats = Stats.of(samples)
    return timing_row("5b", what, stats, target="≤ 100 ms", verdict=verdict(stats.median <= 0.1))


async def measure_png_bomb(ctx: Context) -> Row:
    """``get_image`` on a latched CompressedImage PNG declaring 13000 × 13000 × 16 bit (~330 kB): refused from
    its header, and the server's peak RSS (Linux ``VmHWM``, reset first) grows by at most 50 MiB.

    Before the decode budget one such call raised the server's peak from 531 MiB to 2,497 MiB.
    """
    what = "`get_image` on a 13000² 16-bit PNG bomb (~330 kB): refused, server's peak RSS growth"
    target = "refused, ≤ 50 MiB"
    if "get_image" not in ctx.ours.tools:
        return Row("5c", what, target=target, verdict="n/a (no get_image tool)")
    if not peak_resettable(ctx.ours.process):
        return Row("5c", what, target=target, verdict="n/a (needs Linux /proc/PID/clear_refs)")
    topic = "/bench/png_bomb"
    bomb = {"format": "png", "data": base64.b64encode(png_bomb()).decode()}
    await ctx.raw.publish_latched(topic, "sensor_msgs/msg/CompressedImage", bomb)
    arguments = {"topic": topic, "timeout": 10}
    # A first call learns the topic's type and warms the subscription path; the measured one follows.
    await ctx.ours.session.call_tool("get_image", arguments)
    before = ctx.ours.rss()
    peak_reset(ctx.ours.process)
    began = time.perf_counter()
    result = await ctx.ours.session.call_tool("get_image", arguments)
    elapsed = time.perf_counter() - began
    growth = max(0, peak_rss(ctx.ours.process) - before)
    await ctx.raw.unadvertise(topic)
    text = " ".join(getattr(block, "text", "") for block in result.content)
    refused = bool(result.is_error) and "13000x13000" in text and "budget" in text
    return Row(
        "5c",
        what,
        n=1,
        median=mib(growth),
        versus=f"{'refused' if refused else 'NOT refused'} in {ms(elapsed)}",
        target=target,
        verdict=verdict(refused and growth <= 50 * MIB),
        figures={"refused": refused, "peak_rss_growth_bytes": growth, "elapsed_s": elapsed},
    )


def png_bomb(width: int = 13000, height: int = 13000) -> bytes:
    """A 16-bit grey PNG of ``width`` × ``height`` black pixels: 13000² is ~330 kB that decodes to 338 MB.
    Compressed one row at a time, so making it stays small (the same file the tests publish)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        crc = zlib.crc32(kind + data) & 0xFFFFFFFF
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)

    row = bytes(1 + width * 2)  # filter byte 0 and black pixels
    packer = zlib.compressobj(9)
    parts = [packer.compress(row) for _ in range(height)]
    parts.append(packer.flush())
    header = struct.pack(">IIBBBBB", width, height, 16, 0, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", b"".join(parts)) + chunk(b"IEND", b"")
    )
