"""A bare MCP server over stdio: the reference the benchmark measures our server against.

``scripts/bench.py`` starts it exactly as it starts ``rosbridge-mcp-server`` (the same interpreter, a
separate process on stdio), so the difference between the two is what our server adds on top of the MCP SDK.

* With no flags it has no tools at all: the reference for startup time and memory (items 6 and 7).
* With ``--reference-tools`` it has two tools that do no robot work, so the SDK's own cost can be separated
  from ours: ``noop`` (returns at once: the cost of one tool call through the SDK and stdio) and
  ``sleep(seconds)`` (an ``asyncio.sleep``: the SDK's ceiling for many slow tool calls in parallel).
* ``--asyncio-stdio`` serves the same server with stdin and stdout read and written through asyncio pipes
  instead of the SDK's default, which hands every line read and every write and flush to an anyio worker
  thread. The difference between the two is what those thread hand-offs cost per call.
"""

from __future__ import annotations

import asyncio
import os
import sys
from collections.abc import AsyncIterator

from mcp.server.mcpserver import MCPServer
from mcp.server.stdio import stdio_server

__all__ = ["build_server", "main", "serve_over_asyncio_pipes"]


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


class _PipeLines:
    """stdin lines from an asyncio pipe, shaped like the ``anyio.AsyncFile`` that ``stdio_server`` reads."""

    def __init__(self, reader: asyncio.StreamReader) -> None:
        self._reader = reader

    def __aiter__(self) -> AsyncIterator[str]:
        return self._lines()

    async def _lines(self) -> AsyncIterator[str]:
        while line := await self._reader.readline():
            yield line.decode("utf-8", errors="replace")


class _PipeText:
    """stdout through an asyncio pipe, shaped like the ``anyio.AsyncFile`` that ``stdio_server`` writes."""

    def __init__(self, writer: asyncio.StreamWriter) -> None:
        self._writer = writer

    async def write(self, text: str) -> None:
        self._writer.write(text.encode("utf-8"))

    async def flush(self) -> None:
        await self._writer.drain()


async def serve_over_asyncio_pipes(server: MCPServer) -> None:
    """Serve ``server`` on stdin/stdout like ``MCPServer.run_stdio_async``, with no worker threads."""
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader(limit=64 * 1024 * 1024)
    await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), os.fdopen(os.dup(0), "rb", 0))
    transport, protocol = await loop.connect_write_pipe(
        asyncio.streams.FlowControlMixin, os.fdopen(os.dup(1), "wb", 0)
    )
    writer = asyncio.StreamWriter(transport, protocol, None, loop)
    # MCPServer has no public way to run on given streams; this is what run_stdio_async does inside.
    lowlevel = server._lowlevel_server
    async with stdio_server(stdin=_PipeLines(reader), stdout=_PipeText(writer)) as (read, write):  # type: ignore[arg-type]
        await lowlevel.run(read, write, lowlevel.create_initialization_options())


def main() -> None:
    """Serve MCP over stdio until stdin closes."""
    flags = set(sys.argv[1:])
    server = build_server(reference_tools="--reference-tools" in flags)
    if "--asyncio-stdio" in flags:
        asyncio.run(serve_over_asyncio_pipes(server))
    else:
        server.run("stdio")


if __name__ == "__main__":
    main()
