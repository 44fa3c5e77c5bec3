"""Benchmark rosbridge-mcp-server against the raw rosbridge floor, every figure a ratio taken in one run.

    uv run python scripts/bench.py                       # against a simulated robot in its own process
    uv run python scripts/bench.py --url ws://robot:9090 # against any rosbridge (sim-only rows become n/a)
    uv run python scripts/bench.py --quick               # tiny counts, ~10 s (the smoke test)
    uv run python scripts/bench.py --only latency        # some items: latency, concurrency, throughput, ...
    uv run python scripts/bench.py --json bench-$(date -u +%Y%m%d-%H%M).json

The machines we run on are shared and noisy, so nothing is compared with a number from another run: each
subject is measured next to its reference in the same run, in interleaved blocks (A B C A B C ..., with the
order rotated every round) after warm-up rounds, and reported as median, p90 and the ratio of the medians.

What is measured:

1. the floor: ``call_service /rosapi/topics`` over one raw ``websockets`` connection;
2. the same call through our ``RosbridgeClient`` and through roslibpy;
3. ``list_topics`` and ``publish_service /add_two_ints`` through a real MCP stdio session with the console
   script, next to the same SDK's cost for a tool that does nothing (``scripts/bench/bare_server.py``),
   and, for comparison, all three again on the MCP SDK's own stdio transport instead of ours;
4. 100 tool calls at once in one session against a 50 ms service, against 100 in a row;
5. 1 000 messages of the 1 kHz topic: how many were lost; a camera frame as an MCP image; a PNG
   decompression bomb (13000² at 16 bits in ~330 kB) refused by ``get_image``, with the server's peak RSS
   growth while it is;
6. spawn → ``initialize`` → ``tools/list``, against a bare ``MCPServer`` started the same way;
7. RSS after startup and its growth over 10 000 tool calls, against the same bare server;
8. the graph tools against the raw rosapi round trips each needs (``--only graph``; meant for real bridges).
9. the watch tools: ``get_image`` on a live 640×480 and 1920×1080 rgb8 camera and
   ``subscribe_topic`` count 1 on a live topic, each against a raw subscribe → first message → unsubscribe
   started at the same point of the publisher's cycle; a 10 Hz × 5 s ``publish_topic`` stream as the robot
   receives it; the size of ``tools/list`` with every tool and with the original eight.
10. Streamable HTTP (``--only http``): ``list_topics`` over HTTP with a bearer token against the same call
    over stdio, interleaved, and 100 HTTP sessions opened at once (initialize + one call each), all working.
11. the picture tools (``--only view``): ``view_map`` on a 2000×2000 ``/map`` against a raw socket's receipt
    of the same message (subscribe → every fragment → parsed → unsubscribe), ``view_scan`` against a raw first
    scan (phase-locked to the 5 Hz laser), and the PNG sizes of their pictures and of a ``plot_topic`` chart.
12. every graph tool on a simulated Nav2 robot (``--only nav2``; ~36 nodes, ~400 services, 1,000+
    parameters), the server alone (JSON-RPC lines), against the raw calls its answer needs, with the size of
    each answer's text and structured content; ``get_node_info`` also on the same world behaving like
    rosbridge-server-rs (row 12k: one round trip, no node list first).
13. ``diagnose`` (``--only diagnose``) on the simulated Nav2 world, healthy and with two faults, through the
    console script (p50 against its 1.5 s target); and the log ring under 10,000 ``/rosout`` lines a second
    for 10 s from a simulated robot in this process: lines received, kept, dropped, and the RSS along the way.
14. recording (``--only recording``): ``record`` of a Nav2-like load (scan, odom, tf, a 640×480 camera)
    against what a raw subscriber received, ``list_topics`` while it records against idle, and the summary
    time of a large recording (from the MCAP index).

The table goes to stdout (Markdown, so it can be pasted into docs/performance.md), progress to stderr.
The exit status is 0 when every measurement ran, whatever the figures; 1 when something errored.
"""

from __future__ import annotations

import argparse
import asyncio
import base64
import contextlib
import dataclasses
import datetime as dt
import importlib.metadata
import itertools
import json
import logging
import math
import os
import platform
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import traceback
from collections.abc import AsyncIterator, Awaitable, Callable, Sequence
from pathlib import Path
from typing import IO, Any
from urllib.parse import urlsplit

import cbor2
import httpx2
import mcp_types
import psutil
import roslibpy
from mcp.client.session import ClientSession
from mcp.client.stdio import StdioServerParameters, stdio_client
from mcp.client.streamable_http import streamable_http_client
from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.robot.known_types import infrastructure_types
from rosbridge_mcp_server.sim.png import png_bomb

__all__ = ["main"]

log = logging.getLogger("bench")

REPO = Path(__file__).resolve().parent.parent
BARE_SERVER = Path(__file__).resolve().parent / "bench" / "bare_server.py"
OURS_SDK_STDIO = Path(__file__).resolve().parent / "bench" / "ours_sdk_stdio.py"
CONSOLE_SCRIPT = "rosbridge-mcp-server"

#: What the simulated robot offers for items 3-5 (and a rosbridge given with --url may not).
ADD_TWO_INTS = "/add_two_ints"
SLOW_SERVICE = "/slow_service"
SLOW_SERVICE_SECONDS = 0.05
FAST_TOPIC = "/fast_counter"
#: The camera of items 5 and 9 (the simulated robot's, at this size; item 9 also starts one at full HD).
CAMERA_TOPIC = "/camera/image_raw"
CAMERA_SIZE = "640x480"
FULL_HD = "1920x1080"
#: Item 9: a live 10 Hz topic, and a velocity topic for the publish stream.
CHATTER = "/chatter"
CMD_VEL = "/turtle1/cmd_vel"

MIB = 1024 * 1024


# ----------------------------------------------------------------------------------------------- the plan


@dataclasses.dataclass(frozen=True)
class Plan:
    """How many repetitions of everything; ``FULL`` stays under ~2 minutes on a 2-core machine."""

    name: str
    warmup: int  # calls per latency subject before any is timed
    rounds: int  # interleaved rounds of the latency subjects
    block: int  # calls per subject per round
    parallel_calls: int  # item 4
    concurrency_rounds: int
    messages: int  # item 5
    startup_warmup: int  # item 6: untimed spawns of each server first (page cache, .pyc files)
    startup_rounds: int  # item 6: timed spawns of each server
    memory_calls: int  # item 7
    memory_batch: int  # tool calls in flight at once while churning through memory_calls


FULL = Plan(
    name="full",
    warmup=50,
    rounds=20,
    block=20,
    parallel_calls=100,
    concurrency_rounds=2,
    messages=1000,
    startup_warmup=1,
    startup_rounds=8,
    memory_calls=10_000,
    memory_batch=50,
)
QUICK = Plan(
    name="quick",
    warmup=3,
    rounds=2,
    block=5,
    parallel_calls=10,
    concurrency_rounds=1,
    messages=100,
    startup_warmup=0,
    startup_rounds=1,
    memory_calls=200,
    memory_batch=20,
)


# -------------------------------------------------------------------------------------- figures and rows


@dataclasses.dataclass(frozen=True)
class Stats:
    """Median and p90 (nearest rank) of a set of samples, in the samples' unit."""

    n: int
    median: float
    p90: float

    @classmethod
    def of(cls, samples: Sequence[float]) -> Stats:
        if not samples:
            raise ValueError("no samples")
        ordered = sorted(samples)
        rank = max(1, math.ceil(0.9 * len(ordered)))
        return cls(n=len(ordered), median=statistics.median(ordered), p90=ordered[rank - 1])


