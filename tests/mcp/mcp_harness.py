"""MCP sessions for the tests: the SDK's in-memory client against ``build_server(...)`` on a simulated robot.

The client connects with the initialize handshake (``mode="legacy"``), as Claude Desktop and MCP Inspector
do, so requests, progress and cancellation travel as JSON-RPC messages over in-memory streams.
"""

from __future__ import annotations

import asyncio
import re
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from mcp.types import CallToolResult, TextContent

from mcp import Client
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.client.transport import Dial
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.robot.approval import ALLOW_ALL, Guard
from rosbridge_mcp_server.robot.log_keeper import LogKeeper
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.robot.warm_up import ServiceTypeWarmUp
from rosbridge_mcp_server.safety import Policy, PolicyGuard
from rosbridge_mcp_server.server import Robot, build_server
from rosbridge_mcp_server.server.fleet import Fleet
from rosbridge_mcp_server.server.tasks import TaskBoard
from rosbridge_mcp_server.sim import SimulatedRobot

CONNECT_WAIT = 30.0


@dataclass
class Session:
    """One MCP client session, the rosbridge client behind the server, and progress notifications seen."""

    mcp: Client
    ros: RosbridgeClient
    progress: list[tuple[float, float | None, str | None]] = field(default_factory=list)
    #: The robot session the server drives (for what the console does beside the MCP client: E-STOP).
    robot: RobotSession | None = None

    async def call(self, name: str, arguments: dict[str, Any] | None = None) -> CallToolResult:
        """Call a tool, recording its progress notifications."""

        async def on_progress(progress: float, total: float | None, message: str | None) -> None:
            self.progress.append((progress, total, message))

        return await self.mcp.call_tool(name, arguments or {}, progress_callback=on_progress)

    async def ok(self, name: str, arguments: dict[str, Any] | None = None) -> CallToolResult:
        """Call a tool that must succeed."""
        result = await self.call(name, arguments)
        assert not result.is_error, text_of(result)
        assert result.structured_content is not None
        return result

    async def error(self, name: str, arguments: dict[str, Any] | None = None) -> str:
        """Call a tool that must fail; returns its error text."""
        result = await self.call(name, arguments)
        assert result.is_error, text_of(result)
        return text_of(result)


def guarded(client: RosbridgeClient, config: Config) -> RobotSession:
    """A robot session for *client* under *config*'s policy, as ``serve`` builds one (audited on stderr)."""
    return RobotSession(client, PolicyGuard(config.policy))


def text_of(result: CallToolResult) -> str:
    """The text content of a tool result."""
    return "\n".join(block.text for block in result.content if isinstance(block, TextContent))


@asynccontextmanager
async def open_session(
    url: str,
    *,
    request_timeout: float = 5.0,
    wait: bool = True,
    mode: str = "legacy",
    guard: Guard | None = ALLOW_ALL,
    elicitation_callback: Any = None,
    policy: Policy | None = None,
    tools: tuple[str, ...] | None = None,
    record_dir: str | None = None,
    extensions: tuple[Any, ...] = (),
    tasks: bool | Callable[[Fleet], TaskBoard] = True,
    transport: Dial | None = None,
) -> AsyncIterator[Session]:
    """An MCP session on a server built for ``url``; waits for the bridge connection unless ``wait`` is false.

    ``mode="auto"`` speaks the 2026-07-28 protocol instead (in-process: direct dispatch, no JSON-RPC framing).
    With ``policy`` the server runs under that safety policy (``guard=None``: the server's own PolicyGuard);
    ``tools`` picks the tools as ``--tools`` does; ``record_dir`` is ``--record-dir``; ``extensions`` are the
    client's (e.g. the tasks extension's ad); ``tasks=False`` is ``--no-tasks``, a function makes the server's
    task board (to watch it). ``transport`` is the client's (a simulated robot's ``dial_in_memory``: no
    socket between the server and the robot; see ``tests/sim_transport.py``).

    The SDK client lives in a task of its own: its anyio scopes must be entered and left by one task, and
    pytest-asyncio sets a fixture up and tears it down in different tasks.
    """
    config = Config(
        url=url,
        request_timeout=request_timeout,
        # Room for a loaded machine: a tool call waits this long for a connection attempt in progress (a
        # refused port still answers at once). CI, with coverage on two cores, once saw 2 s pass.
        connect_timeout=5.0,
        policy=policy or Policy(),
        tools=tools,
    )
    if record_dir is not None:
        config = replace(config, record_dir=Path(record_dir))
    ros = RosbridgeClient(
        url,
        connect_timeout=config.connect_timeout,
        request_timeout=request_timeout,
        reconnect_min=0.05,
        reconnect_max=0.2,
        transport=transport,
    )
    ready: asyncio.Future[Session] = asyncio.get_running_loop().create_future()
    stop = asyncio.Event()

    async def host() -> None:
        try:
            robot = guarded(ros, config) if guard is None else RobotSession(ros, guard)
            board = tasks(Fleet([Robot("robot", config, robot)])) if callable(tasks) else tasks
            server = build_server(robot, config, tasks=board)
            async with Client(
                server, mode=mode, elicitation_callback=elicitation_callback, extensions=list(extensions)
            ) as mcp:
                ready.set_result(Session(mcp, ros, robot=robot))
                await stop.wait()
        except BaseException as exc:
            if not ready.done():
                ready.set_exception(exc)
            raise

    hosting = asyncio.create_task(host())
    try:
        session = await ready
        if wait:
            await ros.wait_connected(CONNECT_WAIT)
            await warmed_up(ros)
        yield session
    finally:
        stop.set()
        await hosting


