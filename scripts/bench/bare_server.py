"""A bare MCP server over stdio: the reference the benchmark measures our server against.

``scripts/bench.py`` starts it exactly as it starts ``rosbridge-mcp-server`` (the same interpreter, a
separate process on stdio), so the difference between the two is what our server adds on top of the MCP SDK.

* With no flags it has no tools at all: the reference for startup time and memory (items 6 and 7).
* With ``--reference-tools`` it has two tools that do no robot work, so the SDK's own cost can be separated
  from ours: ``noop`` (returns at once: the cost of one tool call through the SDK and stdio) and
  ``sleep(seconds)`` (an ``asyncio.sleep``: the SDK's ceiling for many slow tool calls in parallel).
"""

from __future__ import annotations

import asyncio
import sys

from mcp.server.mcpserver import MCPServer

__all__ = ["build_server", "main"]


def build_server(*, reference_tools: bool) -> MCPServer:
    """An MCPServer with no tools, or with the two reference tools."""
    server: MCPServer = MCPServer(name="bench-bare-reference")
    if reference_tools:

        @server.tool()
        async def noop() -> str:
            """Return at once."""
            return "ok"

        @server.tool()
        async def sleep(seconds: float) -> str:
            """Wait ``seconds`` without blocking other calls, then return."""
            await asyncio.sleep(seconds)
            return "ok"

    return server


def main() -> None:
    """Serve MCP over stdio until stdin closes."""
    build_server(reference_tools="--reference-tools" in sys.argv[1:]).run("stdio")


if __name__ == "__main__":
    main()
