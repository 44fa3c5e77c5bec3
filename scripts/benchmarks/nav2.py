"""Item 12: every graph tool on a simulated Nav2 robot, the server alone (JSON-RPC lines), against the raw
calls its answer needs, with the size of each answer."""

from __future__ import annotations

import contextlib
import dataclasses
import json
from typing import Any

from websockets.asyncio.client import connect

from benchmarks.edge import NAV2_NODE, Case, allowance, graph_cases, node_info_floor
from benchmarks.harness import (
    TOOL_PAUSE,
    Context,
    Plan,
    RawBridge,
    Row,
    Subject,
    interleave,
    ms,
    our_server_command,
    raw_pipe_client,
    simulated_robot,
    timing_row,
    verdict,
)

__all__: list[str] = []


async def measure_nav2(ctx: Context) -> list[Row]:
    """Item 12: every graph tool on a simulated Nav2 robot (its own process), or on the bridge given with
    --url (which must run a Nav2-like graph), called by JSON-RPC lines (the server alone), against the raw
    calls its answer needs, interleaved; with each answer's size.

    The floors: one call for list_topics / list_services / list_actions / list_nodes / describe_type, the
    node's own service for list_parameters of one node and get_parameter, node_details and topics side by
    side after nodes for get_node_info (rosapi 2.x never answers node_details for an unknown node, so the
    node list comes first), the three topic look-ups side by side for get_topic_info.
    """
    plan = ctx.plan
    async with contextlib.AsyncExitStack() as stack:
        # With --url: the bridge given, which must run a Nav2-like graph (NAV2_NODE, /scan, OccupancyGrid).
        url = (
            await stack.enter_async_context(simulated_robot(ctx.errlog, world="nav2"))
            if ctx.bridge.simulated
            else ctx.bridge.url
        )
        raws = [
            RawBridge(await stack.enter_async_context(connect(url, max_size=None, compression=None)))
            for _ in range(3)
        ]
        raw = raws[0]
        ours = await stack.enter_async_context(raw_pipe_client(our_server_command(url), ctx.errlog, {}))

        # A bridge that answers refusals with status ops (rosbridge-server-rs, given with --url) needs no node
        # list before node_details, and lists every parameter with one get_param_names: so does our server.
        # The simulated world here is rosbridge_suite-like; a bridge given with --url is asked.
        status_replies = False if ctx.bridge.simulated else await raw.answers_with_status()
        cases = await graph_cases(raws, status_replies=status_replies)
        subjects, sizes = await _nav2_subjects(cases, ours)
        counts: dict[str, int] = {"block": max(2, plan.block // 4)}
        if not ctx.bridge.simulated:
            # A real bridge takes 10-100 ms a call (2.1.0: one at a time per connection): fewer rounds.
            counts.update(rounds=max(2, plan.rounds // 4), warmup=min(plan.warmup, 5))
        await interleave(subjects, Plan(**{**dataclasses.asdict(plan), **counts}))
    if not ctx.bridge.simulated:
        return _nav2_rows(ctx, cases, subjects, sizes)
    # The same world on a bridge like rosbridge-server-rs (get_node_info needs no node list there), measured
    # after the first world has stopped: a second world's sensors running beside the rows above took CPU
    # from them on 2 cores.
    async with contextlib.AsyncExitStack() as stack:
        rs_url = await stack.enter_async_context(simulated_robot(ctx.errlog, world="nav2", server="rs"))
        rs_raws = [
            RawBridge(await stack.enter_async_context(connect(rs_url, max_size=None, compression=None)))
            for _ in range(2)
        ]
        ours_rs = await stack.enter_async_context(raw_pipe_client(our_server_command(rs_url), ctx.errlog, {}))

        name, floor = node_info_floor([rs_raws[0], *rs_raws], NAV2_NODE, node_list_first=False)
        rs_case = Case(
            "k", "get_node_info", {"node": NAV2_NODE}, f"{name}, on a bridge like rosbridge-server-rs", floor
        )
        rs_subjects, rs_sizes = await _nav2_subjects([rs_case], ours_rs)
        await interleave(rs_subjects, Plan(**{**dataclasses.asdict(plan), "block": max(2, plan.block // 4)}))
    cases.append(rs_case)
    subjects += rs_subjects
    sizes.update(rs_sizes)
    return _nav2_rows(ctx, cases, subjects, sizes)


def _nav2_rows(
    ctx: Context, cases: list[Case], subjects: list[Subject], sizes: dict[str, tuple[int, int]]
) -> list[Row]:
    """Item 12's rows: each tool's median over its floor, with its answer's size."""
    ctx.samples.update({subject.key: subject.samples for subject in subjects})
    by_key = {subject.key: subject.stats for subject in subjects}
    rows: list[Row] = []
    for case in cases:
        item, tool, arguments, floor_name = f"12{case.letter}", case.tool, case.arguments, case.floor_name
        stats, floor = by_key[f"n_{item}"], by_key[f"n_{item}_floor"]
        over = stats.median - floor.median
        text_size, structured_size = sizes[item]
        shown = json.dumps(arguments) if arguments else "{}"
        row = timing_row(
            item,
            f"`{tool}` {shown} (text {text_size:,} / structured {structured_size:,} characters)",
            stats,
            versus=f"{over * 1e3:+.2f} ms over {floor_name} ({ms(floor.median)} after a pause)",
            target=f"{allowance(case, floor.median)[1]}; text ≤ 8,000",
        )
        row.verdict = verdict(over <= allowance(case, floor.median)[0] and text_size <= 8_000)
        row.figures.update(
            over_floor_s=over,
            floor_median_s=floor.median,
            text_chars=text_size,
            structured_chars=structured_size,
        )
        rows.append(row)
    return rows


async def _nav2_subjects(cases: list[Case], server: Any) -> tuple[list[Subject], dict[str, tuple[int, int]]]:
    """Each case's floor and tool call as interleaved subjects, and each answer's size (text, structured)."""
    subjects: list[Subject] = []
    sizes: dict[str, tuple[int, int]] = {}
    for case in cases:
        item, tool, arguments, floor_call = f"12{case.letter}", case.tool, case.arguments, case.floor
        # The first call also learns the types, as a session's first call does.
        answer = await server.tool(tool, arguments)
        result = answer["result"]
        text = "".join(block.get("text", "") for block in result["content"])
        sizes[item] = (len(text), len(json.dumps(result.get("structuredContent"))))
        subjects.append(Subject(f"n_{item}_floor", floor_call, pause=TOOL_PAUSE))
        subjects.append(
            Subject(f"n_{item}", lambda tool=tool, arguments=arguments: server.tool(tool, arguments))
        )
    return subjects, sizes
