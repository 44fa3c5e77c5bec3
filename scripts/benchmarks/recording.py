"""Item 14: ``record`` under a Nav2-like load against a raw subscriber; a large recording's summary."""

from __future__ import annotations

import asyncio
import base64
import contextlib
import json
import os
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed

from benchmarks.harness import (
    Context,
    Row,
    Served,
    Stats,
    ctx_graph_has,
    mib,
    ms,
    our_server_command,
    serve_mcp,
    simulated_robot,
    timing_row,
    verdict,
)

__all__: list[str] = []

# --------------------------------------------------------------------------------- item 14: recording

#: What item 14 records, as a Nav2 robot publishes it: topic, type, rate (Hz).
RECORDED_LOAD = (
    ("/bench/scan", "sensor_msgs/msg/LaserScan", 10.0),
    ("/bench/odom", "nav_msgs/msg/Odometry", 50.0),
    ("/bench/tf", "tf2_msgs/msg/TFMessage", 50.0),
    ("/bench/camera/image_raw", "sensor_msgs/msg/Image", 30.0),
)
_TOPICS = tuple(topic for topic, _, _ in RECORDED_LOAD)


def _load_message(topic: str, index: int) -> dict[str, Any]:
    stamp = {"sec": int(time.time()), "nanosec": index}
    header = {"stamp": stamp, "frame_id": "base_link"}
    if topic.endswith("scan"):
        return {
            "header": header,
            "angle_min": -3.14,
            "angle_increment": 0.0175,
            "range_max": 12.0,
            "ranges": [1.0 + (i % 50) / 10 for i in range(360)],
        }
    if topic.endswith("odom"):
        return {
            "header": header,
            "child_frame_id": "base_link",
            "pose": {"pose": {"position": {"x": index / 100.0}}},
        }
    if topic.endswith("tf"):
        return {
            "transforms": [
                {
                    "header": header,
                    "child_frame_id": "base_link",
                    "transform": {"translation": {"x": index / 100.0}, "rotation": {"w": 1.0}},
                }
            ]
        }
    return {}


async def _publish_load(
    ws: ClientConnection, seconds: float, published: dict[str, int], first: int = 0
) -> None:
    """On a raw socket that advertised the load's topics: publish each at its rate for ``seconds``."""
    width, height = 640, 480
    frame = bytes((i * 7) % 251 for i in range(width * height * 3))
    image_data = base64.b64encode(frame).decode()
    if True:

        async def one(topic: str, rate: float) -> None:
            loop = asyncio.get_running_loop()
            start = loop.time()
            count = int(seconds * rate)
            for index in range(count):
                if topic.endswith("image_raw"):
                    msg: dict[str, Any] = {
                        "header": {
                            "stamp": {"sec": int(time.time()), "nanosec": first + index},
                            "frame_id": "camera",
                        },
                        "height": height,
                        "width": width,
                        "encoding": "rgb8",
                        "step": width * 3,
                        "data": image_data,
                    }
                else:
                    msg = _load_message(topic, first + index)
                await ws.send(json.dumps({"op": "publish", "topic": topic, "msg": msg}))
                published[topic] += 1
                await asyncio.sleep(max(0.0, start + (index + 1) / rate - loop.time()))

        await asyncio.gather(*(one(topic, rate) for topic, _, rate in RECORDED_LOAD))


def _index_of(message: dict[str, Any]) -> int:
    """The publisher's counter a load message carries (its header stamp's nanoseconds)."""
    header = message.get("header") or (message.get("transforms") or [{}])[0].get("header") or {}
    stamp = header.get("stamp") or {}
    return int(stamp.get("nanosec", stamp.get("nsecs", -1)))


async def _count_load(url: str, counts: dict[str, set[int]], stop: asyncio.Event) -> None:
    """A raw socket subscribed to the load's topics: which messages the simulated robot sent a subscriber."""
    async with connect(url, max_size=None, compression=None) as ws:
        for topic, msg_type, _ in RECORDED_LOAD:
            await ws.send(json.dumps({"op": "subscribe", "topic": topic, "type": msg_type}))
        while not stop.is_set():
            try:
                frame = await asyncio.wait_for(ws.recv(), 0.5)
            except TimeoutError:
                continue
            except ConnectionClosed:
                return
            received = json.loads(frame)
            topic = received.get("topic")
            if topic in counts:
                counts[topic].add(_index_of(received.get("msg") or {}))


