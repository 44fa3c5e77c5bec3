"""The run: which items, in what order, with what deadline; the shared processes; the table; the CLI."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import dataclasses
import datetime as dt
import json
import logging
import os
import sys
import tempfile
import time
import traceback
from collections.abc import Awaitable, Callable, Sequence
from pathlib import Path
from typing import Any

from websockets.asyncio.client import connect

from benchmarks import __doc__ as PACKAGE_DOC
from benchmarks.arm import measure_arm
from benchmarks.arm_limits import measure_arm_limits
from benchmarks.concurrency import measure_concurrency
from benchmarks.diagnose import measure_diagnose
from benchmarks.edge import measure_edge
from benchmarks.graph import measure_graph_tools
from benchmarks.harness import (
    FULL,
    QUICK,
    Bridge,
    Context,
    RawBridge,
    Row,
    Served,
    bare_server_command,
    cpu_speed_probe,
    describe_machine,
    log,
    our_server_command,
    our_server_on_sdk_stdio_command,
    serve_mcp,
    simulated_robot,
    simulated_robot_process,
)
from benchmarks.internals import RosbridgeClient
from benchmarks.latency import measure_latency
from benchmarks.memory import measure_memory
from benchmarks.nav2 import measure_nav2
from benchmarks.recording import measure_recording
from benchmarks.recording_bombs import measure_recording_bombs
from benchmarks.startup import measure_startup
from benchmarks.stops import measure_stops
from benchmarks.streamable_http import measure_http
from benchmarks.tasks import measure_tasks
from benchmarks.throughput import measure_throughput
from benchmarks.view import measure_view
from benchmarks.watch import measure_watch

__all__ = ["ITEMS", "main"]

Item = Callable[[Context], Awaitable[list[Row]]]
#: name for --only, item numbers, title, the measuring function, its deadline in seconds.
ITEMS: list[tuple[str, str, str, Item, float]] = [
    ("latency", "1-3", "call latency", measure_latency, 240.0),
    ("graph", "8", "graph tools", measure_graph_tools, 240.0),
    ("concurrency", "4", "concurrency", measure_concurrency, 120.0),
    ("throughput", "5", "throughput", measure_throughput, 60.0),
    ("startup", "6-7", "startup and RSS", measure_startup, 180.0),
    ("memory", "7", "memory growth", measure_memory, 300.0),
    ("watch", "9", "watch tools", measure_watch, 240.0),
    ("http", "10", "Streamable HTTP", measure_http, 240.0),
    ("view", "11", "picture tools", measure_view, 240.0),
    ("nav2", "12", "graph tools on a Nav2 robot", measure_nav2, 300.0),
    ("diagnose", "13", "diagnose and the log ring", measure_diagnose, 300.0),
    ("recording", "14", "recording", measure_recording, 300.0),
    ("bombs", "18", "hostile recordings", measure_recording_bombs, 240.0),
    ("edge", "15", "the server alone over the floor (issue 26 item 8)", measure_edge, 300.0),
    ("stops", "16", "stop_robot and reconnects, as the robot sees them", measure_stops, 240.0),
    ("tasks", "17", "tasks/get on a running MCP task", measure_tasks, 120.0),
    ("arm", "19", "the arm: the path check's kinematics, view_arm", measure_arm, 120.0),
    ("arm_limits", "19d", "the arm judge along a goal's path", measure_arm_limits, 60.0),
]


async def run_items(ctx: Context, only: set[str]) -> tuple[list[Row], bool]:
    rows: list[Row] = []
    failed = False
    for name, item, title, measure, deadline in ITEMS:
        if only and name not in only:
            continue
        log.info("item %s: %s", item, title)
        began = time.perf_counter()
        try:
            async with asyncio.timeout(deadline):
                rows.extend(await measure(ctx))
        except Exception as error:  # one item failing must not hide the others' figures
            failed = True
            log.error("item %s (%s) failed:\n%s", item, title, traceback.format_exc())
            rows.append(Row(item, title, verdict=f"**error**: {type(error).__name__}: {error}"))
        log.info("item %s took %.1f s", item, time.perf_counter() - began)
    return rows, failed


async def run(arguments: argparse.Namespace) -> tuple[dict[str, Any], list[Row], bool]:
    plan = QUICK if arguments.quick else FULL
    machine = describe_machine()
    report: dict[str, Any] = {
        "date": dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": machine,
        "plan": dataclasses.asdict(plan),
    }
    errlog_path = Path(tempfile.gettempdir()) / f"bench-servers-{os.getpid()}.log"
    log.info("server and simulated-robot stderr goes to %s", errlog_path)
    failed = True
    try:
        with errlog_path.open("w") as errlog:
            async with contextlib.AsyncExitStack() as stack:
                if arguments.url:
                    url, simulated = arguments.url, False
                else:
                    url, simulated = await stack.enter_async_context(simulated_robot(errlog)), True
                ws = await stack.enter_async_context(connect(url, max_size=None, compression=None))
                raw = RawBridge(ws)
                bridge = await Bridge.probe(raw, url, simulated=simulated)
                report["bridge"] = {"url": url, "simulated": simulated, **dataclasses.asdict(bridge)}
                log.info("bridge at %s offers %s", url, ", ".join(bridge.services) or "none of our services")
                client = await stack.enter_async_context(RosbridgeClient(url))
                await client.wait_connected(10)

                async def served(command: list[str]) -> Served:
                    return await stack.enter_async_context(serve_mcp(command, errlog))

                ctx = Context(
                    plan=plan,
                    bridge=bridge,
                    raw=raw,
                    client=client,
                    ours=await served(our_server_command(url)),
                    reference=await served(bare_server_command(reference_tools=True, our_stdio=True)),
                    reference_sdk=await served(bare_server_command(reference_tools=True)),
                    ours_sdk=await served(our_server_on_sdk_stdio_command(url)),
                    errlog=errlog,
                    bridge_process=simulated_robot_process(url) if simulated else None,
                    ros_mcp=arguments.ros_mcp,
                    node=arguments.node,
                )
                rows, failed = await run_items(ctx, set(arguments.only or ()))
                report["samples"] = ctx.samples
                report["cpu_per_call_s"] = ctx.cpu_per_call
    finally:
        if failed:
            log.warning("kept the servers' and the simulated robot's stderr in %s", errlog_path)
        else:
            errlog_path.unlink(missing_ok=True)
    report["rows"] = [dataclasses.asdict(row) for row in rows]
    return report, rows, failed


def render(report: dict[str, Any], rows: Sequence[Row]) -> str:
    machine = report["machine"]
    versions = machine["versions"]
    bridge = report.get("bridge", {})
    where = (
        "simulated robot in its own process"
        if bridge.get("simulated")
        else f"rosbridge at {bridge.get('url')}"
    )
    lines = [
        f"rosbridge-mcp-server benchmark — {report['date']} — plan `{report['plan']['name']}`",
        "",
        f"- Machine: {machine['cpu']}, {machine['cores']} cores, {machine['memory_gib']} GiB; "
        f"{machine['os']}; {machine['python']}",
        f"- Conditions: load average (1 min) {machine['load_average_at_start'][0]} at start, "
        f"{machine.get('load_average_at_end', ['?'])[0]} at the end; speed probe (a 10⁶-step Python loop, "
        f"lower is faster) {machine['speed_probe_ms_at_start']} ms at start, "
        f"{machine.get('speed_probe_ms_at_end', '?')} ms at the end",
        f"- Code: commit {machine['commit']}; mcp {versions['mcp']}, websockets {versions['websockets']}, "
        f"roslibpy {versions['roslibpy']}",
        f"- Bridge: {where}; the run took {report.get('duration_s', 0):.0f} s",
        "",
        "| # | measurement | n | median | p90 | vs reference | target | verdict |",
        "|---|---|--:|--:|--:|---|---|---|",
    ]
    for row in rows:
        cells = [row.item, row.what, "" if row.n is None else str(row.n), row.median, row.p90, row.versus]
        cells += [row.target, row.verdict]
        lines.append("| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |")
    cpu = report.get("cpu_per_call_s", {})
    if cpu:
        lines += [
            "",
            "CPU time per call of items 1-3, by process (ms; where the work is done, not how long it takes):",
            "",
            "| subject | bench process (client side) | MCP server | rosbridge |",
            "|---|--:|--:|--:|",
        ]
        for key, spent in cpu.items():
            server = "—" if spent["server"] is None else f"{spent['server'] * 1e3:.2f}"
            bridge_cpu = f"{spent['bridge'] * 1e3:.2f}" if bridge.get("simulated") else "n/a"
            lines.append(f"| {key} | {spent['bench'] * 1e3:.2f} | {server} | {bridge_cpu} |")
    return "\n".join(lines)


def item_names(text: str) -> list[str]:
    names = [name.strip() for name in text.split(",") if name.strip()]
    known = [name for name, *_ in ITEMS]
    unknown = [name for name in names if name not in known]
    if unknown or not names:
        raise argparse.ArgumentTypeError(
            f"unknown item {', '.join(unknown) or text!r}; known: {', '.join(known)}"
        )
    return names


def parse_arguments(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=PACKAGE_DOC.split("\n\n")[0] if PACKAGE_DOC else None)
    parser.add_argument(
        "--url", help="measure against this rosbridge (ws://host:port) instead of a simulated robot"
    )
    parser.add_argument(
        "--json", type=Path, metavar="FILE", help="also write every figure and sample to FILE"
    )
    parser.add_argument(
        "--quick", action="store_true", help="tiny repetition counts: a few seconds, for smoke tests"
    )
    parser.add_argument(
        "--only",
        type=item_names,
        metavar="ITEMS",
        help=f"run only these, comma-separated: {','.join(name for name, *_ in ITEMS)} (default all)",
    )
    parser.add_argument(
        "--ros-mcp",
        metavar="PYTHON",
        help="item 15 (edge): also call ros-mcp, installed in the venv of this Python, as a peer",
    )
    parser.add_argument(
        "--node", help="item 15 (edge) with --url: the node get_node_info asks about (default: one it finds)"
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log more to stderr")
    return parser.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    arguments = parse_arguments(argv)
    # Only our own progress at INFO: the MCP SDK, our client and roslibpy's Twisted log every step.
    logging.basicConfig(
        level=logging.WARNING,
        format="bench %(relativeCreated)7.0f ms %(levelname)s %(message)s",
        stream=sys.stderr,
    )
    log.setLevel(logging.DEBUG if arguments.verbose else logging.INFO)
    began = time.perf_counter()
    report, rows, failed = asyncio.run(run(arguments))
    report["duration_s"] = time.perf_counter() - began
    report["machine"]["load_average_at_end"] = [round(load, 2) for load in os.getloadavg()]
    report["machine"]["speed_probe_ms_at_end"] = round(cpu_speed_probe() * 1e3, 1)
    print(render(report, rows))
    if arguments.json:
        arguments.json.write_text(json.dumps(report, indent=2, default=str) + "\n")
        log.info("wrote %s", arguments.json)
    log.info("done in %.0f s%s", report["duration_s"], "; some items errored" if failed else "")
    return 1 if failed else 0
