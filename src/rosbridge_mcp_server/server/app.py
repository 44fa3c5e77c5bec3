"""The MCP server: ``build_server`` serves every tool on the SDK's low-level ``Server``.

The low-level server is the SDK's documented way to own the schemas and results exactly (docs/architecture.md
says why we chose it): ``tool_calls.py`` answers ``tools/list`` and ``tools/call``, ``console_app.py`` the MCP
App's resource. The rosbridge client connects in the background from the server's lifespan, so ``initialize``
and ``tools/list`` work while the robot is down; tools then fail fast with the not-connected text naming the
URL.
"""

from __future__ import annotations

import contextlib
import logging
import typing
from collections.abc import AsyncIterator, Callable, Sequence
from contextlib import AbstractAsyncContextManager, asynccontextmanager
from typing import Any

from mcp.server import Server, ServerRequestContext
from mcp.types import (
    INVALID_PARAMS,
    ListPromptsResult,
    ListResourcesResult,
    PaginatedRequestParams,
    ReadResourceRequestParams,
    ReadResourceResult,
)

from mcp import MCPError
from rosbridge_mcp_server import __version__
from rosbridge_mcp_server.server.adapter import EdgeTool, module_tool
from rosbridge_mcp_server.server.console_app import APPS_EXTENSION, ConsoleApp, console_app
from rosbridge_mcp_server.server.fleet import Fleet, Robot, list_robots_tool
from rosbridge_mcp_server.server.read_only import ReadOnlyRefusals
from rosbridge_mcp_server.server.shutdown import stop_robots
from rosbridge_mcp_server.server.tasks import TaskBoard
from rosbridge_mcp_server.server.tool_calls import ToolCalls
from rosbridge_mcp_server.tools import TOOL_MODULES
from rosbridge_mcp_server.tools.base import Need, ToolSpec

if typing.TYPE_CHECKING:
    from rosbridge_mcp_server.config import Config
    from rosbridge_mcp_server.robot.session import RobotSession

__all__ = ["INSTRUCTIONS", "SERVER_NAME", "build_fleet_server", "build_server"]

_log = logging.getLogger("rosbridge_mcp_server.server")

SERVER_NAME = "rosbridge"


