"""``rosbridge-mcp-server`` served through the MCP SDK's own stdio transport instead of ours.

Our server reads and writes stdio through asyncio pipes (``rosbridge_mcp_server.server.stdio``); the SDK's
transport hands every line read and every write and flush to an anyio worker thread instead. This runs
our unchanged server with that one choice reverted, so the benchmark keeps showing what the hand-offs cost
(the "SDK's stdio" comparison rows) and would notice if an SDK release made them cheap.
"""

from __future__ import annotations

from typing import Any

from mcp.server.mcpserver import MCPServer

from rosbridge_mcp_server.cli import commands as cli
from rosbridge_mcp_server.cli import main

__all__: list[str] = []


async def _serve_through_the_sdk(server: MCPServer[Any]) -> None:
    await server.run_stdio_async()


if __name__ == "__main__":
    cli.serve_stdio = _serve_through_the_sdk  # type: ignore[assignment]
    main()
