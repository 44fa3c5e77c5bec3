"""``serve``: the MCP server on stdio or Streamable HTTP, one robot session per robot, the operator console
beside it when asked for, and SIGTERM / Ctrl-C stopping the robots before the process exits."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
import sys
from collections.abc import AsyncIterator, Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO
from urllib.parse import urlsplit, urlunsplit

from rosbridge_mcp_server.cli.arguments import PROG
from rosbridge_mcp_server.cli.collector import resume_collector
from rosbridge_mcp_server.cli.demo import DemoSettings, demo_robot
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config, ConfigError, plain_text_warning
from rosbridge_mcp_server.config.console import ConsoleSettings
from rosbridge_mcp_server.config.http import HttpSettings
from rosbridge_mcp_server.console import ConsoleHub, RobotView
from rosbridge_mcp_server.console.address import ConsoleAddressFile
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import Audit, Operator, PolicyGuard

if TYPE_CHECKING:
    from rosbridge_mcp_server.server import Robot
    from rosbridge_mcp_server.server.tasks import TaskBoard

__all__ = ["CONSOLE_EXAMPLE_PORT", "SIGNAL_GRACE", "serve"]

#: The console's port in examples and advice: not the MCP HTTP listener's default (8765).
CONSOLE_EXAMPLE_PORT = 8770
#: After SIGTERM or Ctrl-C: how long tool calls get to cancel their goals, and then the client to close.
SIGNAL_GRACE = 1.0
_log = logging.getLogger(__name__)


async def serve(
    config: Config,
    audit_file: TextIO | None = None,
    http: HttpSettings | None = None,
    fleet: Sequence[tuple[str, Config]] = (),
    console: ConsoleSettings | None = None,
    *,
    console_dir: Path | None = None,
    demo: DemoSettings | None = None,
    tasks: bool = True,
) -> None:
    """Serve MCP on stdin/stdout until the client closes stdin, or over HTTP (``http``); until SIGTERM /
    Ctrl-C either way. With a *fleet*, drive each of its robots (else the one ``config`` names). With
    *console*, the operator console beside it (one person, one E-STOP for every robot); its URL is also
    written to a file in *console_dir* (this user's alone) while it runs."""
    # The MCP SDK is imported here, by the one command that serves: `check`, `console-url`, `--help` and a
    # refused command line start without it (about a second of CPU less each).
    from rosbridge_mcp_server.server import build_fleet_server, serve_stdio  # noqa: PLC0415
    from rosbridge_mcp_server.server.fleet import Fleet  # noqa: PLC0415
    from rosbridge_mcp_server.server.tasks import TaskBoard  # noqa: PLC0415

    async with demo_robot(config, demo) as effective:
        operator = Operator(present=console is not None)
        robots = list(fleet) or [("robot", effective)]
        entries, views = _robots(robots, audit_file, operator, fleet=bool(fleet), console=console is not None)
        hub = ConsoleHub(views, operator) if console is not None else None
        board = TaskBoard(Fleet(entries)) if tasks else None
        if hub is not None and board is not None:
            hub.tasks = board.running_tasks
        console_view = hub.snapshot if hub is not None else None
        if http is not None and http.transport == "http":
            server_of = _Served(entries, effective, console_view, board)
            await _serve_http(http, server_of, _console(console, hub, console_dir))
            return
        server = build_fleet_server(entries, effective, console_view=console_view, tasks=board or False)
        resume_collector()
        _stop_on_signals([robot.session for robot in entries])
        if sys.stdin.isatty():
            # Someone ran the server by hand: it waits for JSON-RPC and would look hung without a word.
            _log.warning(
                "This is an MCP server: it speaks JSON-RPC on stdin/stdout and is meant to be started by an "
                "MCP client (Claude Desktop, MCP Inspector). To test the connection from a terminal, run "
                "`%s check%s`. Ctrl-C stops it.",
                PROG,
                " --demo" if demo is not None else "",
            )
        async with _console(console, hub, console_dir):
            await serve_stdio(server)


def _robots(
    robots: Sequence[tuple[str, Config]],
    audit_file: TextIO | None,
    operator: Operator,
    *,
    fleet: bool,
    console: bool,
) -> tuple[list[Robot], list[RobotView]]:
    """Each robot's session (its client, its guard for its policy, audited) as the server and the console
    see it; what each policy says goes to the log first."""
    from rosbridge_mcp_server.server import Robot  # noqa: PLC0415 - serving only

    entries: list[Robot] = []
    views: list[RobotView] = []
    for name, robot_config in robots:
        where = f"{name}: " if fleet else ""
        warning = plain_text_warning(robot_config.url)
        if warning:
            _log.warning("%s%s", where, warning)
        for line in robot_config.policy.describe():
            _log.info("%ssafety %s", where, line.strip())
        rules = robot_config.policy
        if rules.approvals == "console" and rules.confirm != "never" and not console:
            _log.warning(
                "%sthe policy sends every confirmation to the operator console (approvals = console), "
                "but no console is served (--console): every act that needs a confirmation is refused",
                where,
            )
        client = RosbridgeClient(
            robot_config.url,
            connect_timeout=robot_config.connect_timeout,
            request_timeout=robot_config.request_timeout,
            ssl_context=robot_config.ssl_context(),
            headers=robot_config.headers,
        )
        audit = Audit(audit_file, robot=name if fleet else None)
        session = RobotSession(client, PolicyGuard(robot_config.policy, audit, operator))
        entries.append(Robot(name, robot_config, session))
        views.append(RobotView(name, session, audit))
    return entries, views


@dataclass(frozen=True)
class _Served:
    """What the MCP server is built from: the robots, the effective configuration, the console's view and
    the task board."""

    entries: Sequence[Robot]
    config: Config
    console_view: Callable[[], dict[str, Any]] | None
    board: TaskBoard | None


async def _serve_http(
    http: HttpSettings, served: _Served, console: contextlib.AbstractAsyncContextManager[None]
) -> None:
    """Serve over Streamable HTTP, with *console* beside it, until uvicorn stops on a signal."""
    # Imported here: uvicorn and the HTTP stack are only needed for HTTP.
    from rosbridge_mcp_server.server import build_fleet_server  # noqa: PLC0415
    from rosbridge_mcp_server.server.http import listen_http, serve_http  # noqa: PLC0415

    # The MCP listener first: when its port is taken, it is named and nothing else has started.
    sock = listen_http(http)
    server = build_fleet_server(
        served.entries, served.config, console_view=served.console_view, tasks=served.board or False
    )
    resume_collector()
    # uvicorn handles SIGTERM / Ctrl-C: it stops accepting, cancels the sessions (and so their tool
    # calls and goals), then the server's lifespan closes the client. Afterwards it raises the signal
    # again under the handler it found: for SIGTERM that is "ignore", so a stop asked for exits 0, as
    # on stdio (Ctrl-C still ends in KeyboardInterrupt, exit 130).
    previous = signal.signal(signal.SIGTERM, signal.SIG_IGN)
    try:
        async with console:
            await serve_http(server, http, sock=sock, robots=[robot.session for robot in served.entries])
    finally:
        signal.signal(signal.SIGTERM, previous)
        sock.close()


def _stop_on_signals(robots: Sequence[RobotSession]) -> None:
    """Make SIGTERM (how MCP clients stop a server that ignores EOF), Ctrl-C and SIGHUP (its terminal closed)
    stop the robots, then exit.

    The first signal stops what the server set going on every robot (streams ended, a zero on each velocity
    topic, goals cancelled: ``server/shutdown.py``), then cancels the server, so every tool call in flight
    unwinds; any later signal (an impatient second Ctrl-C) is only logged, so it cannot cut the stop short.
    When stdin is a terminal or a file, the SDK's transport reads it in a thread that cancellation cannot
    interrupt, so the server may never finish unwinding on its own: after a short grace the clients are
    closed and the process exits. All of it is bounded (docs/deployment.md says how long).
    """
    main = asyncio.current_task()
    if main is None:
        return
    loop = asyncio.get_running_loop()
    pending: set[asyncio.Task[None]] = set()

    def stop(name: str, exit_code: int) -> None:
        if pending:
            _log.info("%s: already stopping the robot and exiting", name)
            return
        _log.info("%s: stopping the robot, cancelling tool calls, then exiting", name)
        pending.add(loop.create_task(_stop_then_exit(main, robots, exit_code)))

    # Windows event loops have no add_signal_handler; there the default handling applies.
    with contextlib.suppress(NotImplementedError, RuntimeError):
        loop.add_signal_handler(signal.SIGTERM, stop, "SIGTERM", 0)
        loop.add_signal_handler(signal.SIGINT, stop, "SIGINT", 130)
        # The terminal it runs in closed: its default ended the process at once, goals running.
        loop.add_signal_handler(signal.SIGHUP, stop, "SIGHUP", 129)


async def _stop_then_exit(main: asyncio.Task[Any], robots: Sequence[RobotSession], exit_code: int) -> None:
    from rosbridge_mcp_server.server.shutdown import stop_robots  # noqa: PLC0415 - serving only

    await stop_robots(robots)
    main.cancel()
    await asyncio.sleep(SIGNAL_GRACE)
    with contextlib.suppress(Exception):
        await asyncio.wait_for(asyncio.gather(*(robot.client.close() for robot in robots)), SIGNAL_GRACE)
    logging.shutdown()
    os._exit(exit_code)


def _serves(hub: ConsoleHub) -> str:
    """What a console serves, for ``console-url``: ``the robot at ws://...`` or ``robots a at ..., b at ...``
    (the bridge URLs without credentials)."""
    places = [(view.name, _bare_url(view.session.client.url)) for view in hub.robots]
    if len(places) == 1:
        return f"the robot at {places[0][1]}"
    return "robots " + ", ".join(f"{name} at {url}" for name, url in places)


def _bare_url(url: str) -> str:
    parts = urlsplit(url)
    return urlunsplit(parts._replace(netloc=parts.netloc.rpartition("@")[2], query="", fragment=""))


@contextlib.asynccontextmanager
async def _console(
    settings: ConsoleSettings | None, hub: ConsoleHub | None, directory: Path | None = None
) -> AsyncIterator[None]:
    """The operator console beside the MCP server, when asked for; its one-time URL goes to stderr and, with
    *directory*, to a file there that only this user can read (``console-url`` prints it)."""
    if settings is None or hub is None:
        yield
        return
    # Imported here: uvicorn and Starlette are only needed with --console.
    from rosbridge_mcp_server.console.serve import open_console  # noqa: PLC0415

    try:
        opened = open_console(settings, hub)
        running = await opened.__aenter__()
    except OSError as exc:
        raise ConfigError(
            f"the operator console (--console) cannot listen on {settings.host}:{settings.port}: "
            f"{exc.strerror or exc}; give it another port, e.g. --console {CONSOLE_EXAMPLE_PORT}, or "
            "--console 0 for any free one"
        ) from None
    # The URL alone on its line, to copy; it carries the session secret, so it is not a log line either.
    sys.stderr.write(f"{running.url}\n")
    address = ConsoleAddressFile(directory) if directory is not None else None
    where = ""
    if address is not None:
        try:
            address.write(running.url, _serves(hub))
            where = f" (also in {address.path}, which `{PROG} console-url` prints)"
        except OSError as exc:
            address = None
            _log.warning("the console's URL is on stderr only: cannot write it to %s: %s", directory, exc)
    sys.stderr.write(f"operator console: open the URL above in a browser beside the robot{where}\n")
    sys.stderr.flush()
    try:
        yield
    finally:
        if address is not None:
            address.remove()
        await opened.__aexit__(None, None, None)
