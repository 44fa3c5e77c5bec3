"""The command line's arguments: one parser per command (``serve``, the default, and ``check``), its flags in
groups, and a bad command line as :class:`UsageError` (one line, exit code 2) rather than argparse's exit."""

from __future__ import annotations

import argparse
from typing import NoReturn

from rosbridge_mcp_server import __version__
from rosbridge_mcp_server.catalogue import groups_help
from rosbridge_mcp_server.config import LOG_LEVELS
from rosbridge_mcp_server.config.http import DEFAULT_BIND

__all__ = ["PROG", "UsageError", "build_parser"]

PROG = "rosbridge-mcp-server"


class UsageError(Exception):
    """argparse found a bad command line."""


class _Parser(argparse.ArgumentParser):
    # argparse prints usage plus the message and exits; we want one line and our own exit code.
    def error(self, message: str) -> NoReturn:
        raise UsageError(message)


def _console_flags(parser: argparse.ArgumentParser) -> None:
    console = parser.add_argument_group("operator console (docs/console.md)")
    console.add_argument(
        "--console",
        metavar="[HOST:]PORT",
        help="serve a web page for the person beside the robot (default host 127.0.0.1); its URL is "
        "written on stderr (env ROSBRIDGE_MCP_CONSOLE)",
    )
    console.add_argument("--console-cert", help="TLS certificate for the console (PEM)")
    console.add_argument("--console-key", help="the TLS certificate's key (PEM)")
    console.add_argument(
        "--console-insecure",
        action="store_true",
        help="allow plain HTTP on a non-loopback --console address (a trusted network only)",
    )


def build_parser(command: str) -> _Parser:
    """The parser of *command* (``serve``, ``check`` or ``console-url``); ``check`` takes every flag ``serve``
    takes."""
    parser = _command_parser(command)
    if command == "console-url":
        return parser
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    _connection_flags(parser)
    _safety_flags(parser)
    _server_flags(parser)
    # `check` takes every flag the server takes, so a server's command line can be checked as it is: it
    # checks each robot of a fleet, and refuses a transport or console setting the server would refuse.
    _fleet_flags(parser)
    _transport_flags(parser)
    _console_flags(parser)
    _demo_flags(parser)
    return parser


def _command_parser(command: str) -> _Parser:
    if command == "console-url":
        return _Parser(
            prog=f"{PROG} console-url",
            description="Print the URL (with its one-time secret) of each operator console this user runs "
            "now (started with --console). Exit code 0 when one runs, 1 when none does. Set "
            "ROSBRIDGE_MCP_RUNTIME_DIR if the server was started with it.",
        )
    if command == "check":
        description = (
            "Diagnose the connection to rosbridge: is it reachable, which ROS it runs, what rosbridge can "
            "do, whether rosapi answers; every robot of --robot / --robots. It takes the server's flags "
            "(the transport and console ones are only checked). Exit code 0 when healthy, 1 when not."
        )
    else:
        description = (
            "MCP server (stdio, or Streamable HTTP) that lets an AI assistant watch and drive a ROS robot "
            "through rosbridge. Use `check` to diagnose the connection."
        )
    if command == "check":
        parser = _Parser(prog=f"{PROG} check", description=description)
    else:
        parser = _Parser(
            prog=PROG,
            usage=f"{PROG} [serve] [options]\n       {PROG} check [options]\n       {PROG} console-url",
            description=description,
            epilog=(
                "commands: serve (the default) runs the MCP server; check diagnoses the connection to "
                f"rosbridge with the same flags (`{PROG} check --help`); console-url prints the URL of the "
                "operator console running now."
            ),
        )
    return parser


def _connection_flags(parser: _Parser) -> None:
    connection = parser.add_argument_group("connection (flags win over the environment)")
    connection.add_argument("--host", help="rosbridge host (env ROSBRIDGE_HOST, default localhost)")
    connection.add_argument("--port", help="rosbridge port (env ROSBRIDGE_PORT, default 9090)")
    connection.add_argument(
        "--url", help="full ws:// or wss:// URL, path included; wins over host/port (env ROSBRIDGE_URL)"
    )
    connection.add_argument(
        "--timeout", help="default request timeout in seconds (env ROSBRIDGE_TIMEOUT, default 10)"
    )
    security = parser.add_argument_group("connection security")
    security.add_argument("--ca-file", help="CA certificate(s) to trust for wss:// (env ROSBRIDGE_CA_FILE)")
    security.add_argument(
        "--client-cert",
        help="client certificate for wss:// (PEM, may hold the key) (env ROSBRIDGE_CLIENT_CERT)",
    )
    security.add_argument("--client-key", help="client certificate's key (env ROSBRIDGE_CLIENT_KEY)")
    security.add_argument(
        "--header",
        action="append",
        metavar="'NAME: VALUE'",
        help=(
            "extra HTTP header for the WebSocket handshake, repeatable, e.g. 'Authorization: Bearer …' "
            "(env ROSBRIDGE_HEADERS, one per line; prefer the environment for secrets)"
        ),
    )


def _safety_flags(parser: _Parser) -> None:
    safety = parser.add_argument_group("safety")
    safety.add_argument(
        "--policy", help="safety policy TOML file (env ROSBRIDGE_MCP_POLICY); see docs/safety.md"
    )
    safety.add_argument(
        "--read-only",
        action="store_true",
        help="only reading tools are listed or callable (env ROSBRIDGE_MCP_READ_ONLY=1)",
    )
    safety.add_argument(
        "--audit-log",
        help="append one JSON line per acting call to this file (env ROSBRIDGE_MCP_AUDIT_LOG)",
    )


