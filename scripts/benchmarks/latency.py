"""Items 1-3: one request through each layer, interleaved: the raw floor, our client, roslibpy, a
no-op tool on a bare ``MCPServer``, and ``list_topics`` / ``publish_service`` through the console script."""

from __future__ import annotations

import contextlib
import time
from urllib.parse import urlsplit

import roslibpy

from benchmarks.harness import (
    ADD_TWO_INTS,
    Context,
    Row,
    Stats,
    Subject,
    interleave,
    publish_service_arguments,
    timing_row,
    verdict,
)

__all__: list[str] = []


class Roslibpy:
    """roslibpy's own blocking service call (its usual use); its Twisted reactor runs in a thread."""

    def __init__(self, url: str) -> None:
        parts = urlsplit(url)
        self.ros = roslibpy.Ros(host=parts.hostname, port=parts.port or 9090, is_secure=parts.scheme == "wss")
        self.topics = roslibpy.Service(self.ros, "/rosapi/topics", "rosapi/Topics")

    def connect(self) -> None:
        self.ros.run(timeout=10)

    async def call_topics(self) -> None:
        # Blocking on purpose: this is how roslibpy is used, and nothing else runs meanwhile.
        self.topics.call(roslibpy.ServiceRequest({}), timeout=10)

    def close(self) -> None:
        # close() only queues the close frame; let the handshake finish before the reactor stops.
        with contextlib.suppress(Exception):
            self.ros.close()
            deadline = time.monotonic() + 2
            while self.ros.is_connected and time.monotonic() < deadline:
                time.sleep(0.01)
        with contextlib.suppress(Exception):
            self.ros.terminate()


async def measure_latency(ctx: Context) -> list[Row]:
    """Items 1-3: the same request through each layer, interleaved; references marked with a dot.

    The no-op reference is served through our stdio transport, as our server is; the "SDK's stdio" rows
    serve the no-op and our server through the MCP SDK's transport instead, to show what it costs.
    """
    raw, client, ours, ours_sdk, plan, bridge = (
        ctx.raw,
        ctx.client,
        ctx.ours,
        ctx.ours_sdk,
        ctx.plan,
        ctx.bridge,
    )
    noop_ours, noop_sdk = ctx.reference, ctx.reference_sdk
    pyros = Roslibpy(bridge.url)
    pyros.connect()
    subjects = [
        Subject("floor", lambda: raw.call("/rosapi/topics")),
        Subject("client", lambda: client.call_service("/rosapi/topics")),
        Subject("roslibpy", pyros.call_topics),
        Subject("noop", lambda: noop_ours.tool("noop", {}), noop_ours.process),
        Subject("list_topics", lambda: ours.tool("list_topics", {}), ours.process),
        Subject("noop_sdk_stdio", lambda: noop_sdk.tool("noop", {}), noop_sdk.process),
        Subject("list_topics_sdk_stdio", lambda: ours_sdk.tool("list_topics", {}), ours_sdk.process),
    ]
    add_type = bridge.services.get(ADD_TWO_INTS)
    if add_type is not None:
        add_arguments = publish_service_arguments(ours, ADD_TWO_INTS, add_type, {"a": 2, "b": 3})
        subjects += [
            Subject("floor_add", lambda: raw.call(ADD_TWO_INTS, {"a": 2, "b": 3})),
            Subject("publish_service", lambda: ours.tool("publish_service", add_arguments), ours.process),
            Subject(
                "publish_service_sdk_stdio",
                lambda: ours_sdk.tool("publish_service", add_arguments),
                ours_sdk.process,
            ),
        ]
    try:
        await interleave(subjects, plan, ctx.bridge_process)
    finally:
        pyros.close()
    ctx.samples.update({subject.key: subject.samples for subject in subjects})
    ctx.cpu_per_call.update({subject.key: subject.cpu_per_call() for subject in subjects})
    by_key = {subject.key: subject.stats for subject in subjects}
    floor, client_stats, roslib = by_key["floor"], by_key["client"], by_key["roslibpy"]
    noop, noop_sdk_stats = by_key["noop"], by_key["noop_sdk_stdio"]

    def times(stats: Stats, reference: Stats, name: str) -> str:
        return f"{stats.median / reference.median:.2f}× {name}"

    def over(stats: Stats, reference: Stats, name: str) -> str:
        return f"{(stats.median - reference.median) * 1e3:+.2f} ms over {name}"

    def tool_row(item: str, what: str, key: str, floor_stats: Stats, floor_name: str, *, no_op: Stats) -> Row:
        stats = by_key[key]
        row = timing_row(
            item, what, stats, versus=f"{over(stats, floor_stats, floor_name)}; {over(stats, no_op, 'no-op')}"
        )
        row.figures["over_floor_s"] = stats.median - floor_stats.median
        if item.startswith("3·"):
            row.verdict = "info"
        else:
            row.target = f"≤ +1.5 ms over {floor_name}"
            row.verdict = verdict(stats.median - floor_stats.median <= 1.5e-3)
        return row

    rows = [
        timing_row("1", "floor: raw websockets `call_service /rosapi/topics`", floor, versus="reference"),
        timing_row(
            "2a",
            "our `RosbridgeClient.call_service('/rosapi/topics')`",
            client_stats,
            versus=times(client_stats, floor, "floor"),
            target="≤ 1.10× floor",
            verdict=verdict(client_stats.median <= 1.10 * floor.median),
        ),
        timing_row(
            "2b",
            "roslibpy `Service.call` (blocking), same call",
            roslib,
            versus=f"{times(roslib, floor, 'floor')}; ours {roslib.median / client_stats.median:.2f}× faster",
            target="ours faster",
            verdict=verdict(client_stats.median < roslib.median),
        ),
        timing_row(
            "3·",
            "SDK reference: no-op tool on a bare `MCPServer`, our stdio transport",
            noop,
            versus=over(noop, floor, "floor"),
            verdict="info",
        ),
        tool_row(
            "3a", "tool `list_topics` (MCP stdio, console script)", "list_topics", floor, "floor", no_op=noop
        ),
    ]
    if add_type is not None:
        floor_add = by_key["floor_add"]
        rows += [
            timing_row("3·", f"floor: raw `call_service {ADD_TWO_INTS}`", floor_add, versus="reference"),
            tool_row(
                "3b",
                f"tool `publish_service` {ADD_TWO_INTS}",
                "publish_service",
                floor_add,
                "its floor",
                no_op=noop,
            ),
        ]
    else:
        rows.append(Row("3b", f"tool `publish_service` {ADD_TWO_INTS}", verdict=f"n/a (no {ADD_TWO_INTS})"))
    rows += [
        timing_row(
            "3·",
            "the same no-op on the MCP SDK's stdio transport (worker threads)",
            noop_sdk_stats,
            versus=f"{over(noop_sdk_stats, floor, 'floor')}; {over(noop_sdk_stats, noop, 'our transport')}",
            verdict="info",
        ),
        tool_row(
            "3·",
            "`list_topics`, our server on the SDK's stdio",
            "list_topics_sdk_stdio",
            floor,
            "floor",
            no_op=noop_sdk_stats,
        ),
    ]
    if add_type is not None:
        rows.append(
            tool_row(
                "3·",
                "`publish_service`, our server on the SDK's stdio",
                "publish_service_sdk_stdio",
                by_key["floor_add"],
                "its floor",
                no_op=noop_sdk_stats,
            )
        )
    return rows
