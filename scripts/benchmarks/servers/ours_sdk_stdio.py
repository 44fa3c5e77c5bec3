"""``rosbridge-mcp-server`` served on the SDK's stdio transport, bare (as ``Server.run`` on its streams).

Our server gives the SDK's transport its stdin and stdout on asyncio pipes
(``rosbridge_mcp_server.server.stdio``); left to itself the transport reads and writes through anyio worker
threads. The "SDK's stdio" rows of the benchmark show what those thread hand-offs cost, and would notice if
either changed.
"""

from __future__ import annotations

from typing import Any

from mcp.server import Server
from mcp.server.stdio import stdio_server

from rosbridge_mcp_server import server as cli
from rosbridge_mcp_server.cli import main

__all__: list[str] = []


async def _serve_through_the_sdk(server: Server[Any]) -> None:
    async with stdio_server() as (read_stream, write_stream):
        await server.run(read_stream, write_stream, server.create_initialization_options())


if __name__ == "__main__":
    cli.serve_stdio = _serve_through_the_sdk  # type: ignore[assignment]
    main()
