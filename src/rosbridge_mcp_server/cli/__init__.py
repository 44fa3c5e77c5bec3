"""The command line: argument parsing (:mod:`.arguments`), the subcommands (serve, ``check``) and their exit
codes (:mod:`.commands`), serving with the console beside it and the signals (:mod:`.serving`), logging to
stderr (:mod:`.log_setup`), the ``check`` diagnostic (:mod:`.check`), the demo's settings and its simulated
robot (:mod:`.demo`)."""

from __future__ import annotations

from rosbridge_mcp_server.cli.arguments import PROG
from rosbridge_mcp_server.cli.commands import configure_logging, run

__all__ = ["PROG", "configure_logging", "main", "run"]


def main() -> None:
    """Console-script entry point: parse configuration, then serve MCP over stdio."""
    raise SystemExit(run())