def _names(names: Sequence[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return " and ".join([", ".join(names[:-1]), names[-1]] if len(names) > 1 else names)


def instructions(specs: Sequence[ToolSpec]) -> str:
    """What the model is told first: which of *specs* act on the robot (every one, from its spec), what
    else changes something, the stop, and how to work."""
    acting = [spec.name for spec in specs if spec.acts_on is not None]
    elsewhere = [f"{spec.name} changes {spec.changes}" for spec in specs if spec.changes is not None]
    stops = _names([spec.name for spec in specs if spec.stops])
    return _INSTRUCTIONS.format(
        acting=_names(acting),
        elsewhere=f" ({_names(elsewhere)})" if elsewhere else "",
        stops=stops,
    )


_INSTRUCTIONS = """\
This server connects to a real (or simulated) ROS robot through rosbridge. {acting} act on the robot and \
can make it move or change how it behaves; every other tool only reads the robot's state{elsewhere}.

Work like this:
1. Look before acting: list_topics, list_services and list_actions show what the robot has, with the exact \
names and types; get_topic_info shows who publishes and subscribes a topic; describe_type shows a type's \
fields with an example. To see the robot's state: subscribe_topic reads messages, get_image shows a camera, \
get_transform says where a frame is (e.g. base_link in odom). When something seems wrong (the robot does \
not move, a sensor is quiet, a node died), diagnose looks at everything at once; read_logs shows the robot's \
log since this server connected.
2. Use those exact names and types. Messages, requests and goals are JSON objects; omitted fields are \
zero or empty, and {{}} is fine for empty messages. Units are SI: metres, seconds, radians, m/s, rad/s.
3. Movement: velocity commands (e.g. geometry_msgs/msg/Twist on /turtle1/cmd_vel) usually act briefly; \
publish_topic with rate_hz and duration keeps the robot moving and stops it with zeros at the end. Prefer \
small, safe values and say what you are about to do.
4. publish_action waits for the goal to finish and cancels it on timeout; cancel_action stops goals that run.
5. {stops} stops everything this server started (streams, velocity, goals): use it when in doubt.

A safety policy set by the robot's operator may refuse a call (the error names the rule) or ask the person \
at the client to confirm it. A refusal is final: do not try to reach the same effect another way; tell the \
user what was refused and why.

A failed call comes back as an error whose text says what went wrong and what to try (a field that does not \
fit the type, an unknown name, the robot being unreachable). Nothing is queued while the robot is \
unreachable, and publish_topic first checks that the bridge answers, so a command is not delivered late. A \
request that timed out may still take effect later: check the robot's state before repeating it.\
"""

#: The instructions of a server with every tool of the catalogue.
INSTRUCTIONS = instructions([module.SPEC for module in TOOL_MODULES])


_READ_ONLY_NOTE = """

This server is read-only: it lists only tools that read the robot, and refuses any other.\
"""

#: What each need of a tool (its spec's ``needs``) starts in every robot's session.
_KEEPERS: dict[Need, Callable[[RobotSession], object]] = {
    "service_types": lambda session: session.learn_service_types(),
    "robot_log": lambda session: session.keep_logs(),
}


def _notes(specs: Sequence[ToolSpec], fleet: Fleet, read_only: bool) -> str:
    """What the instructions add for a fleet, a read-only server and read-only robots of a fleet."""
    notes = ""
    if fleet.several:
        every = [
            f"{spec.name} without it {'stops' if spec.stops else 'runs on'} every robot"
            for spec in specs
            if spec.every_robot
        ]
        notes += (
            "\n\nThis server drives several robots: list_robots names them, and every other tool needs the "
            "robot argument saying which one" + (f" ({'; '.join(every)})." if every else ".")
        )
    if read_only:
        notes += _READ_ONLY_NOTE
    elif fleet.read_only_names:
        also = "".join(f" and {spec.name}" for spec in specs if spec.stops)
        notes += (
            f"\n\nRead-only robots ({', '.join(fleet.read_only_names)}): only reading tools{also} work on "
            "them; any other is refused."
        )
    return notes


def build_server(
    robot: RobotSession,
    config: Config,
    *,
    console_view: Callable[[], dict[str, Any]] | None = None,
    tasks: bool | TaskBoard = True,
) -> Server[None]:
    """A server with every tool, driving one robot (its client started and closed by the server's
    lifespan); see :func:`build_fleet_server`."""
    return build_fleet_server([Robot("robot", config, robot)], config, console_view=console_view, tasks=tasks)


def build_fleet_server(
    robots: Sequence[Robot],
    config: Config,
    *,
    console_view: Callable[[], dict[str, Any]] | None = None,
    tasks: bool | TaskBoard = True,
) -> Server[None]:
    """The SDK's low-level ``Server`` driving *robots* (each client started and closed by its lifespan).

    Every act on a robot is first approved by its session's guard (the server as ``serve`` runs it: a
    :class:`~rosbridge_mcp_server.safety.PolicyGuard` for the robot's policy, audited). *config* chooses the
    tools and, when read-only, withholds the acting ones (``read_only.py``). Every tool call first goes
    through the checks of ``tool_calls.py``, on any transport. With several robots every tool takes a
    ``robot`` argument and ``list_robots`` is listed (``fleet.py``). The tools record what they set going in
    each robot's session, which the operator console's E-STOP shares. With *console_view* (the console's
    snapshot) the server also offers the console's read-only view as an MCP App: ``show_console`` and its
    ``ui://`` resource (``server/console_app.py``). Authentication is the transport's (``http.py``). With
    *tasks* (unless ``--no-tasks``) long work runs as an MCP task for a client that can follow one
    (``server/tasks.py``); a :class:`TaskBoard` given is the one used (the console lists its tasks).
    """
    fleet = Fleet(robots)
    board = tasks if isinstance(tasks, TaskBoard) else TaskBoard(fleet) if tasks else None
    # Read-only when the server is, or when every robot is (a fleet file may make each read-only).
    read_only = config.policy.read_only or not fleet.acting_names
    chosen = _chosen(config)
    specs = [spec for spec in chosen if spec.hints.read_only or not read_only]
    _start_keepers(specs, fleet)
    app = console_app(console_view) if console_view is not None else None
    tools = _edge_tools(specs, fleet, app)
    # Acting tools a read-only policy keeps from the list; a tool --tools left out stays simply unknown.
    withheld = [spec for spec in chosen if spec not in specs]
    refusals = ReadOnlyRefusals(fleet, withheld, [spec.name for spec in specs if spec.stops])
    calls = ToolCalls(tools, fleet, unlisted=refusals.unlisted, robot_check=refusals.robot_check)
    resources = _Resources(app)
    server: Server[None] = Server(
        SERVER_NAME,
        version=__version__,
        title="rosbridge MCP server",
        description="Watch and drive a ROS 1 / ROS 2 robot through rosbridge",
        instructions=INSTRUCTIONS + _notes(specs, fleet, read_only),
        lifespan=_lifespan(fleet, board),
        get_tool_input_schema=calls.input_schema,
        on_list_tools=calls.list_tools,
        on_call_tool=calls.call_tool,
        on_list_resources=resources.list_resources,
        on_read_resource=resources.read_resource,
        on_list_prompts=resources.list_prompts,
    )
    # Arguments that are no object get our sentence before the SDK checks the request's shape.
    server.middleware.append(calls.arguments_kind)
    if board is not None:
        board.register(server, specs)
    if app is not None:
        server.extensions[APPS_EXTENSION] = {}
    return server


#: Every tool module by its tool's name.
_MODULES = {module.SPEC.name: module for module in TOOL_MODULES}


def _chosen(config: Config) -> list[ToolSpec]:
    """The tools *config* chooses (``--tools``), in the catalogue's order, with the stop whenever a tool that
    acts is among them: whoever can set the robot going can stop it."""
    specs = [m.SPEC for m in TOOL_MODULES]
    chosen = [spec for spec in specs if config.tools is None or spec.name in config.tools]
    if any(not spec.hints.read_only for spec in chosen):
        chosen += [spec for spec in specs if spec.stops and spec not in chosen]
    return chosen


def _start_keepers(specs: Sequence[ToolSpec], fleet: Fleet) -> None:
    """What the served tools need kept in the background (their specs' ``needs``), started on every robot."""
    for need in sorted({need for spec in specs for need in spec.needs}):
        for robot in fleet.robots:
            _KEEPERS[need](robot.session)


def _edge_tools(specs: Sequence[ToolSpec], fleet: Fleet, app: ConsoleApp | None) -> list[EdgeTool]:
    """Every tool listed, made the same way (``adapter.edge_tool``), in the order it is listed: the served
    tools, then ``list_robots`` on a fleet and ``show_console`` with the MCP App."""
    tools = [module_tool(_MODULES[spec.name]) for spec in specs]
    if fleet.several:
        tools.append(list_robots_tool(fleet))
    if app is not None:
        tools.append(app.tool)
    return tools


def _lifespan(
    fleet: Fleet, board: TaskBoard | None
) -> Callable[[Server[None]], AbstractAsyncContextManager[None]]:
    """The server's lifespan: every robot's client started (connecting in the background) and, on leaving,
    what the server set going stopped, the tasks ended, then the clients closed."""

    @asynccontextmanager
    async def lifespan(_server: Server[None]) -> AsyncIterator[None]:
        async with contextlib.AsyncExitStack() as started:
            for robot in fleet.robots:
                client = robot.session.client
                await client.start()
                started.push_async_callback(client.close)
                where = f"{robot.name} at " if fleet.several else ""
                _log.info(
                    "rosbridge-mcp-server %s: connecting to %s%s in the background",
                    __version__,
                    where,
                    client.url,
                )
            sessions = [robot.session for robot in fleet.robots]
            # Left first, before any client closes: what the server set going on the robots is stopped.
            started.push_async_callback(stop_robots, sessions)
            if board is None:
                yield None
                return
            # Tasks end before the connections close: their cancels and zero commands still reach the robot.
            async with board.running():
                try:
                    yield None
                finally:
                    await stop_robots(sessions)  # the robots first, then each task's own end

    return lifespan


class _Resources:
    """``resources/list``, ``resources/read`` and ``prompts/list``: the MCP App's page when it is served."""

    def __init__(self, app: ConsoleApp | None) -> None:
        self._app = app

    async def list_resources(
        self, ctx: ServerRequestContext[None], params: PaginatedRequestParams | None
    ) -> ListResourcesResult:
        return ListResourcesResult(resources=[self._app.resource] if self._app is not None else [])

    async def read_resource(
        self, ctx: ServerRequestContext[None], params: ReadResourceRequestParams
    ) -> ReadResourceResult:
        contents = self._app.read(str(params.uri)) if self._app is not None else None
        if contents is None:
            raise MCPError(code=INVALID_PARAMS, message=f"Unknown resource: {params.uri}")
        return ReadResourceResult(contents=[contents])

    async def list_prompts(
        self, ctx: ServerRequestContext[None], params: PaginatedRequestParams | None
    ) -> ListPromptsResult:
        return ListPromptsResult(prompts=[])
