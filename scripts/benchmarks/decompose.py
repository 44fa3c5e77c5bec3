"""Where the time of one tool call goes: a profiling aid for the misses in docs/performance.md.

    uv run python scripts/benchmarks/decompose.py               # our stdio transport (asyncio pipes)
    uv run python scripts/benchmarks/decompose.py --sdk-stdio   # the MCP SDK's (worker threads)
    uv run python scripts/benchmarks/decompose.py --url ws://127.0.0.1:9090   # a running bridge instead
    uv run python scripts/benchmarks/decompose.py --raw-client  # JSON-RPC lines on the pipes, no client SDK

It starts a simulated robot and ``timed_server.py`` (our unchanged server with stopwatches around
``MCPServer._handle_call_tool`` and ``RosbridgeClient.call_service``), then makes the same tool call
many times, in blocks alternating with the raw-websockets floor, and splits each call's median:

* the floor: one ``call_service`` over a raw websocket from this process;
* rosbridge round trips made inside the server for the call (how many, and their time);
* our code: the server's tool handler minus those round trips (argument validation, the tool module,
  building and serializing the answer);
* the rest: the MCP SDK's request and response path on both sides and the stdio pipes.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from websockets.asyncio.client import connect

__all__ = ["main"]

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # scripts/, so the package imports

from benchmarks import harness as bench

TIMED_SERVER = Path(__file__).resolve().parent / "servers" / "timed_server.py"


def median_ms(samples: list[float]) -> float:
    return statistics.median(samples) * 1e3


async def decompose(
    tool: str,
    arguments: dict[str, Any],
    floor_service: str,
    floor_args: dict[str, Any],
    *,
    calls: int,
    block: int,
    sdk_stdio: bool,
    raw_client: bool,
    url: str,
    errlog: Any,
) -> dict[str, Any]:
    timings = Path(tempfile.gettempdir()) / f"bench-timings-{tool}-{time.time_ns()}.json"
    command = [
        sys.executable,
        str(TIMED_SERVER),
        "--url",
        url,
        *(["--sdk-stdio"] if sdk_stdio else []),
    ]
    observed: list[float] = []
    floor: list[float] = []
    env = {"BENCH_TIMINGS": str(timings)}
    serving = (
        bench.raw_pipe_client(command, errlog, env)
        if raw_client
        else bench.serve_mcp(command, errlog, env=env)
    )
    async with connect(url, compression=None) as ws:
        raw = bench.RawBridge(ws)
        async with serving as served:
            for _ in range(100):  # warm-up, dropped below by keeping only the last `calls` server samples
                await served.tool(tool, arguments)
                await raw.call(floor_service, floor_args)
            while len(observed) < calls:
                for _ in range(block):
                    began = time.perf_counter()
                    await raw.call(floor_service, floor_args)
                    floor.append(time.perf_counter() - began)
                for _ in range(block):
                    began = time.perf_counter()
                    await served.tool(tool, arguments)
                    observed.append(time.perf_counter() - began)
    recorded = json.loads(timings.read_text())
    timings.unlink()
    handler = recorded["handler"][-len(observed) :]
    per_call = round(len(recorded["rosbridge"]) / len(recorded["handler"]))
    trips = recorded["rosbridge"][-len(observed) * per_call :]
    trips_per_call = [sum(trips[i * per_call : (i + 1) * per_call]) for i in range(len(observed))]
    ours = [h - t for h, t in zip(handler, trips_per_call, strict=True)]
    rest = [o - h for o, h in zip(observed, handler, strict=True)]
    return {
        "tool": tool,
        "calls": len(observed),
        "observed_ms": median_ms(observed),
        "floor_ms": median_ms(floor),
        "round_trips_per_call": per_call,
        "round_trips_ms": median_ms(trips_per_call),
        "one_round_trip_ms": median_ms(trips),
        "our_code_ms": median_ms(ours),
        "sdk_and_stdio_ms": median_ms(rest),
    }


async def run(arguments: argparse.Namespace, errlog: Any) -> list[dict[str, Any]]:
    if arguments.url:
        return await run_on(arguments.url, arguments, errlog)
    async with bench.simulated_robot(errlog) as url:
        return await run_on(url, arguments, errlog)


async def run_on(url: str, arguments: argparse.Namespace, errlog: Any) -> list[dict[str, Any]]:
    async with connect(url, compression=None) as ws:
        found = await bench.RawBridge(ws).call("/rosapi/service_type", {"service": bench.ADD_TWO_INTS})
    add = {"a": 2, "b": 3}
    cases = [
        ("list_topics", {}, "/rosapi/topics", {}),
        (
            "publish_service",
            {"service": bench.ADD_TWO_INTS, "service_type": found["type"], "request": add},
            bench.ADD_TWO_INTS,
            add,
        ),
    ]
    return [
        await decompose(
            *case,
            calls=arguments.calls,
            block=50,
            sdk_stdio=arguments.sdk_stdio,
            raw_client=arguments.raw_client,
            url=url,
            errlog=errlog,
        )
        for case in cases
    ]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--calls", type=int, default=1000, help="timed calls per tool (default 1000)")
    parser.add_argument(
        "--sdk-stdio", action="store_true", help="serve stdio through the MCP SDK's transport"
    )
    parser.add_argument("--url", help="a running rosbridge to use instead of a simulated robot")
    parser.add_argument(
        "--raw-client",
        action="store_true",
        help="call through JSON-RPC lines on the pipes instead of the MCP SDK's client (no client-side cost)",
    )
    arguments = parser.parse_args()
    with open(Path(tempfile.gettempdir()) / "bench-decompose.log", "w") as errlog:
        results = asyncio.run(run(arguments, errlog))
    transport = "the SDK's stdio (worker threads)" if arguments.sdk_stdio else "our stdio (asyncio pipes)"
    client = "JSON-RPC lines on the pipes (no client SDK)" if arguments.raw_client else "the MCP SDK's client"
    print(f"medians over {arguments.calls} calls per tool; our server on {transport}; called by {client}")
    print("| tool | observed | floor | rosbridge round trips in the server | our code | MCP SDK + stdio |")
    print("|---|--:|--:|--:|--:|--:|")
    for r in results:
        print(
            f"| `{r['tool']}` | {r['observed_ms']:.2f} ms | {r['floor_ms']:.2f} ms | "
            f"{r['round_trips_per_call']} × {r['one_round_trip_ms']:.2f} ms = {r['round_trips_ms']:.2f} ms | "
            f"{r['our_code_ms']:.2f} ms | {r['sdk_and_stdio_ms']:.2f} ms |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