def _server_flags(parser: _Parser) -> None:
    parser.add_argument(
        "--record-dir",
        help=(
            "where record writes MCAP files and read_recording reads them (env ROSBRIDGE_MCP_RECORD_DIR, "
            "default ~/.local/share/rosbridge-mcp-server/recordings)"
        ),
    )
    parser.add_argument(
        "--tools",
        help=(
            f"tools the host sees: {groups_help()}; "
            "or a comma list of groups and tool names (env ROSBRIDGE_MCP_TOOLS, default all)"
        ),
    )
    parser.add_argument(
        "--no-tasks",
        action="store_true",
        help="never answer a long call (a drive, a goal, a recording) with an MCP task: every call runs to "
        "its end, as for a client without tasks",
    )
    parser.add_argument(
        "--log-level",
        help=f"stderr log level: {', '.join(LOG_LEVELS)} (env ROSBRIDGE_MCP_LOG_LEVEL, default INFO)",
    )


def _demo_flags(parser: _Parser) -> None:
    demo = parser.add_argument_group("demo")
    demo.add_argument(
        "--demo", action="store_true", help="start the built-in simulated robot and connect to it"
    )
    demo.add_argument(
        "--demo-dialect",
        choices=("ros1", "ros2"),
        default="ros2",
        help="which rosbridge the simulated robot imitates (default ros2)",
    )
    demo.add_argument(
        "--demo-world",
        choices=("turtle", "nav2", "arm"),
        default="turtle",
        help="the simulated robot: turtle (default), nav2 (a Nav2 mobile robot's graph, ~36 nodes) or arm "
        "(the turtle with a 6-joint arm and a gripper; ROS 1 too)",
    )
    demo.add_argument(
        "--demo-robots",
        type=int,
        default=1,
        metavar="N",
        help="with --demo-world nav2: N robots under /robot1 ... /robotN (default 1)",
    )
    demo.add_argument(
        "--demo-fault",
        default=None,
        metavar="NAME[,NAME...]",
        help="with --demo-world nav2: break the robot on purpose (scan-stopped, tf-stale, driver-error, "
        "controller-inactive, log-errors, node-gone); with arm: arm-controller-inactive, joint-states-stale",
    )


def _fleet_flags(parser: _Parser) -> None:
    fleet = parser.add_argument_group("several robots (every tool then takes a robot argument)")
    fleet.add_argument(
        "--robot",
        action="append",
        metavar="NAME=URL",
        help="a robot and its rosbridge URL, repeatable; the other flags apply to each",
    )
    fleet.add_argument(
        "--robots",
        metavar="FILE",
        help="robots in TOML: [robots.NAME] with url and optional headers, ca_file, client_cert, client_key, "
        "policy, read_only",
    )


def _transport_flags(parser: _Parser) -> None:
    http = parser.add_argument_group("MCP transport (see docs/deployment.md)")
    http.add_argument(
        "--transport",
        choices=("stdio", "http"),
        help="stdio (default, started by the host) or http: Streamable HTTP (env ROSBRIDGE_MCP_TRANSPORT)",
    )
    http.add_argument(
        "--bind",
        metavar="HOST:PORT",
        help=f"HTTP address, path /mcp (env ROSBRIDGE_MCP_BIND, default {DEFAULT_BIND})",
    )
    http.add_argument(
        "--auth-tokens",
        metavar="FILE",
        help="bearer tokens, one 'name token' per line (env ROSBRIDGE_MCP_AUTH_TOKENS: the pairs themselves)",
    )
    http.add_argument(
        "--allow-host",
        action="append",
        metavar="NAME[:PORT]",
        help="another Host clients use (a DNS name, a proxy's), repeatable (env ROSBRIDGE_MCP_ALLOWED_HOSTS)",
    )
    http.add_argument(
        "--allow-origin",
        action="append",
        metavar="URL",
        help="another browser Origin to accept, repeatable (env ROSBRIDGE_MCP_ALLOWED_ORIGINS)",
    )
    http.add_argument("--tls-cert", metavar="FILE", help="serve HTTPS with this certificate (PEM)")
    http.add_argument("--tls-key", metavar="FILE", help="the certificate's private key (PEM)")
    http.add_argument(
        "--behind-tls-proxy",
        action="store_true",
        help="a reverse proxy in front terminates TLS: allows plain HTTP on a non-loopback --bind "
        "(env ROSBRIDGE_MCP_BEHIND_TLS_PROXY=1)",
    )
    oauth = parser.add_argument_group("OAuth 2.1 resource server (JWT access tokens)")
    oauth.add_argument("--oauth-issuer", metavar="URL", help="the authorization server (the tokens' iss)")
    oauth.add_argument("--oauth-audience", metavar="AUD", help="the tokens' aud (default: --oauth-resource)")
    oauth.add_argument(
        "--oauth-jwks",
        metavar="URL|FILE",
        help="the issuer's signing keys (default ISSUER/.well-known/jwks.json)",
    )
    oauth.add_argument(
        "--oauth-resource",
        metavar="URL",
        help="this server's public URL, e.g. https://robot.example.com/mcp (default: the bind address)",
    )
    oauth.add_argument("--oauth-scopes", metavar="A,B", help="scopes every token must carry")