@dataclasses.dataclass
class Row:
    """One line of the table; ``figures`` holds the raw numbers for --json."""

    item: str
    what: str
    n: int | None = None
    median: str = ""
    p90: str = ""
    versus: str = ""
    target: str = ""
    verdict: str = ""
    figures: dict[str, Any] = dataclasses.field(default_factory=dict)


def ms(seconds: float) -> str:
    """A duration for the table: two decimals of ms below 10 ms, one below 1 s, then seconds."""
    if seconds >= 10:
        return f"{seconds:.1f} s"
    if seconds >= 1:
        return f"{seconds:.2f} s"
    if seconds >= 0.01:
        return f"{seconds * 1e3:.1f} ms"
    return f"{seconds * 1e3:.2f} ms"


def mib(size: float) -> str:
    return f"{size / MIB:.1f} MiB"


def verdict(met: bool) -> str:
    return "met" if met else "**MISSED**"


def timing_row(item: str, what: str, stats: Stats, **extra: Any) -> Row:
    row = Row(item=item, what=what, n=stats.n, median=ms(stats.median), p90=ms(stats.p90), **extra)
    row.figures.update(median_s=stats.median, p90_s=stats.p90, n=stats.n)
    return row


# ------------------------------------------------------------------------------------------- the machine


def cpu_speed_probe() -> float:
    """Seconds for a fixed pure-Python loop (best of 5): how fast this shared machine runs right now.

    The same machine runs everything up to ~1.5x slower at some moments than at others (neighbours on the
    host); absolute figures from two runs compare only when their probes agree.
    """
    best = math.inf
    for _ in range(5):
        began = time.perf_counter()
        total = 0
        for number in range(1_000_000):
            total += number & 7
        best = min(best, time.perf_counter() - began)
    return best


def describe_machine() -> dict[str, Any]:
    """CPU model, cores, memory, OS, Python and the versions of what is being measured."""
    cpu = platform.processor()
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    versions = {}
    for package in ("mcp", "websockets", "roslibpy", "pydantic", "rosbridge-mcp-server"):
        try:
            versions[package] = importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            versions[package] = "not installed"
    commit = "unknown"
    with contextlib.suppress(OSError, subprocess.SubprocessError):
        found = subprocess.run(
            ["git", "-C", str(REPO), "describe", "--always", "--dirty"],
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        )
        commit = found.stdout.strip()
    return {
        "cpu": cpu or "unknown",
        "cores": os.cpu_count(),
        "memory_gib": round(psutil.virtual_memory().total / 2**30, 1),
        "os": platform.platform(),
        "python": f"{platform.python_implementation()} {platform.python_version()}",
        "load_average_at_start": [round(load, 2) for load in os.getloadavg()],
        "speed_probe_ms_at_start": round(cpu_speed_probe() * 1e3, 1),
        "versions": versions,
        "commit": commit,
    }


# ------------------------------------------------------------------------------------- the rosbridge side


def free_port() -> int:
    # The sim takes a fixed --port; a port the kernel just handed out is free for the moment it takes to
    # start, and a clash shows up as the sim exiting before it listens (reported with its stderr).
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


async def wait_for_port(host: str, port: int, process: asyncio.subprocess.Process, deadline: float) -> None:
    """Poll until something accepts TCP connections on host:port (the sim prints nothing we rely on)."""
    loop = asyncio.get_running_loop()
    while True:
        if process.returncode is not None:
            raise RuntimeError(
                f"the simulated robot exited with status {process.returncode} before listening"
            )
        try:
            _, writer = await asyncio.open_connection(host, port)
        except OSError:
            if loop.time() > deadline:
                raise TimeoutError(f"the simulated robot did not listen on {host}:{port} in time") from None
            await asyncio.sleep(0.05)
            continue
        writer.close()
        with contextlib.suppress(OSError):
            await writer.wait_closed()
        return


def tail(errlog: IO[str], lines: int = 15) -> str:
    """The last lines written to the shared stderr log of the servers and the simulated robot."""
    errlog.flush()
    try:
        return "\n".join(Path(errlog.name).read_text(errors="replace").splitlines()[-lines:])
    except OSError:
        return "(unreadable)"


@contextlib.asynccontextmanager
async def simulated_robot(
    errlog: IO[str],
    *,
    fast_topic: bool = False,
    camera_size: str = CAMERA_SIZE,
    map_cells: int | None = None,
    world: str = "turtle",
    server: str = "rosbridge_suite",
    faults: str = "",
) -> AsyncIterator[str]:
    """Run ``python -m rosbridge_mcp_server.sim`` in its own process; yield its URL.

    The 1 kHz topic is a separate robot's (``fast_topic``): its publishing loop costs the sim ~6 % of a core
    even with nobody subscribed, which would blur the CPU figures of everything else.
    """
    port = free_port()
    command = [
        sys.executable,
        "-m",
        "rosbridge_mcp_server.sim",
        "--port",
        str(port),
        *(["--fast-topic"] if fast_topic else []),
        "--slow-service-seconds",
        str(SLOW_SERVICE_SECONDS),
        "--camera-size",
        camera_size,
        *(["--map-cells", str(map_cells)] if map_cells else []),
        "--world",
        world,
        *(["--server", server] if server != "rosbridge_suite" else []),
        *(["--fault", faults] if faults else []),
        "--log-level",
        "WARNING",
    ]
    log.info("starting the simulated robot: %s", " ".join(command[1:]))
    process = await asyncio.create_subprocess_exec(
        *command, stdin=asyncio.subprocess.DEVNULL, stdout=errlog, stderr=errlog, cwd=REPO
    )
    try:
        try:
            await wait_for_port("127.0.0.1", port, process, asyncio.get_running_loop().time() + 30)
        except (RuntimeError, TimeoutError) as error:
            raise RuntimeError(f"{error}; the end of its stderr:\n{tail(errlog)}") from None
        yield f"ws://127.0.0.1:{port}"
    finally:
        if process.returncode is None:
            process.terminate()
            try:
                await asyncio.wait_for(process.wait(), 5)
            except TimeoutError:
                process.kill()
                await process.wait()


def simulated_robot_process(url: str) -> psutil.Process | None:
    """Our child process serving ``url``, to read its CPU time."""
    port = str(urlsplit(url).port)
    for child in psutil.Process().children():
        with contextlib.suppress(psutil.Error):
            command = child.cmdline()
            if "rosbridge_mcp_server.sim" in command and port in command:
                return child
    return None


