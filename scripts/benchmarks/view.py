"""Item 11: the picture tools: ``view_map`` on a large map and ``view_scan`` against the raw socket."""

from __future__ import annotations

import base64
import contextlib
import json
import time

import cbor2
import mcp_types
from websockets.asyncio.client import connect

from benchmarks.harness import (
    Context,
    Metronome,
    Row,
    Stats,
    mib,
    our_server_command,
    phase_locked,
    ratio_row,
    raw_first_message,
    serve_mcp,
    simulated_robot,
    timing_row,
)

__all__: list[str] = []

# --------------------------------------------------------------------------------- item 11: picture tools

#: The side of the benchmark's map in cells (4 M cells: ~12 MB of JSON, fragmented by ROS 2 bridges); a
#: --quick run uses a small one, to stay a smoke test.
BIG_MAP_CELLS = 2000
QUICK_MAP_CELLS = 300


async def raw_whole_message(url: str, topic: str, msg_type: str, *, cbor: bool = False) -> int:
    """A fresh raw connection: subscribe → the first message, reassembled from its fragments and parsed →
    unsubscribe. Returns the message's JSON size in characters (with ``cbor``: its binary frame's bytes,
    decoded by cbor2 with the typed arrays left as byte strings)."""
    async with connect(url, max_size=None, compression=None) as ws:
        subscribe = {"op": "subscribe", "id": "raw:map", "topic": topic, "type": msg_type}
        await ws.send(json.dumps({**subscribe, "compression": "cbor"} if cbor else subscribe))
        parts: list[str] = []
        size = 0
        while True:
            data = await ws.recv()
            if isinstance(data, bytes):
                frame = cbor2.loads(data)
                if frame.get("op") == "publish" and frame.get("topic") == topic:
                    size = len(data)
                    break
                continue
            frame = json.loads(data)
            if frame.get("op") == "fragment":
                if frame["num"] == 0:
                    parts = []
                parts.append(frame["data"])
                # rosbridge's total is a float (true division): 2.28 for two parts.
                if len(parts) < int(frame["total"]):
                    continue
                text = "".join(parts)
                size = len(text)
                frame = json.loads(text)
            if frame.get("op") == "publish" and frame.get("topic") == topic:
                size = size or len(json.dumps(frame))
                break
        await ws.send(json.dumps({"op": "unsubscribe", "id": "raw:map", "topic": topic}))
    return size


def image_bytes(result: mcp_types.CallToolResult) -> int:
    """The size of a tool answer's (first) image, as PNG bytes."""
    for block in result.content:
        if isinstance(block, mcp_types.ImageContent):
            return len(base64.b64decode(block.data))
    raise RuntimeError("the answer has no image")


async def measure_view(ctx: Context) -> list[Row]:
    """Item 11: view_map on a large map and view_scan against the raw socket; picture sizes."""
    trials = 6 if ctx.plan.name == "full" else 1
    cells = BIG_MAP_CELLS if ctx.plan.name == "full" else QUICK_MAP_CELLS
    rows: list[Row] = []
    sizes: dict[str, int] = {}
    async with contextlib.AsyncExitStack() as stack:
        if ctx.bridge.simulated:
            url = await stack.enter_async_context(simulated_robot(ctx.errlog, map_cells=cells))
            served = await stack.enter_async_context(serve_mcp(our_server_command(url), ctx.errlog))
            label = f"{cells}×{cells}"
        else:
            url, served, label = ctx.bridge.url, ctx.ours, "the bridge's"
        # The large-map robot is a ROS 2 simulated robot of its own.
        map_type = "nav_msgs/msg/OccupancyGrid" if ctx.bridge.simulated else ctx.bridge.topics.get("/map", "")
        if not map_type:
            rows.append(Row("11a", "`view_map` /map", verdict="n/a (no /map)"))
        else:
            samples: dict[str, list[float]] = {"raw": [], "tool": [], "cbor": []}
            json_chars = cbor_bytes = 0
            for trial in range(trials + 1):
                order = ["raw", "cbor", "tool"] if trial % 2 == 0 else ["tool", "cbor", "raw"]
                for name in order:
                    began = time.perf_counter()
                    if name == "raw":
                        json_chars = await raw_whole_message(url, "/map", map_type)
                    elif name == "cbor":
                        cbor_bytes = await raw_whole_message(url, "/map", map_type, cbor=True)
                    else:
                        result = await served.tool("view_map", {"timeout": 30})
                        sizes["view_map"] = image_bytes(result)
                    if trial:  # the first round warms up
                        samples[name].append(time.perf_counter() - began)
            row = ratio_row(
                "11a",
                f"`view_map` /map {label} cells → PNG 800 px (raw: {mib(json_chars)} of JSON)",
                Stats.of(samples["tool"]),
                Stats.of(samples["raw"]),
                1.5,
            )
            rows.append(row)
            # view_map asks for CBOR (#19): the raw CBOR receipt is the floor it cannot beat.
            rows.append(
                timing_row(
                    "11a·",
                    f"↳ reference: a raw CBOR receipt of the same /map ({mib(cbor_bytes)}, one binary frame)",
                    Stats.of(samples["cbor"]),
                    verdict="info",
                )
            )
    scan_type = ctx.bridge.topics.get("/scan")
    if scan_type is None:
        rows.append(Row("11b", "`view_scan` /scan", verdict="n/a (no /scan)"))
    else:
        async with (
            connect(ctx.bridge.url, max_size=None, compression=None) as ws,
            Metronome(ws, "/scan", scan_type) as metronome,
        ):
            stats = await phase_locked(
                metronome,
                trials * 3,
                {
                    "raw": lambda: raw_first_message(ctx.raw, "/scan", scan_type),
                    "tool": lambda: ctx.ours.tool("view_scan", {}),
                },
            )
        rows.append(
            ratio_row(
                "11b", "`view_scan` /scan (5 Hz, 360 beams) → PNG 600 px", stats["tool"], stats["raw"], 1.3
            )
        )
        sizes["view_scan"] = image_bytes(await ctx.ours.tool("view_scan", {}))
    pose_type = ctx.bridge.topics.get("/turtle1/pose")
    if pose_type is not None:
        chart = await ctx.ours.tool("plot_topic", {"series": ["/turtle1/pose x y theta"], "duration": 1})
        sizes["plot_topic"] = image_bytes(chart)
    rows.append(
        Row(
            "11c",
            "picture sizes (PNG): " + ", ".join(f"`{name}`" for name in sizes),
            median=" / ".join(f"{size} B" for size in sizes.values()),
            verdict="info",
            figures={"bytes": sizes},
        )
    )
    return rows
