"""Item 8: the graph tools against the raw rosapi round trips each needs (meant for real bridges too)."""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import time
from collections.abc import Awaitable, Callable

from websockets.asyncio.client import connect

from benchmarks.harness import (
    BARE,
    TOOL_PAUSE,
    Context,
    Plan,
    RawBridge,
    Row,
    Stats,
    Subject,
    interleave,
    ms,
    our_server_command,
    raw_pipe_client,
    serve_mcp,
    timing_row,
    verdict,
)
from benchmarks.internals import infrastructure_types

__all__: list[str] = []

# ------------------------------------------------------------------------------- item 8: the graph tools

#: Fresh servers for list_services' first call (each spawn is ~1 s; the call itself is what is timed).
FIRST_CALL_SERVERS = {"full": 6, "quick": 1}
#: The least time between a server connecting and a model's first tool call: initialize, tools/list and one
#: model turn. The server learns the service types meanwhile (robot/warm_up.py).
FIRST_TURN = 1.0
GRAPH_TOPIC = "/rosout"


async def measure_graph_tools(ctx: Context) -> list[Row]:
    """Item 8: each graph tool against the raw rosapi round trips it needs, interleaved in one run.

    get_topic_info needs topic_type, publishers and subscribers: its floor is the faster of the two raw ways
    to ask them (one after another on one connection, or side by side on three). list_actions needs
    action_servers (and, the first time on a connection, one type look-up per action). list_services is
    held to list_topics: at most 3× on a connection's first call (fresh servers), at most 1.5× after.

    Each floor is measured twice: back to back, and after an untimed pause as long as an MCP round trip
    (``TOOL_PAUSE``), because a tool's request always reaches the bridge after one, and rosbridge 2.1.0
    answers a request that follows a short pause ~9 ms later than one sent back to back
    (docs/rosbridge-behaviour.md).
    """
    raw, ours, plan, url = ctx.raw, ctx.ours, ctx.plan, ctx.bridge.url
    topic_args = {"topic": GRAPH_TOPIC}
    queries = ("/rosapi/topic_type", "/rosapi/publishers", "/rosapi/subscribers")
    async with contextlib.AsyncExitStack() as stack:
        extra = [
            RawBridge(await stack.enter_async_context(connect(url, max_size=None, compression=None)))
            for _ in range(2)
        ]
        # The same server called by JSON-RPC lines: what the server alone adds, without the client SDK's work.
        bare = await stack.enter_async_context(raw_pipe_client(our_server_command(url), ctx.errlog, {}))

        async def info_in_a_row() -> None:
            for service in queries:
                await raw.call(service, topic_args)

        async def info_side_by_side() -> None:
            bridges = [raw, *extra]
            await asyncio.gather(
                *(bridge.call(service, topic_args) for bridge, service in zip(bridges, queries, strict=True))
            )

        def floor(key: str, call: Callable[[], Awaitable[object]]) -> list[Subject]:
            return [Subject(key, call), Subject(f"{key}_paused", call, pause=TOOL_PAUSE)]

        subjects = [
            *floor("g_floor_topics", lambda: raw.call("/rosapi/topics")),
            Subject("g_list_topics", lambda: ours.tool("list_topics", {}), ours.process),
            Subject("g_list_services", lambda: ours.tool("list_services", {}), ours.process),
            *floor("g_floor_info_row", info_in_a_row),
            *floor("g_floor_info_wide", info_side_by_side),
            Subject("g_get_topic_info", lambda: ours.tool("get_topic_info", topic_args), ours.process),
            *floor("g_floor_actions", lambda: raw.call("/rosapi/action_servers")),
            Subject("g_list_actions", lambda: ours.tool("list_actions", {}), ours.process),
            Subject("g_list_topics_bare", lambda: bare.tool("list_topics", {})),
            Subject("g_get_topic_info_bare", lambda: bare.tool("get_topic_info", topic_args)),
            Subject("g_list_actions_bare", lambda: bare.tool("list_actions", {})),
        ]
        await interleave(subjects, Plan(**{**dataclasses.asdict(plan), "block": max(2, plan.block // 4)}))
    first, at_once, first_floor, fresh_topics = await first_listings(ctx)
    ctx.samples.update(
        {subject.key: subject.samples for subject in subjects}
        | {
            "g_list_services_first": first,
            "g_list_services_at_once": at_once,
            "g_floor_services_first": first_floor,
            "g_list_topics_fresh": fresh_topics,
        }
    )
    by_key = {subject.key: subject.stats for subject in subjects}
    topics = by_key["g_list_topics"]
    first_stats, at_once_stats, first_floor_stats = Stats.of(first), Stats.of(at_once), Stats.of(first_floor)

    def ratio_row(item: str, what: str, stats: Stats, limit: float, extra: str = "") -> Row:
        factor = stats.median / topics.median
        row = timing_row(
            item,
            what,
            stats,
            versus=f"{factor:.2f}× list_topics{extra}",
            target=f"≤ {limit:g}× list_topics",
        )
        row.verdict = verdict(factor <= limit)
        row.figures["times_list_topics"] = factor
        return row

    def floor_row(item: str, what: str, key: str, *, hot: Stats, paused: Stats, floor_name: str) -> Row:
        stats = by_key[key]
        over_hot, over_paused = stats.median - hot.median, stats.median - paused.median
        row = timing_row(
            item,
            what,
            stats,
            versus=f"{over_paused * 1e3:+.2f} ms over {floor_name} after a pause; "
            f"{over_hot * 1e3:+.2f} ms over it back to back",
            target="≤ +1.5 ms over its floor",
        )
        row.verdict = verdict(over_paused <= 1.5e-3) + ("" if over_hot <= 1.5e-3 else " (after a pause)")
        row.figures["over_floor_s"] = over_hot
        row.figures["over_paused_floor_s"] = over_paused
        return row

    def tool_rows(item: str, what: str, key: str, floor_key: str, floor_name: str) -> list[Row]:
        """The tool through the SDK's client, then the same by JSON-RPC lines, each against its floor."""
        hot, paused = by_key[floor_key], by_key[f"{floor_key}_paused"]
        return [
            floor_row(item, what, key, hot=hot, paused=paused, floor_name=floor_name),
            floor_row(f"{item}′", BARE, f"{key}_bare", hot=hot, paused=paused, floor_name=floor_name),
        ]

    def floor_rows(what: str, key: str) -> list[Row]:
        return [
            timing_row("8·", f"floor: {what}", by_key[key], versus="reference"),
            timing_row("8·", f"the same after a {TOOL_PAUSE * 1e3:g} ms pause", by_key[f"{key}_paused"]),
        ]

    row_floor, wide_floor = by_key["g_floor_info_row_paused"], by_key["g_floor_info_wide_paused"]
    info_key, info_name = (
        ("g_floor_info_row", "3 raw calls in a row")
        if row_floor.median <= wide_floor.median
        else ("g_floor_info_wide", "3 raw calls side by side")
    )
    over_at_once = at_once_stats.median - first_floor_stats.median
    at_once_row = ratio_row(
        "8b·",
        "tool `list_services` at once after connecting (fresh server; the types are still being learnt)",
        at_once_stats,
        3.0,
        f"; {over_at_once * 1e3:+.1f} ms over its floor",
    )
    at_once_row.target, at_once_row.verdict = "", "info"
    return [
        *floor_rows("raw `call_service /rosapi/topics`", "g_floor_topics"),
        *tool_rows("8a", "tool `list_topics`", "g_list_topics", "g_floor_topics", "its floor"),
        timing_row(
            "8·",
            "floor: a fresh raw client asks `services`, then the types as our server does (ROS 2: a "
            "refused probe call each, 8 at a time; ROS 1: `service_type`, 4 at a time), on connections of "
            "their own",
            first_floor_stats,
            versus="reference",
        ),
        first_row(first_stats, Stats.of(fresh_topics), topics),
        at_once_row,
        ratio_row("8c", "tool `list_services`, later calls", by_key["g_list_services"], 1.5),
        *floor_rows("raw topic_type + publishers + subscribers, in a row", "g_floor_info_row"),
        *floor_rows("the same three side by side on three connections", "g_floor_info_wide"),
        *tool_rows("8d", f"tool `get_topic_info` {GRAPH_TOPIC}", "g_get_topic_info", info_key, info_name),
        *floor_rows("raw `call_service /rosapi/action_servers`", "g_floor_actions"),
        *tool_rows(
            "8e",
            "tool `list_actions` (types known on the connection)",
            "g_list_actions",
            "g_floor_actions",
            "its floor",
        ),
    ]


def first_row(first: Stats, fresh_topics: Stats, warm_topics: Stats) -> Row:
    """8b: a session's first list_services against list_topics on the same fresh server right after it.

    A fresh process runs every path for the first time (the bench's own MCP client too: it compiles each
    tool's output schema on its first result), so a warm server's list_topics is no fair reference; the
    row holds what it is meant to: no round trips the later calls do not make (docs/performance.md).
    """
    factor = first.median / fresh_topics.median
    row = timing_row(
        "8b",
        f"tool `list_services`, a session's first call, {FIRST_TURN:g} s after connecting (fresh server)",
        first,
        versus=f"{factor:.2f}× list_topics on the same fresh server right after ({ms(fresh_topics.median)}); "
        f"{first.median / warm_topics.median:.2f}× a warm server's",
        target="≤ 3× list_topics (same fresh server)",
    )
    row.verdict = verdict(factor <= 3.0)
    row.figures.update(
        times_list_topics=first.median / warm_topics.median,
        times_fresh_list_topics=factor,
        fresh_list_topics_median_s=fresh_topics.median,
    )
    return row


async def look_up_types(bridge: RawBridge, queue: list[str]) -> None:
    """Take services off *queue* and ask their types, one at a time on *bridge*, until none is left."""
    while queue:
        await bridge.call("/rosapi/service_type", {"service": queue.pop()})


async def probe_types(bridge: RawBridge, queue: list[str]) -> None:
    """Take services off *queue* and call each with a field no request has (the bridge refuses, naming it)."""
    while queue:
        with contextlib.suppress(RuntimeError):
            await bridge.call(queue.pop(), {"__type_probe__": 0})


async def first_listings(ctx: Context) -> tuple[list[float], list[float], list[float], list[float]]:
    """list_services on fresh servers, as a model's first call and at once after connecting, list_topics on
    the same fresh server right after the first, and the same rosapi round trips from a fresh raw client."""
    url, errlog = ctx.bridge.url, ctx.errlog
    first: list[float] = []
    at_once: list[float] = []
    floor: list[float] = []
    fresh_topics: list[float] = []
    for _ in range(FIRST_CALL_SERVERS[ctx.plan.name]):
        for turn, samples in ((FIRST_TURN, first), (0.0, at_once)):
            async with serve_mcp(our_server_command(url), errlog) as fresh:
                await fresh.tool("list_topics", {})  # the connection is up and the bridge's kind known
                await asyncio.sleep(turn)  # not a synchronisation: the model's turn being modelled
                began = time.perf_counter()
                await fresh.tool("list_services", {})
                samples.append(time.perf_counter() - began)
                if turn:
                    # The reference of 8b: list_topics on the same fresh process, at the same moment.
                    began = time.perf_counter()
                    await fresh.tool("list_topics", {})
                    fresh_topics.append(time.perf_counter() - began)
        began = time.perf_counter()
        async with connect(url, max_size=None, compression=None) as ws:
            raw = RawBridge(ws)
            names = (await raw.call("/rosapi/services")).get("services", [])
            version = 2 if any(name == "/rosapi/get_ros_version" for name in names) else 1
            fixed = infrastructure_types(names, version)
            asked = [name for name in names if name not in fixed]
            # What our server does: on ROS 2 a probe call per service, up to 8 at once (beside the services
            # call, one probe of rosapi's get_time); on ROS 1 rosapi's service_type, 4 at once.
            wide_count = min(8 if version == 2 else 4, len(asked))
            async with contextlib.AsyncExitStack() as lanes:
                # Opened side by side, as the server's client opens its lanes.
                opened = await asyncio.gather(
                    *(connect(url, max_size=None, compression=None) for _ in range(wide_count))
                )
                for ws_lane in opened:
                    lanes.push_async_callback(ws_lane.close)
                wide = [RawBridge(ws_lane) for ws_lane in opened]
                look_up = probe_types if version == 2 else look_up_types
                await asyncio.gather(*(look_up(bridge, asked) for bridge in wide))
        floor.append(time.perf_counter() - began)
    return first, at_once, floor, fresh_topics