class RawBridge:
    """The floor: one raw websockets connection, one JSON object per frame, nothing else in the way."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        self._ids = 0

    def _next_id(self) -> str:
        self._ids += 1
        return f"bench:{self._ids}"

    async def call(self, service: str, args: dict[str, Any] | None = None) -> Any:
        request_id = self._next_id()
        await self.ws.send(
            json.dumps({"op": "call_service", "id": request_id, "service": service, "args": args or {}})
        )
        while True:
            reply = json.loads(await self.ws.recv())
            if reply.get("op") == "service_response" and reply.get("id") == request_id:
                if reply.get("result") is False:
                    raise RuntimeError(f"{service} failed: {reply.get('values')}")
                return reply.get("values")

    async def call_parallel(self, service: str, count: int, args: dict[str, Any] | None = None) -> None:
        """Send ``count`` calls back to back, then wait for every reply."""
        pending = set()
        for _ in range(count):
            request_id = self._next_id()
            pending.add(request_id)
            await self.ws.send(
                json.dumps({"op": "call_service", "id": request_id, "service": service, "args": args or {}})
            )
        while pending:
            reply = json.loads(await self.ws.recv())
            if reply.get("op") == "service_response" and reply.get("id") in pending:
                if reply.get("result") is False:
                    raise RuntimeError(f"{service} failed: {reply.get('values')}")
                pending.discard(reply["id"])

    async def collect(self, topic: str, msg_type: str, count: int) -> list[dict[str, Any]]:
        subscription = self._next_id()
        await self.ws.send(
            json.dumps({"op": "subscribe", "id": subscription, "topic": topic, "type": msg_type})
        )
        messages: list[dict[str, Any]] = []
        try:
            while len(messages) < count:
                frame = json.loads(await self.ws.recv())
                if frame.get("op") == "publish" and frame.get("topic") == topic:
                    messages.append(frame["msg"])
        finally:
            await self.ws.send(json.dumps({"op": "unsubscribe", "id": subscription, "topic": topic}))
        return messages


@dataclasses.dataclass
class Bridge:
    """What the bridge under test offers, looked up once through rosapi over the raw connection."""

    url: str
    simulated: bool
    services: dict[str, str]  # name -> type, for the services the benchmark uses
    topics: dict[str, str]  # name -> type

    @classmethod
    async def probe(cls, raw: RawBridge, url: str, *, simulated: bool) -> Bridge:
        listed = await raw.call("/rosapi/topics")
        topics = dict(zip(listed.get("topics", []), listed.get("types", []), strict=False))
        services: dict[str, str] = {}
        offered = set((await raw.call("/rosapi/services")).get("services", []))
        for name in (ADD_TWO_INTS, SLOW_SERVICE):
            if name in offered:
                services[name] = (await raw.call("/rosapi/service_type", {"service": name})).get("type", "")
        return cls(url=url, simulated=simulated, services=services, topics=topics)


# ------------------------------------------------------------------------------------------- MCP sessions


@dataclasses.dataclass
class Served:
    """An MCP server process on stdio with an initialized session."""

    session: ClientSession
    process: psutil.Process
    initialize_s: float  # spawn -> initialize answered
    tools_list_s: float  # spawn -> tools/list answered
    tools: dict[str, mcp_types.Tool]

    def rss(self) -> int:
        rss: int = self.process.memory_info().rss
        return rss

    async def tool(self, name: str, arguments: dict[str, Any]) -> mcp_types.CallToolResult:
        result = await self.session.call_tool(name, arguments)
        if result.is_error:
            text = " ".join(getattr(block, "text", "") for block in result.content)
            raise RuntimeError(f"tool {name} answered with an error: {text}")
        return result


def our_server_command(url: str) -> list[str]:
    """The console script, as an MCP client such as Claude Desktop starts it."""
    script = Path(sys.executable).parent / CONSOLE_SCRIPT
    found = str(script) if script.exists() else shutil.which(CONSOLE_SCRIPT)
    if found is None:
        raise FileNotFoundError(f"the console script {CONSOLE_SCRIPT} is not installed (run `uv sync`)")
    return [found, "--url", url]


def bare_server_command(*, reference_tools: bool = False, our_stdio: bool = False) -> list[str]:
    flags = [
        flag
        for flag, wanted in (("--reference-tools", reference_tools), ("--our-stdio", our_stdio))
        if wanted
    ]
    return [sys.executable, str(BARE_SERVER), *flags]


def our_server_on_sdk_stdio_command(url: str) -> list[str]:
    """Our server on the MCP SDK's stdio transport instead of its own (``bench/ours_sdk_stdio.py``)."""
    return [sys.executable, str(OURS_SDK_STDIO), "--url", url]


@contextlib.asynccontextmanager
async def serve_mcp(
    command: list[str], errlog: IO[str], env: dict[str, str] | None = None
) -> AsyncIterator[Served]:
    """Spawn an MCP server, run ``initialize`` and ``tools/list``, and time both from the spawn."""
    me = psutil.Process()
    before = {child.pid for child in me.children()}
    params = StdioServerParameters(command=command[0], args=command[1:], cwd=str(REPO), env=env)
    started = time.perf_counter()
    async with stdio_client(params, errlog=errlog) as (read, write), ClientSession(read, write) as session:
        try:
            async with asyncio.timeout(60):
                await session.initialize()
                initialized = time.perf_counter()
                listed = await session.list_tools()
                tools_listed = time.perf_counter()
        except Exception as error:
            raise RuntimeError(
                f"{' '.join(command)} did not start ({type(error).__name__}: {error}); "
                f"the end of its stderr:\n{tail(errlog)}"
            ) from error
        spawned = [child for child in me.children() if child.pid not in before]
        if len(spawned) != 1:
            raise RuntimeError(f"expected one new server process, found {[p.pid for p in spawned]}")
        yield Served(
            session=session,
            process=spawned[0],
            initialize_s=initialized - started,
            tools_list_s=tools_listed - started,
            tools={tool.name: tool for tool in listed.tools},
        )


class RawPipeClient:
    """An MCP client reduced to JSON-RPC lines on the server's pipes: no SDK, no validation on this side."""

    def __init__(self, process: asyncio.subprocess.Process) -> None:
        self._process = process
        self._ids = 0

    async def request(self, method: str, params: dict[str, Any]) -> dict[str, Any]:
        assert self._process.stdin is not None
        assert self._process.stdout is not None
        self._ids += 1
        line = {"jsonrpc": "2.0", "id": self._ids, "method": method, "params": params}
        self._process.stdin.write(json.dumps(line).encode() + b"\n")
        while True:
            answer: dict[str, Any] = json.loads(await self._process.stdout.readline())
            if answer.get("id") == self._ids:
                return answer  # notifications (progress, logging) are skipped

    async def tool(self, name: str, arguments: dict[str, Any]) -> dict[str, Any]:
        answer = await self.request("tools/call", {"name": name, "arguments": arguments})
        if "error" in answer or answer["result"].get("isError"):
            raise RuntimeError(f"tool {name} failed: {answer}")
        return answer


@contextlib.asynccontextmanager
async def raw_pipe_client(
    command: list[str], errlog: Any, env: dict[str, str]
) -> AsyncIterator[RawPipeClient]:
    """Spawn the server and do the initialize handshake by hand."""
    process = await asyncio.create_subprocess_exec(
        *command,
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
        stderr=errlog,
        env={**os.environ, **env},
        limit=64 * 1024 * 1024,
    )
    client = RawPipeClient(process)
    try:
        info = {"name": "bench", "version": "0"}
        hello = {"protocolVersion": "2025-06-18", "capabilities": {}, "clientInfo": info}
        await client.request("initialize", hello)
        assert process.stdin is not None
        process.stdin.write(b'{"jsonrpc": "2.0", "method": "notifications/initialized"}\n')
        yield client
    finally:
        if process.stdin is not None:
            process.stdin.close()
        try:
            await asyncio.wait_for(process.wait(), 5)
        except TimeoutError:
            process.kill()
            await process.wait()


def publish_service_arguments(
    served: Served, service: str, service_type: str, request: dict[str, Any]
) -> dict[str, Any]:
    """Arguments for the ``publish_service`` tool; optional fields are left to the tool's defaults."""
    arguments: dict[str, Any] = {"service": service, "service_type": service_type, "request": request}
    schema = served.tools["publish_service"].input_schema
    return {key: value for key, value in arguments.items() if key in schema.get("properties", arguments)}


# ------------------------------------------------------------------------------- item 1-3: call latency


