"""`rosbridge-mcp-server` with stdio read and written through asyncio pipes: an experiment, not a product.

The MCP SDK's default stdio transport hands every line read and every write and flush to an anyio worker
thread. This runs our unchanged server with ``MCPServer.run_stdio_async`` swapped for the thread-free
transport of ``bare_server.py``, so the benchmark can show what our tool calls would cost without the
hand-offs (rows marked "asyncio stdio").
"""

from __future__ import annotations

from bare_server import serve_over_asyncio_pipes  # this script's own folder is first on sys.path
from mcp.server.mcpserver import MCPServer

from rosbridge_mcp_server import main

__all__: list[str] = []

if __name__ == "__main__":
    MCPServer.run_stdio_async = serve_over_asyncio_pipes  # type: ignore[method-assign]
    main()
