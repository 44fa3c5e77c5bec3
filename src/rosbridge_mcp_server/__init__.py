"""rosbridge-mcp-server: an MCP server that watches and drives a ROS robot through rosbridge."""

from __future__ import annotations

__all__ = ["__version__", "main"]

__version__ = "0.1.0"


def main() -> None:
    """Console-script entry point: parse configuration, then serve MCP over stdio."""
    from rosbridge_mcp_server.cli import run

    raise SystemExit(run())