def cpu_seconds(process: psutil.Process | None) -> float:
    """CPU time a process has had so far, every thread summed (0 for one we cannot see, e.g. a remote bridge).

    Linux's per-thread schedstat counts nanoseconds; elsewhere psutil's user + system time, which the kernel
    counts in 10 ms ticks (good enough over many blocks for the slow subjects, not for the floor).
    """
    if process is None:
        return 0.0
    try:
        nanoseconds = 0
        for task in os.scandir(f"/proc/{process.pid}/task"):
            with open(f"{task.path}/schedstat") as stat:
                nanoseconds += int(stat.read().split()[0])
        return nanoseconds / 1e9
    except (OSError, ValueError, IndexError):
        times = process.cpu_times()
        return float(times.user + times.system)


@dataclasses.dataclass
class Subject:
    """One thing whose latency is sampled, call by call, with the CPU each process spent on it."""

    key: str
    call: Callable[[], Awaitable[object]]
    server: psutil.Process | None = None  # the MCP server process the calls go through, if any
    pause: float = 0.0  # idle seconds before each call, not timed (a tool call's rosapi request follows one)
    samples: list[float] = dataclasses.field(default_factory=list)
    cpu: dict[str, float] = dataclasses.field(
        default_factory=lambda: {"bench": 0.0, "server": 0.0, "bridge": 0.0}
    )

    @property
    def stats(self) -> Stats:
        return Stats.of(self.samples)

    def cpu_per_call(self) -> dict[str, float | None]:
        spent = {where: total / len(self.samples) for where, total in self.cpu.items()}
        return spent | ({} if self.server else {"server": None})


async def interleave(subjects: Sequence[Subject], plan: Plan, bridge: psutil.Process | None = None) -> None:
    """Warm every subject up, then time them in rotated A/B/C blocks so drift hits all of them alike.

    CPU time is read around each block: where the work of a call is done, as well as how long it takes.
    """
    for subject in subjects:
        for _ in range(plan.warmup):
            await subject.call()
    me = psutil.Process()
    clock = time.perf_counter
    for round_number in range(plan.rounds):
        shift = round_number % len(subjects)
        for subject in [*subjects[shift:], *subjects[:shift]]:
            call, samples = subject.call, subject.samples
            before = (cpu_seconds(me), cpu_seconds(subject.server), cpu_seconds(bridge))
            for _ in range(plan.block):
                if subject.pause:
                    await asyncio.sleep(subject.pause)
                began = clock()
                await call()
                samples.append(clock() - began)
            after = (cpu_seconds(me), cpu_seconds(subject.server), cpu_seconds(bridge))
            for where, start, end in zip(("bench", "server", "bridge"), before, after, strict=True):
                subject.cpu[where] += end - start


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


# ------------------------------------------------------------------------------- item 8: the graph tools