#: The background learning after connecting asks rosapi one service at a time: on the Nav2 fleet world (1,200
#: services) with four test workers on two cores that can take well over CONNECT_WAIT.
WARM_UP_WAIT = 60.0


async def warmed_up(ros: RosbridgeClient) -> None:
    """Wait until the server has learnt the service types and had its first look at the graph after connecting
    (tests then count only theirs)."""
    for watcher in ros.watchers:
        if isinstance(watcher, ServiceTypeWarmUp):
            await asyncio.wait_for(watcher.done.wait(), WARM_UP_WAIT)
        if isinstance(watcher, LogKeeper):
            # Its first look at the graph (a topic and a node listing) is behind it too.
            await asyncio.wait_for(watcher.looked.wait(), WARM_UP_WAIT)
    # Whether calls hold each other up is measured in the background (tests then count only theirs).
    assert await ros.ordering_known(WARM_UP_WAIT) or not ros.connected


def service_rows(data: dict[str, Any] | None) -> list[dict[str, str]]:
    """Every row of a list_services answer's structured content: the page's own rows and the grouped ones
    spelled out (a group's node + "/" + leaf), sorted by name."""
    assert data is not None
    rows: list[dict[str, str]] = list(data["services"])
    for group in data.get("groups", []):
        rows += [
            {"name": f"{node}/{row['name']}", "type": row["type"]}
            for node in group["nodes"]
            for row in group["services"]
        ]
    return sorted(rows, key=lambda row: row["name"])


def parameter_names(data: dict[str, Any] | None) -> list[str]:
    """The full parameter names of a list_parameters answer's page (/node:name on ROS 2, /ns/name on
    ROS 1)."""
    assert data is not None
    return [f"{group['node']}{data['separator']}{name}" for group in data["nodes"] for name in group["names"]]


def unreadable_services(result: CallToolResult) -> list[dict[str, str]]:
    """The rows of a list_services answer that its text does not name with their type.

    The text lists the robot's own services a line each (``/name (type)``) and groups the rest:
    ``On 2 nodes (/a, /b): <node>/get_parameters (rcl_interfaces/srv/GetParameters), ...`` and
    ``rosapi's own, /rosapi/<name> (rosapi_msgs/srv/<Type>): topics (Topics), ...``.
    """
    assert result.structured_content is not None
    lines = text_of(result).splitlines()
    readable = set(lines)
    for line in lines:
        if grouped := re.fullmatch(r"On \d+ nodes? \((.*?)\): (.*)", line):
            for node in grouped[1].split(", "):
                readable |= {entry.replace("<node>", node) for entry in grouped[2].split(", ")}
        elif rosapi := re.fullmatch(r"rosapi's own, /rosapi/<name> \((.*)/<Type>\): (.*)", line):
            for entry in rosapi[2].split(", "):
                leaf, short_type = entry.rstrip(")").split(" (")
                readable.add(f"/rosapi/{leaf} ({rosapi[1]}/{short_type})")
    rows = service_rows(result.structured_content)
    return [row for row in rows if f"{row['name']} ({row['type'] or 'type unknown'})" not in readable]


def types_for(robot: SimulatedRobot) -> dict[str, str]:
    """Type names of the simulated world in the robot's own dialect."""
    if robot.dialect == "ros2":
        return {
            "twist": "geometry_msgs/msg/Twist",
            "string": "std_msgs/msg/String",
            "add_two_ints": "example_interfaces/srv/AddTwoInts",
            "trigger": "std_srvs/srv/Trigger",
            "empty_srv": "std_srvs/srv/Empty",
            "set_bool": "std_srvs/srv/SetBool",
            "fibonacci": "example_interfaces/action/Fibonacci",
        }
    return {
        "twist": "geometry_msgs/Twist",
        "string": "std_msgs/String",
        "add_two_ints": "rospy_tutorials/AddTwoInts",
        "trigger": "std_srvs/Trigger",
        "empty_srv": "std_srvs/Empty",
        "set_bool": "std_srvs/SetBool",
        "fibonacci": "actionlib_tutorials/FibonacciAction",
    }
