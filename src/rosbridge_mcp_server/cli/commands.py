"""Command line: ``rosbridge-mcp-server [serve] [flags]`` (the MCP server on stdio, or Streamable HTTP with
``--transport http``) and ``... check [flags]``.

Exit codes: 0 done (or healthy, for ``check``), 1 ``check`` found a problem, 2 bad command line or
configuration (one line on stderr, never a traceback), 130 interrupted.

In ``serve`` mode stdout belongs to JSON-RPC: everything else goes to stderr through ``logging``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
import sys
from collections.abc import AsyncIterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO
from urllib.parse import urlsplit, urlunsplit

from rosbridge_mcp_server.cli.arguments import PROG, UsageError, build_parser
from rosbridge_mcp_server.cli.check import run_check
from rosbridge_mcp_server.cli.demo import DemoSettings, demo_robot, demo_settings
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config, ConfigError, load_config, plain_text_warning
from rosbridge_mcp_server.config.addresses import is_loopback
from rosbridge_mcp_server.config.console import ConsoleSettings, console_runtime_dir, load_console_settings
from rosbridge_mcp_server.config.fleet import load_fleet
from rosbridge_mcp_server.config.http import HttpSettings, load_http_settings
from rosbridge_mcp_server.console import ConsoleHub, RobotView
from rosbridge_mcp_server.console.address import ConsoleAddressFile, console_urls
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.robot.text import shown
from rosbridge_mcp_server.safety import Audit, Operator, PolicyGuard

if TYPE_CHECKING:
    from rosbridge_mcp_server.server import Robot

__all__ = ["PROG", "check", "configure_logging", "demo_robot", "open_audit_log", "run", "serve"]

#: The console's port in examples and advice: not the MCP HTTP listener's default (8765).
CONSOLE_EXAMPLE_PORT = 8770
#: After SIGTERM or Ctrl-C: how long tool calls get to cancel their goals, and then the client to close.
SIGNAL_GRACE = 1.0
_log = logging.getLogger(__name__)


def run(argv: Sequence[str] | None = None, environ: Mapping[str, str] | None = None) -> int:
    """Parse the command line and the environment, then serve MCP or run ``check``; returns the exit code."""
    args = list(sys.argv[1:] if argv is None else argv)
    env = os.environ if environ is None else environ
    command = "serve"
    if args and args[0] in ("serve", "check", "console-url"):
        command = args.pop(0)
    if command == "console-url":
        return console_url(args, env)
    try:
        options = build_parser(command).parse_args(args)
        config = load_config(
            env,
            host=options.host,
            port=options.port,
            url=options.url,
            timeout=options.timeout,
            log_level=options.log_level,
            policy=options.policy,
            read_only=options.read_only,
            audit_log=options.audit_log,
            ca_file=options.ca_file,
            client_cert=options.client_cert,
            client_key=options.client_key,
            headers=options.header,
            tools=options.tools,
            record_dir=options.record_dir,
            simulated=options.demo,
        )
        http = load_http_settings(
            env,
            transport=options.transport,
            bind=options.bind,
            auth_tokens=options.auth_tokens,
            allow_hosts=options.allow_host,
            allow_origins=options.allow_origin,
            tls_cert=options.tls_cert,
            tls_key=options.tls_key,
            oauth_issuer=options.oauth_issuer,
            oauth_audience=options.oauth_audience,
            oauth_jwks=options.oauth_jwks,
            oauth_resource=options.oauth_resource,
            oauth_scopes=options.oauth_scopes,
            behind_tls_proxy=options.behind_tls_proxy,
        )
        fleet = load_fleet(config, robots=options.robot, robots_file=options.robots)
        demo = demo_settings(
            options.demo,
            dialect=options.demo_dialect,
            world=options.demo_world,
            robots=options.demo_robots,
            faults=options.demo_fault,
            fleet=fleet,
        )
        console = load_console_settings(
            env,
            address=options.console,
            cert=options.console_cert,
            key=options.console_key,
            insecure=options.console_insecure,
        )
        if console is not None:
            same_port_check(console, http)
        audit_file = open_audit_log(config.audit_log) if command == "serve" else None
    except (UsageError, ConfigError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2

    # `check` prints its own findings; the client's warnings would only repeat them.
    configure_logging(
        config.log_level if command == "serve" or config.log_level == "DEBUG" else "ERROR",
        secrets=[value for _, value in config.headers]
        + [value for _, robot in fleet for _, value in robot.headers]
        + [token for _, token in http.tokens],
    )
    try:
        if command == "check":
            return asyncio.run(check(config, sys.stdout, fleet, demo=demo))
        asyncio.run(
            serve(
                config,
                audit_file,
                http,
                fleet,
                console,
                console_dir=console_runtime_dir(env),
                demo=demo,
                tasks=not options.no_tasks,
            )
        )
    except ConfigError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        # `check | head`: the reader left. Stop quietly, and keep the interpreter's last flush off the pipe.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except asyncio.CancelledError:
        # A signal after stdin was closed: the server unwound and cleaned up by itself.
        return 0
    finally:
        if audit_file is not None:
            audit_file.close()
    return 0


def console_url(args: Sequence[str], env: Mapping[str, str]) -> int:
    """``console-url``: print the URL of each operator console this user runs now (0), or say there is none
    (1). The URL carries the console's secret: it is for the person, not for a model's context."""
    try:
        build_parser("console-url").parse_args(list(args))
    except UsageError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    directory = console_runtime_dir(env)
    found = list(console_urls(directory))
    for pid, url, serves in found:
        # Several consoles: each says which robot it is for, so the person opens the right one.
        print(f"{url}  (process {pid}{f', {serves}' if serves else ''})" if len(found) > 1 else url)
    if not found:
        print(
            f"{PROG}: no operator console is running for this user (looked in {directory}); start the server "
            "with --console PORT",
            file=sys.stderr,
        )
        return 1
    return 0


def same_port_check(console: ConsoleSettings, http: HttpSettings) -> None:
    """:class:`ConfigError` when ``--console`` and the MCP HTTP listener's ``--bind`` name one port."""
    if http.transport != "http" or console.port == 0 or console.port != http.port:
        return
    wildcard = ("0.0.0.0", "::", "")
    if (
        console.host == http.host
        or console.host in wildcard
        or http.host in wildcard
        or (console.loopback and is_loopback(http.host))
    ):
        raise ConfigError(
            f"--console {console.host}:{console.port} and the MCP HTTP listener "
            f"(--bind {http.host}:{http.port}{', the default' if http.port == 8765 else ''}) "
            "name the same port; give the console another, "
            f"e.g. --console {CONSOLE_EXAMPLE_PORT} (or --console 0 for any free port)"
        )


