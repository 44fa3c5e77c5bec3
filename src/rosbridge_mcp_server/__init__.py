"""rosbridge-mcp-server: an MCP server that watches and drives a ROS robot through rosbridge."""

from __future__ import annotations

__all__ = ["__version__", "main"]

__version__ = "0.1.0"


def main() -> None:
    """Console-script entry point: parse configuration, then serve MCP over stdio."""
    # Imported on use: `import rosbridge_mcp_server` (the simulated robot does) need not load the MCP SDK.
    from rosbridge_mcp_server.cli import main as cli_main  # noqa: PLC0415

    cli_main()