#: Fresh servers for list_services' first call (each spawn is ~1 s; the call itself is what is timed).
FIRST_CALL_SERVERS = {"full": 6, "quick": 1}
#: The least time between a server connecting and a model's first tool call: initialize, tools/list and one
#: model turn. The server learns the service types meanwhile (robot/warm_up.py).
FIRST_TURN = 1.0
GRAPH_TOPIC = "/rosout"
#: The rows of tool calls made by JSON-RPC lines on the pipes instead of the MCP SDK's client.
BARE = "the same called by JSON-RPC lines (the server alone, without the MCP client SDK's work)"
#: An MCP round trip's worth of idle before a floor call (the no-op tool's median on this machine).
TOOL_PAUSE = 0.001


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
    first, at_once, first_floor = await first_listings(ctx)
    ctx.samples.update(
        {subject.key: subject.samples for subject in subjects}
        | {
            "g_list_services_first": first,
            "g_list_services_at_once": at_once,
            "g_floor_services_first": first_floor,
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
        ratio_row(
            "8b",
            f"tool `list_services`, a session's first call, {FIRST_TURN:g} s after connecting (fresh server)",
            first_stats,
            3.0,
        ),
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


# ------------------------------------------------------------------------------- item 10: the Nav2 world

#: Item 10: the tools a model uses first on a Nav2 robot, with the arguments it would give.
NAV2_NODE = "/controller_server"
NAV2_PARAMETER = "FollowPath.vx_max"


class ManyCalls:
    """Several rosapi or node calls sent at once on one raw connection, their replies awaited together."""

    def __init__(self, raw: RawBridge) -> None:
        self.raw = raw

    async def __call__(self, calls: Sequence[tuple[str, dict[str, Any]]]) -> None:
        pending = set()
        for service, args in calls:
            request_id = self.raw._next_id()
            pending.add(request_id)
            await self.raw.ws.send(
                json.dumps({"op": "call_service", "id": request_id, "service": service, "args": args})
            )
        while pending:
            reply = json.loads(await self.raw.ws.recv())
            if reply.get("op") == "service_response" and reply.get("id") in pending:
                pending.discard(reply["id"])


#: A row of item 12: (item, tool, arguments, what its floor is, the floor's raw calls).
_Nav2Case = tuple[str, str, dict[str, Any], str, Callable[[], Awaitable[object]]]


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
        many = ManyCalls(raw)
        ours = await stack.enter_async_context(raw_pipe_client(our_server_command(url), ctx.errlog, {}))
        services = (await raw.call("/rosapi/services"))["services"]
        parameter_nodes = [
            name.removesuffix("/list_parameters") for name in services if name.endswith("/list_parameters")
        ]
        topic = {"topic": "/scan"}

        # A bridge that answers refusals with status ops (rosbridge-server-rs, given with --url) needs no node
        # list before node_details, and lists every parameter with one get_param_names: so does our server.
        status_replies = (await ctx.client.dialect()).info.status_replies

        async def node_info_floor() -> None:
            if not status_replies:
                await raw.call("/rosapi/nodes")
            await asyncio.gather(
                raws[1].call("/rosapi/node_details", {"node": NAV2_NODE}), raws[2].call("/rosapi/topics")
            )

        async def topic_info_floor() -> None:
            await asyncio.gather(
                *(
                    bridge.call(f"/rosapi/{leaf}", topic)
                    for bridge, leaf in zip(raws, ("topic_type", "publishers", "subscribers"), strict=True)
                )
            )

        async def all_parameters_floor() -> None:
            if status_replies:
                await raw.call("/rosapi/get_param_names")
                return
            await raw.call("/rosapi/services")
            await many(
                [(f"{node}/list_parameters", {"prefixes": [], "depth": 0}) for node in parameter_nodes]
            )

        cases: list[_Nav2Case] = [
            ("12a", "list_topics", {}, "`topics`", lambda: raw.call("/rosapi/topics")),
            ("12b", "list_services", {}, "`services`", lambda: raw.call("/rosapi/services")),
            ("12c", "list_actions", {}, "`action_servers`", lambda: raw.call("/rosapi/action_servers")),
            ("12d", "list_nodes", {}, "`nodes`", lambda: raw.call("/rosapi/nodes")),
            (
                "12e",
                "list_parameters",
                {"node": NAV2_NODE},
                "the node's `list_parameters`",
                lambda: raw.call(f"{NAV2_NODE}/list_parameters", {"prefixes": [], "depth": 0}),
            ),
            (
                "12f",
                "list_parameters",
                {},
                "`get_param_names`"
                if status_replies
                else f"`services`, then {len(parameter_nodes)} nodes' `list_parameters` at once",
                all_parameters_floor,
            ),
            (
                "12g",
                "get_parameter",
                {"name": f"{NAV2_NODE}:{NAV2_PARAMETER}"},
                "the node's `get_parameters`",
                lambda: raw.call(f"{NAV2_NODE}/get_parameters", {"names": [NAV2_PARAMETER]}),
            ),
            (
                "12h",
                "get_node_info",
                {"node": NAV2_NODE},
                "`node_details` and `topics` side by side"
                if status_replies
                else "`nodes`, then `node_details` and `topics` side by side",
                node_info_floor,
            ),
            ("12i", "get_topic_info", topic, "3 look-ups side by side", topic_info_floor),
            (
                "12j",
                "describe_type",
                {"type_name": "nav_msgs/msg/OccupancyGrid"},
                "`message_details`",
                lambda: raw.call("/rosapi/message_details", {"type": "nav_msgs/msg/OccupancyGrid"}),
            ),
        ]
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

        async def node_info_rs_floor() -> None:
            details = rs_raws[0].call("/rosapi/node_details", {"node": NAV2_NODE})
            await asyncio.gather(details, rs_raws[1].call("/rosapi/topics"))

        rs_case: _Nav2Case = (
            "12k",
            "get_node_info",
            {"node": NAV2_NODE},
            "`node_details` and `topics` side by side, on a bridge like rosbridge-server-rs",
            node_info_rs_floor,
        )
        rs_subjects, rs_sizes = await _nav2_subjects([rs_case], ours_rs)
        await interleave(rs_subjects, Plan(**{**dataclasses.asdict(plan), "block": max(2, plan.block // 4)}))
    cases.append(rs_case)
    subjects += rs_subjects
    sizes.update(rs_sizes)
    return _nav2_rows(ctx, cases, subjects, sizes)


def _nav2_rows(
    ctx: Context, cases: list[_Nav2Case], subjects: list[Subject], sizes: dict[str, tuple[int, int]]
) -> list[Row]:
    """Item 12's rows: each tool's median over its floor, with its answer's size."""
    ctx.samples.update({subject.key: subject.samples for subject in subjects})
    by_key = {subject.key: subject.stats for subject in subjects}
    rows: list[Row] = []
    for item, tool, arguments, floor_name, _ in cases:
        stats, floor = by_key[f"n_{item}"], by_key[f"n_{item}_floor"]
        over = stats.median - floor.median
        text_size, structured_size = sizes[item]
        shown = json.dumps(arguments) if arguments else "{}"
        row = timing_row(
            item,
            f"`{tool}` {shown} (text {text_size:,} / structured {structured_size:,} characters)",
            stats,
            versus=f"{over * 1e3:+.2f} ms over {floor_name} ({ms(floor.median)} after a pause)",
            target="≤ +1.5 ms over its floor; text ≤ 8,000",
        )
        row.verdict = verdict(over <= 1.5e-3 and text_size <= 8_000)
        row.figures.update(
            over_floor_s=over,
            floor_median_s=floor.median,
            text_chars=text_size,
            structured_chars=structured_size,
        )
        rows.append(row)
    return rows


async def _nav2_subjects(
    cases: list[_Nav2Case], server: Any
) -> tuple[list[Subject], dict[str, tuple[int, int]]]:
    """Each case's floor and tool call as interleaved subjects, and each answer's size (text, structured)."""
    subjects: list[Subject] = []
    sizes: dict[str, tuple[int, int]] = {}
    for item, tool, arguments, _, floor_call in cases:
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


async def look_up_types(bridge: RawBridge, queue: list[str]) -> None:
    """Take services off *queue* and ask their types, one at a time on *bridge*, until none is left."""
    while queue:
        await bridge.call("/rosapi/service_type", {"service": queue.pop()})


async def probe_types(bridge: RawBridge, queue: list[str]) -> None:
    """Take services off *queue* and call each with a field no request has (the bridge refuses, naming it)."""
    while queue:
        with contextlib.suppress(RuntimeError):
            await bridge.call(queue.pop(), {"__type_probe__": 0})


async def first_listings(ctx: Context) -> tuple[list[float], list[float], list[float]]:
    """list_services on fresh servers, as a model's first call and at once after connecting, and the same
    rosapi round trips from a fresh raw client, in turn."""
    url, errlog = ctx.bridge.url, ctx.errlog
    first: list[float] = []
    at_once: list[float] = []
    floor: list[float] = []
    for _ in range(FIRST_CALL_SERVERS[ctx.plan.name]):
        for turn, samples in ((FIRST_TURN, first), (0.0, at_once)):
            async with serve_mcp(our_server_command(url), errlog) as fresh:
                await fresh.tool("list_topics", {})  # the connection is up and the bridge's kind known
                await asyncio.sleep(turn)  # not a synchronisation: the model's turn being modelled
                began = time.perf_counter()
                await fresh.tool("list_services", {})
                samples.append(time.perf_counter() - began)
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
    return first, at_once, floor


# ------------------------------------------------------------------------------------ item 4: concurrency


async def wall_time(action: Callable[[], Awaitable[object]]) -> float:
    began = time.perf_counter()
    await action()
    return time.perf_counter() - began


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


# ------------------------------------------------------------------------------- item 10: Streamable HTTP

HTTP_TOKEN = "bench-token-0123456789abcdef0123"


@contextlib.asynccontextmanager
async def http_server(url: str, errlog: IO[str]) -> AsyncIterator[tuple[str, psutil.Process]]:
    """Our console script on Streamable HTTP (loopback, a free port, a bearer token): its URL and process."""
    command = [*our_server_command(url), "--transport", "http", "--bind", "127.0.0.1:0"]
    env = {**os.environ, "ROSBRIDGE_MCP_AUTH_TOKENS": f"bench {HTTP_TOKEN}"}
    process = await asyncio.create_subprocess_exec(
        *command, cwd=str(REPO), env=env, stdin=asyncio.subprocess.DEVNULL, stderr=asyncio.subprocess.PIPE
    )
    assert process.stderr is not None
    draining: asyncio.Task[None] | None = None
    try:
        async with asyncio.timeout(60):
            while True:
                line = (await process.stderr.readline()).decode(errors="replace")
                if not line:
                    raise RuntimeError("the HTTP server exited before it listened")
                errlog.write(line)
                if "serving MCP on " in line:
                    served_at = line.split("serving MCP on ", 1)[1].split()[0]
                    break

        async def drain() -> None:
            assert process.stderr is not None
            while chunk := await process.stderr.readline():
                errlog.write(chunk.decode(errors="replace"))

        draining = asyncio.get_running_loop().create_task(drain())
        yield served_at, psutil.Process(process.pid)
    finally:
        if process.returncode is None:
            process.terminate()
        await asyncio.wait_for(process.wait(), 30)
        if draining is not None:
            await draining


@contextlib.asynccontextmanager
async def http_session(url: str) -> AsyncIterator[ClientSession]:
    """An initialized MCP session over the SDK's Streamable HTTP client, with the bench token."""
    headers = {"Authorization": f"Bearer {HTTP_TOKEN}"}
    async with (
        httpx2.AsyncClient(headers=headers, timeout=httpx2.Timeout(60, read=300)) as http,
        streamable_http_client(url, http_client=http) as (read, write),
        ClientSession(read, write) as session,
    ):
        await session.initialize()
        yield session


async def measure_http(ctx: Context) -> list[Row]:
    """Item 10: ``list_topics`` over Streamable HTTP against stdio (interleaved); N HTTP sessions at once."""
    ours, plan = ctx.ours, ctx.plan
    async with http_server(ctx.bridge.url, ctx.errlog) as (url, process), http_session(url) as session:

        async def over_http() -> None:
            result = await session.call_tool("list_topics", {})
            if result.is_error:
                raise RuntimeError(f"list_topics over HTTP failed: {result.content}")

        subjects = [
            Subject("list_topics_stdio", lambda: ours.tool("list_topics", {}), ours.process),
            Subject("list_topics_http", over_http, process),
        ]
        await interleave(subjects, plan, ctx.bridge_process)
        n = plan.parallel_calls
        errors: list[str] = []

        async def one_session() -> None:
            try:
                async with http_session(url) as own:
                    result = await own.call_tool("list_topics", {})
                    if result.is_error:
                        errors.append("list_topics answered with an error")
            except Exception as error:
                errors.append(f"{type(error).__name__}: {error}")

        began = time.perf_counter()
        await asyncio.gather(*(one_session() for _ in range(n)))
        sessions_s = time.perf_counter() - began
    ctx.samples.update({subject.key: subject.samples for subject in subjects})
    ctx.cpu_per_call.update({subject.key: subject.cpu_per_call() for subject in subjects})
    stdio, http = subjects[0].stats, subjects[1].stats
    per_call = timing_row(
        "10a",
        "`list_topics` over Streamable HTTP (SDK client, bearer token, loopback)",
        http,
        versus=f"{(http.median - stdio.median) * 1e3:+.2f} ms over stdio ({ms(stdio.median)})",
        verdict="info",
    )
    per_call.figures["over_stdio_s"] = http.median - stdio.median
    stdio_row = timing_row(
        "10·", "`list_topics` over stdio, same run", stdio, versus="reference", verdict="info"
    )
    if errors:
        log.error("HTTP sessions failed: %s", "; ".join(sorted(set(errors))[:5]))
    sessions = Row(
        "10b",
        f"{n} HTTP sessions at once: initialize + `list_topics` each",
        n=n,
        median=ms(sessions_s),
        versus=f"{len(errors)} errors",
        target="0 errors",
        verdict=verdict(not errors) if n >= 100 else f"n/a ({n} sessions); {len(errors)} errors",
        figures={"errors": len(errors), "wall_s": sessions_s},
    )
    return [per_call, stdio_row, sessions]


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
    await ctx.client.publish(topic, "sensor_msgs/msg/Image", frame, latch=True)
    arguments = {"topic": topic, "max_size": 640}
    samples: list[float] = []
    for index in range(max(3, ctx.plan.block) + 2):
        began = time.perf_counter()
        result = await ctx.ours.tool("get_image", arguments)
        if index >= 2:  # the first two warm up (graph look-ups, the bridge's publisher)
            samples.append(time.perf_counter() - began)
    if not any(isinstance(block, mcp_types.ImageContent) for block in result.content):
        raise RuntimeError("get_image answered without an image")
    await ctx.client.unadvertise(topic)
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
    if not _peak_resettable(ctx.ours.process):
        return Row("5c", what, target=target, verdict="n/a (needs Linux /proc/PID/clear_refs)")
    topic = "/bench/png_bomb"
    bomb = {"format": "png", "data": base64.b64encode(png_bomb()).decode()}
    await ctx.client.publish(topic, "sensor_msgs/msg/CompressedImage", bomb, latch=True)
    arguments = {"topic": topic, "timeout": 10}
    # A first call learns the topic's type and warms the subscription path; the measured one follows.
    await ctx.ours.session.call_tool("get_image", arguments)
    before = ctx.ours.rss()
    _peak_reset(ctx.ours.process)
    began = time.perf_counter()
    result = await ctx.ours.session.call_tool("get_image", arguments)
    elapsed = time.perf_counter() - began
    growth = max(0, _peak_rss(ctx.ours.process) - before)
    await ctx.client.unadvertise(topic)
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


def _peak_resettable(process: psutil.Process) -> bool:
    return Path(f"/proc/{process.pid}/clear_refs").exists() and Path(f"/proc/{process.pid}/status").exists()


def _peak_reset(process: psutil.Process) -> None:
    """Reset the process's peak RSS to its current RSS (Linux ≥ 4.0: ``5`` into ``clear_refs``)."""
    Path(f"/proc/{process.pid}/clear_refs").write_text("5")


def _peak_rss(process: psutil.Process) -> int:
    """The process's peak RSS since the last reset (``VmHWM``), in bytes."""
    for line in Path(f"/proc/{process.pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
    raise RuntimeError("no VmHWM in /proc/PID/status")


# ---------------------------------------------------------------------------------- item 9: watch tools


class Metronome:
    """A raw connection that only notes when each message of a topic arrives (frames are not parsed).

    Each trial of a subscribe-to-first-message comparison starts right after a tick, so the raw socket and
    the tool both wait one period of the publisher plus their own overhead, instead of a random part of it.
    """

    def __init__(self, ws: ClientConnection, topic: str, msg_type: str) -> None:
        self.ws, self.topic, self.msg_type = ws, topic, msg_type
        self.tick = asyncio.Event()
        self._task: asyncio.Task[None] | None = None

    async def __aenter__(self) -> Metronome:
        await self.ws.send(
            json.dumps({"op": "subscribe", "id": "metronome", "topic": self.topic, "type": self.msg_type})
        )
        self._task = asyncio.create_task(self._listen())
        return self

    async def __aexit__(self, *_: object) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
        await self.ws.send(json.dumps({"op": "unsubscribe", "id": "metronome", "topic": self.topic}))

    async def _listen(self) -> None:
        async for _ in self.ws:
            self.tick.set()

    async def next_tick(self) -> None:
        self.tick.clear()
        await asyncio.wait_for(self.tick.wait(), 10)


async def raw_first_message(raw: RawBridge, topic: str, msg_type: str) -> None:
    """subscribe → first message (parsed) → unsubscribe, on the raw connection."""
    await raw.collect(topic, msg_type, 1)


async def phase_locked(
    metronome: Metronome, trials: int, subjects: dict[str, Callable[[], Awaitable[object]]]
) -> dict[str, Stats]:
    """Each subject ``trials`` times, alternating, every call started right after a metronome tick."""
    samples: dict[str, list[float]] = {name: [] for name in subjects}
    for trial in range(trials + 1):
        order = list(subjects.items())
        if trial % 2:
            order.reverse()
        for name, call in order:
            await metronome.next_tick()
            began = time.perf_counter()
            await call()
            if trial:  # the first round warms up
                samples[name].append(time.perf_counter() - began)
    return {name: Stats.of(values) for name, values in samples.items()}


def ratio_row(item: str, what: str, stats: Stats, floor: Stats, limit: float) -> Row:
    ratio = stats.median / floor.median
    row = timing_row(
        item,
        what,
        stats,
        versus=f"{ratio:.2f}× raw ({ms(floor.median)})",
        target=f"≤ {limit:g}× raw",
        verdict=verdict(ratio <= limit),
    )
    row.figures.update(floor_median_s=floor.median, ratio=ratio)
    return row


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


# --------------------------------------------------------------------------------- item 14: recording

#: What item 14 records, as a Nav2 robot publishes it: topic, type, rate (Hz).
RECORDED_LOAD = (
    ("/bench/scan", "sensor_msgs/msg/LaserScan", 10.0),
    ("/bench/odom", "nav_msgs/msg/Odometry", 50.0),
    ("/bench/tf", "tf2_msgs/msg/TFMessage", 50.0),
    ("/bench/camera/image_raw", "sensor_msgs/msg/Image", 30.0),
)


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


async def ctx_graph_has(served: Served, topic: str) -> None:
    """Wait (at most 10 s) until list_topics shows ``topic``."""
    async with asyncio.timeout(10):
        # The graph has no event to wait on: it is asked again until it shows the topic, within the timeout.
        while topic not in str((await served.tool("list_topics", {})).content):  # noqa: ASYNC110
            await asyncio.sleep(0.05)


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
            # The same load with nobody recording: what list_topics costs when the bridge is this busy.
            loaded: list[float] = []
            warm = asyncio.create_task(
                _publish_load(publisher, min(seconds, 10.0), dict.fromkeys(published, 0), first=500_000_000)
            )
            while not warm.done():
                began = time.perf_counter()
                await served.tool("list_topics", {})
                loaded.append(time.perf_counter() - began)
                await asyncio.sleep(0.25)
            await warm
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
            during, before = Stats.of(busy), Stats.of(idle)
            factor = during.median / before.median
            row = timing_row(
                "14b",
                "`list_topics` while `record` runs (14a's load) vs idle, same server",
                during,
                versus=f"{factor:.2f}× idle ({ms(before.median)})",
                target="≤ 2× idle",
                verdict=verdict(factor <= 2.0),
            )
            row.figures.update(idle_median_s=before.median, ratio=factor)
            rows.append(row)
            busy_only = Stats.of(loaded)
            rows.append(
                timing_row(
                    "14b·",
                    "↳ reference: `list_topics` under the same load with nobody recording",
                    busy_only,
                    versus=f"recording: {during.median / busy_only.median:.2f}× this",
                    verdict="info",
                )
            )
        # A large recording: summary from the index (the file is not read through).
        size = 1024**3 if ctx.plan.name == "full" else 16 * 1024**2
        if shutil.disk_usage(folder).free < size * 2:
            rows.append(Row("14c", "`read_recording` summary of a large recording", verdict="n/a (disk)"))
            return rows
        path = Path(folder) / "large.mcap"
        await asyncio.to_thread(_write_large_recording, path, size)
        from rosbridge_mcp_server.robot.recording.reading import summarize_recording  # noqa: PLC0415

        times = []
        for _ in range(5):
            began = time.perf_counter()
            summary = await asyncio.to_thread(summarize_recording, path)
            times.append(time.perf_counter() - began)
        rows.append(
            timing_row(
                "14c",
                f"summary of a {mib(path.stat().st_size)} recording ({summary.messages} messages) "
                "from its index",
                Stats.of(times),
                target="< 1 s",
                verdict=verdict(Stats.of(times).median < 1.0),
            )
        )
    return rows


def _recorded_indices(path: Path) -> dict[str, set[int]]:
    from rosbridge_mcp_server.robot.recording.reading import decoded_messages  # noqa: PLC0415

    found: dict[str, set[int]] = {}
    for topic, _, message in decoded_messages(path):
        found.setdefault(topic, set()).add(_index_of(message))
    return found


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


# --------------------------------------------------------------------------------- items 6-7: startup, memory


async def measure_startup(ctx: Context) -> list[Row]:
    """Item 6 (and the RSS half of item 7): spawn each server in turn, alternating which goes first."""
    commands = {"bare": bare_server_command(), "ours": our_server_command(ctx.bridge.url)}
    timings: dict[str, list[float]] = {"bare": [], "ours": []}
    initialize: dict[str, list[float]] = {"bare": [], "ours": []}
    rss: dict[str, list[float]] = {"bare": [], "ours": []}
    closing: dict[str, list[float]] = {"bare": [], "ours": []}
    # Untimed spawns first, so both find the interpreter and the packages in the page cache.
    for _ in range(ctx.plan.startup_warmup):
        for command in commands.values():
            async with serve_mcp(command, ctx.errlog):
                pass
    for round_number in range(ctx.plan.startup_rounds):
        order = ["bare", "ours"] if round_number % 2 == 0 else ["ours", "bare"]
        for which in order:
            async with serve_mcp(commands[which], ctx.errlog) as served:
                timings[which].append(served.tools_list_s)
                initialize[which].append(served.initialize_s)
                rss[which].append(served.rss())
                closed_from = time.perf_counter()
            closing[which].append(time.perf_counter() - closed_from)
    ctx.samples.update({f"startup_{key}": values for key, values in timings.items()})
    ctx.samples.update({f"startup_rss_{key}": values for key, values in rss.items()})
    ctx.samples.update({f"shutdown_{key}": values for key, values in closing.items()})
    bare, ours = Stats.of(timings["bare"]), Stats.of(timings["ours"])
    bare_rss, ours_rss = Stats.of(rss["bare"]), Stats.of(rss["ours"])
    ctx.startup_rss = {"bare": bare_rss, "ours": ours_rss}
    startup_ratio = ours.median / bare.median
    rss_ratio = ours_rss.median / bare_rss.median
    ours_close, bare_close = Stats.of(closing["ours"]), Stats.of(closing["bare"])
    return [
        timing_row(
            "6·",
            "bare `MCPServer`: spawn → `initialize` → `tools/list`",
            bare,
            versus=f"reference (initialize {ms(Stats.of(initialize['bare']).median)})",
        ),
        timing_row(
            "6a",
            "`rosbridge-mcp-server`: spawn → `initialize` → `tools/list`",
            ours,
            versus=f"{startup_ratio:.2f}× bare (initialize {ms(Stats.of(initialize['ours']).median)})",
            target="≤ 1.3× bare",
            verdict=verdict(startup_ratio <= 1.3),
        ),
        timing_row(
            "6·",
            "exit after stdin closes (ours / bare)",
            ours_close,
            versus=f"bare {ms(bare_close.median)}",
            verdict="info",
        ),
        Row(
            "7·",
            "bare `MCPServer`: RSS after startup",
            n=bare_rss.n,
            median=mib(bare_rss.median),
            p90=mib(bare_rss.p90),
            versus="reference",
            figures={"median_bytes": bare_rss.median},
        ),
        Row(
            "7a",
            "`rosbridge-mcp-server`: RSS after startup",
            n=ours_rss.n,
            median=mib(ours_rss.median),
            p90=mib(ours_rss.p90),
            versus=f"{rss_ratio:.2f}× bare",
            target="≤ 1.3× bare",
            verdict=verdict(rss_ratio <= 1.3),
            figures={"median_bytes": ours_rss.median, "ratio": rss_ratio},
        ),
    ]


async def churn(served: Served, calls: int, batch: int, call: Callable[[], Awaitable[object]]) -> list[int]:
    """Make ``calls`` requests, ``batch`` at a time; RSS at the start, halfway and at the end."""
    marks = [served.rss()]
    done = 0
    for checkpoint in (calls // 2, calls):
        while done < checkpoint:
            size = min(batch, checkpoint - done)
            await asyncio.gather(*(call() for _ in range(size)))
            done += size
        marks.append(served.rss())
    return marks


async def measure_memory(ctx: Context) -> list[Row]:
    """Item 7: RSS growth over N cheap requests: ours (``list_topics``), the bare server (``tools/list``)."""
    calls, batch = ctx.plan.memory_calls, ctx.plan.memory_batch
    async with serve_mcp(bare_server_command(), ctx.errlog) as bare:
        began = time.perf_counter()
        bare_marks = await churn(bare, calls, batch, bare.session.list_tools)
        bare_elapsed = time.perf_counter() - began
    async with serve_mcp(our_server_command(ctx.bridge.url), ctx.errlog) as ours:
        began = time.perf_counter()
        our_marks = await churn(ours, calls, batch, lambda: ours.tool("list_topics", {}))
        our_elapsed = time.perf_counter() - began
    ctx.samples["memory_rss_bare"] = [float(mark) for mark in bare_marks]
    ctx.samples["memory_rss_ours"] = [float(mark) for mark in our_marks]
    # Growth in the second half is the leak signal; the first half also holds one-off warm-up (caches).
    noise = max(bare_marks[2] - bare_marks[1], 0) + 1 * MIB
    late_growth = our_marks[2] - our_marks[1]

    def growth(marks: list[int]) -> str:
        return f"{(marks[2] - marks[0]) / MIB:+.1f} MiB (second half {(marks[2] - marks[1]) / MIB:+.1f})"

    return [
        Row(
            "7·",
            f"bare `MCPServer`: RSS after {calls} `tools/list`, {batch} at a time",
            n=calls,
            median=mib(bare_marks[2]),
            versus=f"{growth(bare_marks)}; {calls / bare_elapsed:.0f} calls/s",
            verdict="info",
            figures={"rss_bytes": bare_marks, "elapsed_s": bare_elapsed},
        ),
        Row(
            "7b",
            f"`rosbridge-mcp-server`: RSS after {calls} `list_topics`, {batch} at a time",
            n=calls,
            median=mib(our_marks[2]),
            versus=f"{growth(our_marks)}; {calls / our_elapsed:.0f} calls/s",
            target="second-half growth ≤ bare's + 1 MiB",
            verdict=verdict(late_growth <= noise),
            figures={"rss_bytes": our_marks, "elapsed_s": our_elapsed},
        ),
    ]


# ------------------------------------------------------------------------------------------------ the run


@dataclasses.dataclass
class Context:
    """Everything the items share: the plan, the bridge, the open connections and the raw samples."""

    plan: Plan
    bridge: Bridge
    raw: RawBridge
    client: RosbridgeClient
    ours: Served
    reference: Served  # the bare server with the reference tools, on our stdio transport
    reference_sdk: Served  # the same on the SDK's stdio transport
    ours_sdk: Served  # our server on the SDK's stdio transport
    errlog: IO[str]
    bridge_process: psutil.Process | None = None  # the simulated robot, when we started it
    samples: dict[str, list[float]] = dataclasses.field(default_factory=dict)
    cpu_per_call: dict[str, dict[str, float | None]] = dataclasses.field(default_factory=dict)
    startup_rss: dict[str, Stats] = dataclasses.field(default_factory=dict)


DIAGNOSE_TARGET = 1.5
LOG_FLOOD_RATE = 10_000
LOG_FLOOD_SECONDS = 10


async def measure_diagnose(ctx: Context) -> list[Row]:
    """Item 13: ``diagnose`` on the simulated Nav2 world (healthy, then scan-stopped + log-errors), its p50
    against 1.5 s; the log ring under a flood of /rosout lines."""
    rows: list[Row] = []
    full = ctx.plan.name == "full"
    calls = 10 if full else 2
    cases = (("13a", ""), ("13b", "scan-stopped,log-errors")) if full else (("13a", ""),)
    for item, faults in cases:
        async with contextlib.AsyncExitStack() as stack:
            url = await stack.enter_async_context(simulated_robot(ctx.errlog, world="nav2", faults=faults))
            ours = await stack.enter_async_context(raw_pipe_client(our_server_command(url), ctx.errlog, {}))
            answer = await ours.tool("diagnose", {})  # the first look also waits for the connection
            samples = []
            for _ in range(calls):
                began = time.perf_counter()
                answer = await ours.tool("diagnose", {})
                samples.append(time.perf_counter() - began)
            text = answer["result"]["content"][0]["text"]
            stats = Stats.of(samples)
            what = "healthy" if not faults else f"--fault {faults}"
            row = timing_row(
                item,
                f"`diagnose` on the Nav2 world, {what}: {text.splitlines()[0]}",
                stats,
                target=f"p50 ≤ {DIAGNOSE_TARGET:g} s",
            )
            row.verdict = verdict(stats.median <= DIAGNOSE_TARGET)
            row.figures.update(first_line=text.splitlines()[0], text_chars=len(text))
            rows.append(row)
    rows.append(await _log_flood_row(ctx))
    return rows


async def _log_flood_row(ctx: Context) -> Row:
    """10,000 /rosout lines a second for 10 s (quick: 1 s) from a simulated robot in this process into a
    session's log keeper over a real socket: every line received, the ring holding exactly the newest it
    keeps, and the process's RSS sampled every half second."""
    from rosbridge_mcp_server.robot.logs import RING_LINES  # noqa: PLC0415
    from rosbridge_mcp_server.robot.seam import ALLOW_ALL  # noqa: PLC0415
    from rosbridge_mcp_server.robot.session import RobotSession  # noqa: PLC0415
    from rosbridge_mcp_server.sim import SimulatedRobot  # noqa: PLC0415

    seconds = LOG_FLOOD_SECONDS if ctx.plan.name == "full" else 1
    process = psutil.Process()
    rss: list[float] = []

    async def sample() -> None:
        while True:
            rss.append(process.memory_info().rss)
            await asyncio.sleep(0.5)

    async with SimulatedRobot(world="nav2") as robot, RosbridgeClient(robot.url) as client:
        keeper = RobotSession(client, ALLOW_ALL).keep_logs()
        await client.wait_connected(10)
        await asyncio.wait_for(keeper.ready.wait(), 10)
        nav2, health = robot.nav2.robots[0], robot.nav2.health
        before = keeper.ring.received
        sampler = asyncio.create_task(sample())
        began = time.monotonic()
        sent = 0
        per_tick = LOG_FLOOD_RATE // 100
        for tick in range(seconds * 100):
            await asyncio.sleep(max(0.0, began + tick / 100 - time.monotonic()))
            for _ in range(per_tick):
                sent += 1
                health.log(nav2, "flood", "warn", f"line {sent}")
        sent_in = time.monotonic() - began
        deadline = time.monotonic() + 120
        # The ring has no event to wait on (it is fed by the keeper's reader); a bounded poll reads it.
        while keeper.ring.received - before < sent and time.monotonic() < deadline:  # noqa: ASYNC110
            await asyncio.sleep(0.05)
        received_in = time.monotonic() - began
        sampler.cancel()
        kept = keeper.ring.lines()
        newest = [f"line {i}" for i in range(max(1, sent - RING_LINES + 1), sent + 1)]
        exact = [line.text for line in kept if line.node == "/flood"] == newest
        received = keeper.ring.received - before
    settled = rss[len(rss) // 4 :] or rss
    growth = (max(settled) - min(settled)) / MIB
    row = Row(
        "13c",
        f"log ring: {LOG_FLOOD_RATE:,} /rosout lines/s for {seconds} s ({sent:,} sent in {sent_in:.1f} s, "
        f"received by {received_in:.1f} s)",
        n=sent,
        median=f"{received:,} received",
        p90=f"{len(kept):,} kept",
        versus=f"RSS {min(rss) / MIB:.0f}-{max(rss) / MIB:.0f} MiB, {growth:+.1f} MiB after the ring filled",
        target="nothing lost; the newest 5,000 kept in order; RSS flat (≤ 8 MiB)",
    )
    row.verdict = verdict(received == sent and exact and growth <= 8)
    row.figures.update(sent=sent, received=received, kept=len(kept), exact=exact, rss_growth_mib=growth)
    return row


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
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
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


if __name__ == "__main__":
    sys.exit(main())
