"""The harness every measurement shares: the plan, timing and RSS, figures, ratios and rows, and the processes
(the simulated robot, our server, the bare reference server) with the connections to them.

Only the package's public ways in are used: the console script ``rosbridge-mcp-server`` (as an MCP host starts
it), ``python -m rosbridge_mcp_server.sim`` (the simulated robot), MCP over stdio (the SDK's client, or
JSON-RPC lines written on the server's pipes) and the rosbridge protocol over a raw WebSocket. The few figures
that measure an internal part on its own import it from :mod:`benchmarks.internals`, which says which.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import importlib.metadata
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
import time
from collections.abc import AsyncIterator, Awaitable, Callable, Sequence
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any
from urllib.parse import urlsplit

import mcp_types
import psutil
from mcp.client.session import ClientSession
from mcp.client.stdio import StdioServerParameters, stdio_client
from websockets.asyncio.client import ClientConnection

if TYPE_CHECKING:
    from benchmarks.internals import RosbridgeClient


log = logging.getLogger("bench")

REPO = Path(__file__).resolve().parents[2]
SERVERS = Path(__file__).resolve().parent / "servers"
BARE_SERVER = SERVERS / "bare_server.py"
OURS_SDK_STDIO = SERVERS / "ours_sdk_stdio.py"
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

#: The rows of tool calls made by JSON-RPC lines on the pipes instead of the MCP SDK's client.
BARE = "the same called by JSON-RPC lines (the server alone, without the MCP client SDK's work)"
#: An MCP round trip's worth of idle before a floor call (the no-op tool's median on this machine): a tool's
#: request always reaches the bridge after one, and rosbridge 2.1.0 answers a request that follows a short
#: pause ~9 ms later than one sent back to back (docs/rosbridge-behaviour.md).
TOOL_PAUSE = 0.001


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


def simulated_robot_command(
    port: int,
    *,
    fast_topic: bool = False,
    camera_size: str = CAMERA_SIZE,
    map_cells: int | None = None,
    world: str = "turtle",
    server: str = "rosbridge_suite",
    faults: str = "",
) -> list[str]:
    """``python -m rosbridge_mcp_server.sim`` on ``port`` with these options (``simulated_robot`` runs it)."""
    return [
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
    command = simulated_robot_command(
        port,
        fast_topic=fast_topic,
        camera_size=camera_size,
        map_cells=map_cells,
        world=world,
        server=server,
        faults=faults,
    )
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

    async def publish_latched(self, topic: str, msg_type: str, msg: dict[str, Any]) -> None:
        """Advertise ``topic`` latched and publish one message: the bridge keeps it for late subscribers while
        this connection holds the advertisement."""
        await self.ws.send(
            json.dumps(
                {"op": "advertise", "id": self._next_id(), "topic": topic, "type": msg_type, "latch": True}
            )
        )
        await self.ws.send(json.dumps({"op": "publish", "topic": topic, "msg": msg, "latch": True}))

    async def unadvertise(self, topic: str) -> None:
        await self.ws.send(json.dumps({"op": "unadvertise", "id": self._next_id(), "topic": topic}))

    async def call_many(self, calls: Sequence[tuple[str, dict[str, Any]]]) -> None:
        """Several calls sent at once on this connection, their replies awaited together."""
        pending = set()
        for service, args in calls:
            request_id = self._next_id()
            pending.add(request_id)
            await self.ws.send(
                json.dumps({"op": "call_service", "id": request_id, "service": service, "args": args})
            )
        while pending:
            reply = json.loads(await self.ws.recv())
            if reply.get("op") == "service_response" and reply.get("id") in pending:
                pending.discard(reply["id"])

    async def answers_with_status(self) -> bool:
        """Whether the bridge answers a refused op with an error ``status`` (rosbridge-server-rs does; every
        rosbridge_suite release ignores it): a cancel of a goal nobody started, then a call, on this
        connection. Nothing acts: no goal has this id."""
        goal = f"{self._next_id()}:probe"
        await self.ws.send(json.dumps({"op": "cancel_action_goal", "id": goal, "action": "/bench/probe"}))
        request_id = self._next_id()
        await self.ws.send(
            json.dumps({"op": "call_service", "id": request_id, "service": "/rosapi/get_time"})
        )
        told = False
        async with asyncio.timeout(10):
            while True:
                reply = json.loads(await self.ws.recv())
                if reply.get("op") == "status" and reply.get("id") == goal:
                    told = True
                if reply.get("op") == "service_response" and reply.get("id") == request_id:
                    return told

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
    """Our server on the MCP SDK's stdio transport instead of its own (``servers/ours_sdk_stdio.py``)."""
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

    def __init__(self, process: asyncio.subprocess.Process, *, lenient: bool = False) -> None:
        self._process = process
        self._ids = 0
        self._lenient = lenient  # a peer's stray non-JSON lines on stdout are skipped; never ours

    async def request(self, method: str, params: dict[str, Any]) -> dict[str, Any]:
        assert self._process.stdin is not None
        assert self._process.stdout is not None
        self._ids += 1
        line = {"jsonrpc": "2.0", "id": self._ids, "method": method, "params": params}
        self._process.stdin.write(json.dumps(line).encode() + b"\n")
        while True:
            line = await self._process.stdout.readline()
            if not line:
                raise RuntimeError(f"the server closed its stdout before answering {method}")
            try:
                answer: dict[str, Any] = json.loads(line)
            except ValueError:
                if self._lenient:
                    continue
                raise
            if answer.get("id") == self._ids:
                return answer  # notifications (progress, logging) are skipped

    async def tool(self, name: str, arguments: dict[str, Any]) -> dict[str, Any]:
        answer = await self.request("tools/call", {"name": name, "arguments": arguments})
        if "error" in answer or answer["result"].get("isError"):
            raise RuntimeError(f"tool {name} failed: {answer}")
        return answer


@contextlib.asynccontextmanager
async def raw_pipe_client(
    command: list[str], errlog: Any, env: dict[str, str], *, lenient: bool = False
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
    client = RawPipeClient(process, lenient=lenient)
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


async def ctx_graph_has(served: Served, topic: str) -> None:
    """Wait (at most 10 s) until list_topics shows ``topic``."""
    async with asyncio.timeout(10):
        # The graph has no event to wait on: it is asked again until it shows the topic, within the timeout.
        while topic not in str((await served.tool("list_topics", {})).content):  # noqa: ASYNC110
            await asyncio.sleep(0.05)


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


# ------------------------------------------------------------------------------------ item 4: concurrency


async def wall_time(action: Callable[[], Awaitable[object]]) -> float:
    began = time.perf_counter()
    await action()
    return time.perf_counter() - began


def peak_resettable(process: psutil.Process) -> bool:
    return Path(f"/proc/{process.pid}/clear_refs").exists() and Path(f"/proc/{process.pid}/status").exists()


def peak_reset(process: psutil.Process) -> None:
    """Reset the process's peak RSS to its current RSS (Linux ≥ 4.0: ``5`` into ``clear_refs``)."""
    Path(f"/proc/{process.pid}/clear_refs").write_text("5")


def peak_rss(process: psutil.Process) -> int:
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
    ros_mcp: str | None = None  # --ros-mcp: the Python of a venv with ros-mcp, the peer of item 15
    node: str | None = None  # --node: the node item 15's get_node_info asks about on a --url bridge