async def measure_recording(ctx: Context) -> list[Row]:
    """Item 14: record a Nav2-like load (scan 10 Hz, odom 50 Hz, tf 50 Hz, a 640×480 camera at 30 Hz) and
    count what was lost against a raw subscriber; list_topics while recording; a large recording's summary."""
    seconds = 60.0 if ctx.plan.name == "full" else 1.0
    rows: list[Row] = []
    with tempfile.TemporaryDirectory(prefix="bench-rec-") as folder:
        async with contextlib.AsyncExitStack() as stack:
            url = await stack.enter_async_context(simulated_robot(ctx.errlog))
            served = await stack.enter_async_context(
                serve_mcp([*our_server_command(url), "--record-dir", folder], ctx.errlog)
            )
            # Advertised first, so record finds the topics in the graph.
            publisher = await stack.enter_async_context(connect(url, max_size=None, compression=None))
            for topic, msg_type, _ in RECORDED_LOAD:
                await publisher.send(json.dumps({"op": "advertise", "topic": topic, "type": msg_type}))
            await ctx_graph_has(served, RECORDED_LOAD[-1][0])
            published = dict.fromkeys((t for t, _, _ in RECORDED_LOAD), 0)
            idle: list[float] = []
            for _ in range(20):
                began = time.perf_counter()
                await served.tool("list_topics", {})
                idle.append(time.perf_counter() - began)
            counted: dict[str, set[int]] = {topic: set() for topic in published}
            stop = asyncio.Event()
            counter = asyncio.create_task(_count_load(url, counted, stop))
            # The same load with nobody recording, before the recording and again after it (so that drift on
            # this shared machine hits the reference as it hits the recording): 14b's reference.
            loaded = await _list_topics_under_load(served, publisher, min(seconds, 10.0), 500_000_000)
            for seen in counted.values():
                seen.clear()
            recording = asyncio.create_task(
                served.tool(
                    "record",
                    {
                        "topics": ["/bench/*"],
                        "duration": seconds + (6 if ctx.plan.name == "full" else 3),
                        "name": "load",
                    },
                )
            )
            # record's subscriptions are in place (what it got is counted from its first message on)
            await asyncio.sleep(3.0 if ctx.plan.name == "full" else 1.5)
            load = asyncio.create_task(_publish_load(publisher, seconds, published))
            busy: list[float] = []
            while not load.done():
                began = time.perf_counter()
                await served.tool("list_topics", {})
                busy.append(time.perf_counter() - began)
                await asyncio.sleep(0.25)
            await load
            result = await recording
            stop.set()
            await counter
            loaded += await _list_topics_under_load(served, publisher, min(seconds, 10.0), 700_000_000)
            data = result.structured_content or {}
            recorded = await asyncio.to_thread(_recorded_indices, Path(folder) / "load.mcap")
            # What the raw subscriber got while the recording was running (between the recording's first and
            # last message of the topic) and the recording lacks.
            lost: dict[str, int] = {}
            for topic, seen in counted.items():
                mine = recorded.get(topic, set())
                low, high = (min(mine), max(mine)) if mine else (0, -1)
                lost[topic] = len({i for i in seen if low <= i <= high} - mine)
            sent = 0
            for topic, seen in counted.items():
                mine = recorded.get(topic, set())
                sent += len({i for i in seen if mine and min(mine) <= i <= max(mine)})
            rows.append(
                Row(
                    "14a",
                    f"`record` {seconds:g} s of scan 10 Hz, odom 50 Hz, tf 50 Hz, 640×480 camera 30 Hz: "
                    f"messages lost vs a raw subscriber ({sent} sent while recording, "
                    f"{data.get('bytes', 0) / 1e6:.1f} MB file)",
                    median=str(sum(lost.values())),
                    target="0",
                    verdict=verdict(sum(lost.values()) == 0 and sent > 0),
                    figures={
                        "published": published,
                        "counted": {t: len(v) for t, v in counted.items()},
                        "recorded": {t: len(v) for t, v in recorded.items()},
                        "lost": lost,
                        "lost_in_the_server": {t["topic"]: t["lost"] for t in data.get("topics", [])},
                    },
                )
            )
            rows += _responsiveness_rows(Stats.of(busy), Stats.of(loaded), Stats.of(idle))
            # A large recording: read_recording's summary, from the index (the file is not read through).
            size = 1024**3 if ctx.plan.name == "full" else 16 * 1024**2
            if shutil.disk_usage(folder).free < size * 2:
                rows.append(Row("14c", "`read_recording` summary of a large recording", verdict="n/a (disk)"))
                return rows
            path = Path(folder) / "large.mcap"
            await asyncio.to_thread(_write_large_recording, path, size)
            times = []
            for _ in range(5):
                began = time.perf_counter()
                summary = await served.tool("read_recording", {"file": path.name})
                times.append(time.perf_counter() - began)
            details = (summary.structured_content or {}).get("details", {})
            rows.append(
                timing_row(
                    "14c",
                    f"`read_recording` summary of a {mib(path.stat().st_size)} recording "
                    f"({details.get('messages')} messages) from its index, through MCP",
                    Stats.of(times),
                    target="< 1 s",
                    verdict=verdict(Stats.of(times).median < 1.0 and details.get("indexed") is True),
                )
            )
    return rows


