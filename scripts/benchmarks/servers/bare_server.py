"""A bare MCP server over stdio: the reference the benchmark measures our server against.

``scripts/bench.py`` starts it exactly as it starts ``rosbridge-mcp-server`` (the same interpreter, a
separate process on stdio), so the difference between the two is what our server adds on top of the MCP SDK.

* With no flags it has no tools at all and serves through the SDK's own stdio transport: the reference for
  startup time and memory (items 6 and 7).
* With ``--reference-tools`` it has two tools that do no robot work, so the SDK's own cost can be separated
  from ours: ``noop`` (returns at once: the cost of one tool call through the SDK and stdio) and
  ``sleep(seconds)`` (an ``asyncio.sleep``: the SDK's ceiling for many slow tool calls in parallel).
* With ``--our-stdio`` it serves through our transport (``server.stdio.serve_stdio``: asyncio
  pipes, no worker threads) instead of the SDK's, which hands every line read and every write and flush to an
  anyio worker thread. Our server uses that transport, so this is the like-for-like reference for its tool
  calls; the SDK's is kept as a second reference to show what the hand-offs cost.
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
    flags = set(sys.argv[1:])
    server = build_server(reference_tools="--reference-tools" in flags)
    if "--our-stdio" in flags:
        # Imported only here: the startup and memory reference must not load our package.
        from rosbridge_mcp_server.server.stdio import serve_stdio  # noqa: PLC0415

        # Our transport serves the SDK's low-level server, which a bare MCPServer is built on.
        asyncio.run(serve_stdio(server._lowlevel_server))
    else:
        server.run("stdio")


if __name__ == "__main__":
    main()
