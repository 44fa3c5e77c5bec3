"""The rosbridge side: the simulated robot's process, a raw rosbridge connection, the bridge measured."""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import json
import socket
import sys
from collections.abc import AsyncIterator, Sequence
from pathlib import Path
from typing import IO, Any
from urllib.parse import urlsplit

import psutil
from websockets.asyncio.client import ClientConnection

from benchmarks.constants import ADD_TWO_INTS, CAMERA_SIZE, REPO, SLOW_SERVICE, SLOW_SERVICE_SECONDS, log


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