async def _list_topics_under_load(
    served: Served, publisher: ClientConnection, seconds: float, first: int
) -> list[float]:
    """``list_topics`` every 0.25 s while the load is published (nobody recording), its messages numbered
    from *first* (outside the recording's numbers)."""
    samples: list[float] = []
    load = asyncio.create_task(_publish_load(publisher, seconds, dict.fromkeys(_TOPICS, 0), first=first))
    while not load.done():
        began = time.perf_counter()
        await served.tool("list_topics", {})
        samples.append(time.perf_counter() - began)
        await asyncio.sleep(0.25)
    await load
    return samples


def _responsiveness_rows(during: Stats, loaded: Stats, idle: Stats) -> list[Row]:
    """14b: list_topics while recording against the same load with nobody recording (the recorder's own
    cost; docs/performance.md says why not against idle), and 14b·: the idle figure, for information."""
    factor = during.median / loaded.median
    row = timing_row(
        "14b",
        "`list_topics` while `record` runs (14a's load) vs the same load with nobody recording, same server",
        during,
        versus=f"{factor:.2f}× the same load unrecorded ({ms(loaded.median)}, n={loaded.n}, before + after)",
        target="≤ 2× the same load unrecorded",
        verdict=verdict(factor <= 2.0),
    )
    row.figures.update(loaded_median_s=loaded.median, idle_median_s=idle.median, ratio=factor)
    reference = timing_row(
        "14b·",
        "↳ `list_topics` on the same server idle (no load)",
        idle,
        versus=f"while recording: {during.median / idle.median:.2f}× this; the load unrecorded: "
        f"{loaded.median / idle.median:.2f}× this",
        verdict="info",
    )
    return [row, reference]


def _recorded_indices(path: Path) -> dict[str, set[int]]:
    """The publisher's counter of every message in the recording, by topic: read with the ``mcap`` library and
    its ROS 2 decoder (both dependencies of the package), as any MCAP reader would."""
    found: dict[str, set[int]] = {}
    with path.open("rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        for _, channel, _, decoded in reader.iter_decoded_messages():
            found.setdefault(channel.topic, set()).add(_index_of_decoded(decoded))
    return found


def _index_of_decoded(message: Any) -> int:
    """:func:`_index_of` for a decoded ROS 2 message (attributes, not keys)."""
    header = getattr(message, "header", None)
    if header is None:
        transforms = getattr(message, "transforms", None) or []
        header = transforms[0].header if transforms else None
    return int(header.stamp.nanosec) if header is not None else -1


def _write_large_recording(path: Path, size: int) -> None:
    """An uncompressed MCAP of 640×480 frames at 30 Hz until ``size`` bytes (as a camera recording is)."""
    from mcap.writer import CompressionType, Writer  # noqa: PLC0415

    frame = os.urandom(640 * 480 * 3)
    with path.open("wb") as handle:
        writer = Writer(handle, chunk_size=4 * 1024**2, compression=CompressionType.NONE)
        writer.start(profile="ros2", library="bench")
        schema = writer.register_schema("sensor_msgs/msg/Image", "ros2msg", b"uint8[] data\n")
        channel = writer.register_channel("/camera/image_raw", "cdr", schema)
        start = time.time_ns()
        written = index = 0
        while written < size:
            data = b"\x00\x01\x00\x00" + len(frame).to_bytes(4, "little") + frame
            writer.add_message(channel, log_time=start + index * 33_333_333, data=data, publish_time=start)
            written += len(data)
            index += 1
        writer.finish()
