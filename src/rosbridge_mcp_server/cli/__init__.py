"""The command line: argument parsing (:mod:`.arguments`), the subcommands (serve, ``check``) and their exit
codes (:mod:`.commands`), serving with the console beside it and the signals (:mod:`.serving`), logging to
stderr (:mod:`.log_setup`), the ``check`` diagnostic (:mod:`.check`), the demo's settings and its simulated
robot (:mod:`.demo`), the collector paused while the server starts (:mod:`.collector`).

Importing this package imports nothing else of ours: the console script's :func:`main` pauses the collector
first, then imports the command (``PROG``, ``run`` and ``configure_logging`` are those of its modules).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from rosbridge_mcp_server.cli.collector import pause_collector

if TYPE_CHECKING:
    from rosbridge_mcp_server.cli.arguments import PROG
    from rosbridge_mcp_server.cli.commands import configure_logging, run

__all__ = ["PROG", "configure_logging", "main", "run"]

#: Each name this package re-exports, and the module that holds it.
_HOMES = {"PROG": "arguments", "configure_logging": "commands", "run": "commands"}


def main() -> None:
    """Console-script entry point: parse configuration, then serve MCP over stdio."""
    pause_collector()
    from rosbridge_mcp_server.cli.commands import run  # noqa: PLC0415 - after the collector is paused

    raise SystemExit(run())


def __getattr__(name: str) -> object:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{home}"), name)
