"""MCP over stdin/stdout through asyncio pipes: the SDK's stdio transport without its worker threads.

The SDK's own transport (``mcp.server.stdio``) hands every line it reads and every write and flush to an
anyio worker thread: three thread hand-offs per tool call, measured at 0.3-0.7 ms of a call's latency on
our machines (``docs/performance.md``). When the MCP host gives us pipes or sockets, as every host does, we
read and write them from the event loop instead and reuse the SDK's framing (``stdio_server`` with explicit
streams). Anything else (a terminal, a regular file) goes through the SDK's transport unchanged: a person
typing JSON needs no speed, and a terminal's file description is shared with the shell, which must not be
left non-blocking.

Like the SDK, we keep stray output off the wire: while serving, fd 1 points at stderr and fd 0 at the null
device; the wire is served from private duplicates, and both descriptors are restored on the way out.
"""

from __future__ import annotations

import asyncio
import contextlib
import fcntl
import os
import stat
from collections.abc import AsyncIterator, Iterator
from typing import TYPE_CHECKING, Any, cast

from mcp.server.stdio import stdio_server

from rosbridge_mcp_server.server.sdk import serve_streams

if TYPE_CHECKING:
    import anyio
    from mcp.server.mcpserver import MCPServer

__all__ = ["serve_stdio"]

# One JSON-RPC message per line; a tool call carrying a large message (an image, a map) can be long.
_MAX_LINE = 64 * 1024 * 1024


async def serve_stdio(server: MCPServer[Any]) -> None:
    """Serve ``server`` on this process's stdin/stdout until stdin closes."""
    if not (_is_pipe_or_socket(0) and _is_pipe_or_socket(1)):
        await server.run_stdio_async()
        return
    with _claim_std_fds() as (wire_in, wire_out):
        loop = asyncio.get_running_loop()
        reader = asyncio.StreamReader(limit=_MAX_LINE)
        read_transport, _ = await loop.connect_read_pipe(
            lambda: asyncio.StreamReaderProtocol(reader), os.fdopen(wire_in, "rb", buffering=0, closefd=False)
        )
        write_transport, write_protocol = await loop.connect_write_pipe(
            asyncio.streams.FlowControlMixin, os.fdopen(wire_out, "wb", buffering=0, closefd=False)
        )
        writer = asyncio.StreamWriter(write_transport, write_protocol, None, loop)
        try:
            stdin = cast("anyio.AsyncFile[str]", _Lines(reader))
            stdout = cast("anyio.AsyncFile[str]", _Text(writer))
            async with stdio_server(stdin=stdin, stdout=stdout) as (read_stream, write_stream):
                await serve_streams(server, read_stream, write_stream)
        finally:
            read_transport.close()
            write_transport.close()


def _is_pipe_or_socket(fd: int) -> bool:
    try:
        mode = os.fstat(fd).st_mode
    except OSError:
        return False
    return stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode)


@contextlib.contextmanager
def _claim_std_fds() -> Iterator[tuple[int, int]]:
    """Private duplicates of fd 0 and 1 for the wire; fd 0 → /dev/null and fd 1 → stderr meanwhile."""
    wire_in = fcntl.fcntl(0, fcntl.F_DUPFD_CLOEXEC, 3)
    wire_out = fcntl.fcntl(1, fcntl.F_DUPFD_CLOEXEC, 3)
    null = os.open(os.devnull, os.O_RDONLY)
    try:
        os.dup2(null, 0)
        os.dup2(2, 1)
    finally:
        os.close(null)
    try:
        yield wire_in, wire_out
    finally:
        # The event loop made the wire non-blocking; the host's end of a socket pair shares that flag.
        for fd in (wire_in, wire_out):
            with contextlib.suppress(OSError):
                os.set_blocking(fd, True)
        os.dup2(wire_in, 0)
        os.dup2(wire_out, 1)
        os.close(wire_in)
        os.close(wire_out)


class _Lines:
    """stdin lines from an asyncio pipe, shaped like the ``anyio.AsyncFile`` ``stdio_server`` iterates."""

    def __init__(self, reader: asyncio.StreamReader) -> None:
        self._reader = reader

    def __aiter__(self) -> AsyncIterator[str]:
        return self._lines()

    async def _lines(self) -> AsyncIterator[str]:
        while line := await self._reader.readline():
            yield line.decode("utf-8", errors="replace")


class _Text:
    """stdout through an asyncio pipe, shaped like the ``anyio.AsyncFile`` that ``stdio_server`` writes."""

    def __init__(self, writer: asyncio.StreamWriter) -> None:
        self._writer = writer

    async def write(self, text: str) -> None:
        self._writer.write(text.encode("utf-8"))

    async def flush(self) -> None:
        await self._writer.drain()
