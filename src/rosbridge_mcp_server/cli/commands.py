"""Command line: ``rosbridge-mcp-server [serve] [flags]`` (the MCP server on stdio, or Streamable HTTP with
``--transport http``) and ``... check [flags]``.

Exit codes: 0 done (or healthy, for ``check``), 1 ``check`` found a problem, 2 bad command line or
configuration (one line on stderr, never a traceback), 130 interrupted.

In ``serve`` mode stdout belongs to JSON-RPC: everything else goes to stderr through ``logging``
(``log_setup.py``); the serving itself is ``serving.py``.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TextIO

from rosbridge_mcp_server.cli.arguments import PROG, UsageError, build_parser
from rosbridge_mcp_server.cli.collector import resume_collector
from rosbridge_mcp_server.cli.demo import DemoSettings, demo_robot, demo_settings
from rosbridge_mcp_server.cli.log_setup import configure_logging
from rosbridge_mcp_server.cli.serving import CONSOLE_EXAMPLE_PORT, serve
from rosbridge_mcp_server.config import Config, ConfigError, load_config
from rosbridge_mcp_server.config.addresses import is_loopback
from rosbridge_mcp_server.config.console import ConsoleSettings, console_runtime_dir, load_console_settings
from rosbridge_mcp_server.config.fleet import load_fleet
from rosbridge_mcp_server.config.http import HttpSettings, load_http_settings
from rosbridge_mcp_server.console.address import console_urls

__all__ = ["PROG", "check", "configure_logging", "demo_robot", "open_audit_log", "run", "serve"]


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
        settings = _read_settings(command, args, env)
        audit_file = open_audit_log(settings.config.audit_log) if command == "serve" else None
    except (UsageError, ConfigError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2

    config, http, fleet = settings.config, settings.http, settings.fleet
    # `check` prints its own findings; the client's warnings would only repeat them.
    configure_logging(
        config.log_level if command == "serve" or config.log_level == "DEBUG" else "ERROR",
        secrets=[value for _, value in config.headers]
        + [value for _, robot in fleet for _, value in robot.headers]
        + [token for _, token in http.tokens],
    )
    try:
        return _execute(command, settings, audit_file, env)
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


@dataclass(frozen=True)
class _Settings:
    """Everything the command line and the environment set, read and checked once."""

    options: argparse.Namespace
    config: Config
    http: HttpSettings
    fleet: tuple[tuple[str, Config], ...]
    demo: DemoSettings | None
    console: ConsoleSettings | None


def _read_settings(command: str, args: list[str], env: Mapping[str, str]) -> _Settings:
    """The command line and the environment read into settings; :class:`UsageError` or :class:`ConfigError`
    names what is wrong."""
    options = build_parser(command).parse_args(args)
    config = _robot_config(options, env)
    http = _http_settings(options, env)
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
    return _Settings(options, config, http, fleet, demo, console)


def _robot_config(options: argparse.Namespace, env: Mapping[str, str]) -> Config:
    return load_config(
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


def _http_settings(options: argparse.Namespace, env: Mapping[str, str]) -> HttpSettings:
    return load_http_settings(
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


def _execute(command: str, settings: _Settings, audit_file: TextIO | None, env: Mapping[str, str]) -> int:
    """Run ``check`` (its exit code) or serve until told to stop (0)."""
    if command == "check":
        resume_collector()  # paused for a start of the server only
        return asyncio.run(check(settings.config, sys.stdout, settings.fleet, demo=settings.demo))
    asyncio.run(
        serve(
            settings.config,
            audit_file,
            settings.http,
            settings.fleet,
            settings.console,
            console_dir=console_runtime_dir(env),
            demo=settings.demo,
            tasks=not settings.options.no_tasks,
        )
    )
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


async def check(
    config: Config,
    out: TextIO,
    fleet: Sequence[tuple[str, Config]] = (),
    *,
    demo: DemoSettings | None = None,
) -> int:
    """The ``check`` command: diagnose the bridge (or the *demo* robot), or each robot of a *fleet* in turn;
    0 when every one is healthy, 1 when not."""
    from rosbridge_mcp_server.cli.check import run_check  # noqa: PLC0415 - `check` only, not a server's start

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