def open_audit_log(path: str | None) -> TextIO | None:
    """The audit file, opened for appending (line-buffered); :class:`ConfigError` if it cannot be."""
    if path is None:
        return None
    try:
        return open(path, "a", encoding="utf-8", buffering=1)
    except OSError as exc:
        raise ConfigError(f"audit log: cannot open {path!r} for appending: {exc.strerror or exc}") from None


def configure_logging(level: str, stream: TextIO | None = None, secrets: Sequence[str] = ()) -> None:
    """Log to stderr: our own loggers at ``level``, everyone else's at WARNING (or DEBUG when asked).

    ``secrets`` (e.g. the values of ``--header``) are replaced by ``***`` in every line: at DEBUG, websockets
    logs each handshake header it sends.
    """
    handler = logging.StreamHandler(stream if stream is not None else sys.stderr)
    handler.set_name(PROG)
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
    if secrets:
        handler.addFilter(_Redact(secrets))
    handler.addFilter(_OneLine())
    root = logging.getLogger()
    # Replace only our own handler (run() may be called more than once in one process, e.g. in tests). Having
    # a handler on the root also keeps MCPServer's logging.basicConfig from adding its own.
    for old in [h for h in root.handlers if h.get_name() == PROG]:
        root.removeHandler(old)
    root.addHandler(handler)
    root.setLevel(logging.DEBUG if level == "DEBUG" else logging.WARNING)
    logging.getLogger("rosbridge_mcp_server").setLevel(level)


class _Redact(logging.Filter):
    """Replaces each secret by ``***`` in a record's message (and drops its arguments, already merged)."""

    def __init__(self, secrets: Sequence[str]) -> None:
        super().__init__()
        self._secrets = [secret for secret in secrets if secret]

    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        if any(secret in message for secret in self._secrets):
            for secret in self._secrets:
                message = message.replace(secret, "***")
            record.msg, record.args = message, None
        return True


#: The longest message one log line carries (a traceback, written after it, is not cut).
LOG_LINE_CHARS = 10_000


class _OneLine(logging.Filter):
    """Each record's message on one line, escaped as robot text is (``robot/text.py``): a message quotes
    what the robot, a bridge or a caller wrote (a refusal's text, a JWT's subject), and a newline or an ANSI
    sequence in it must not write a line of its own on the operator's terminal."""

    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        safe = shown(message, LOG_LINE_CHARS)
        if safe is not message:
            record.msg, record.args = safe, None
        return True


def _stop_on_signals(robots: Sequence[RobotSession]) -> None:
    """Make SIGTERM (how MCP clients stop a server that ignores EOF) and Ctrl-C stop the robots, then exit.

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


async def _stop_then_exit(main: asyncio.Task[Any], robots: Sequence[RobotSession], exit_code: int) -> None:
    from rosbridge_mcp_server.server.shutdown import stop_robots  # noqa: PLC0415 - serving only

    await stop_robots(robots)
    main.cancel()
    await asyncio.sleep(SIGNAL_GRACE)
    with contextlib.suppress(Exception):
        await asyncio.wait_for(asyncio.gather(*(robot.client.close() for robot in robots)), SIGNAL_GRACE)
    logging.shutdown()
    os._exit(exit_code)


async def check(
    config: Config,
    out: TextIO,
    fleet: Sequence[tuple[str, Config]] = (),
    *,
    demo: DemoSettings | None = None,
) -> int:
    """The ``check`` command: diagnose the bridge (or the *demo* robot), or each robot of a *fleet* in turn;
    0 when every one is healthy, 1 when not."""
    if fleet:
        worst = 0
        for number, (name, robot_config) in enumerate(fleet):
            if number:
                out.write("\n")
            out.write(f"== robot {name} ({robot_config.url}) ==\n")
            worst = max(worst, await run_check(robot_config, out))
        unhealthy = "" if worst == 0 else " (at least one is not healthy: see above)"
        out.write(f"\nchecked {len(fleet)} robots{unhealthy}\n")
        return worst
    async with demo_robot(config, demo) as effective:
        return await run_check(effective, out, demo=demo)


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
    from rosbridge_mcp_server.server import Robot, build_fleet_server, serve_stdio  # noqa: PLC0415
    from rosbridge_mcp_server.server.fleet import Fleet  # noqa: PLC0415
    from rosbridge_mcp_server.server.tasks import TaskBoard  # noqa: PLC0415

    async with demo_robot(config, demo) as effective:
        robots = list(fleet) or [("robot", effective)]
        entries: list[Robot] = []
        operator = Operator(present=console is not None)
        views: list[RobotView] = []
        for name, robot_config in robots:
            where = f"{name}: " if fleet else ""
            warning = plain_text_warning(robot_config.url)
            if warning:
                _log.warning("%s%s", where, warning)
            for line in robot_config.policy.describe():
                _log.info("%ssafety %s", where, line.strip())
            rules = robot_config.policy
            if rules.approvals == "console" and rules.confirm != "never" and console is None:
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
        hub = ConsoleHub(views, operator) if console is not None else None
        board = TaskBoard(Fleet(entries)) if tasks else None
        if hub is not None and board is not None:
            hub.tasks = board.running_tasks
        console_view = hub.snapshot if hub is not None else None
        if http is not None and http.transport == "http":
            # Imported here: uvicorn and the HTTP stack are only needed for HTTP.
            from rosbridge_mcp_server.server.http import listen_http, serve_http  # noqa: PLC0415

            # The MCP listener first: when its port is taken, it is named and nothing else has started.
            sock = listen_http(http)
            server = build_fleet_server(entries, effective, console_view=console_view, tasks=board or False)
            # uvicorn handles SIGTERM / Ctrl-C: it stops accepting, cancels the sessions (and so their tool
            # calls and goals), then the server's lifespan closes the client. Afterwards it raises the signal
            # again under the handler it found: for SIGTERM that is "ignore", so a stop asked for exits 0, as
            # on stdio (Ctrl-C still ends in KeyboardInterrupt, exit 130).
            previous = signal.signal(signal.SIGTERM, signal.SIG_IGN)
            try:
                async with _console(console, hub, console_dir):
                    await serve_http(server, http, sock=sock, robots=[robot.session for robot in entries])
            finally:
                signal.signal(signal.SIGTERM, previous)
                sock.close()
            return
        server = build_fleet_server(entries, effective, console_view=console_view, tasks=board or False)
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
