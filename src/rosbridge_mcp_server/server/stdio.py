"""MCP over stdin/stdout: the SDK's stdio transport fed through asyncio pipes, every line it cannot read
answered.

The SDK's transport (``mcp.server.stdio.stdio_server``) takes the streams it reads and writes as arguments.
Left to itself it wraps stdin and stdout in anyio worker threads: every line read, every write and every flush
is a hand-off to a thread and back, three per tool call, which cost 0.3-0.7 ms of each call's latency on our
machines (``docs/performance.md``). When the host gives us pipes or sockets, as every MCP host does, we hand
it streams read and written from the event loop instead (:class:`_PipeOut`,
:meth:`_BoundedLines.from_stream`); a terminal or a regular file keeps the worker threads (a person typing
JSON needs no speed, and a terminal's file description is shared with the shell, which must not be left
non-blocking).

The transport hands a line it cannot read (not JSON, JSON nested deeper than its parser allows, not JSON-RPC)
on as an exception, which the SDK only logs at debug level: the client would wait forever. Here each gets the
JSON-RPC error reply (-32700 / -32600) under the request's id when the text shows it, so every line gets an
answer.

Stray output stays off the wire, as with the SDK's own transport: while serving, fd 0 points at the null
device and fd 1 at stderr, the wire is served from private duplicates, and both are restored on the way out
(:func:`_diverted`; the SDK diverts a descriptor itself only when it is given no stream for it, and what it
relies on of the streams it is given is listed in ``server/sdk.py``: :func:`~.sdk.stdio_streams`).

Lines are bounded: the transport reads a line whole, so a client could make the server hold any amount of
memory with one line. We give it stdin's lines ourselves (:class:`_BoundedLines`): a line longer than
:data:`MAX_LINE_BYTES` is read to its end without being kept (its first 64 KiB and last 1,000 bytes are kept
to find its id) and answered ``-32600`` naming the limit.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import re
import stat
import sys
from collections.abc import AsyncIterator, Awaitable, Callable, Iterator
from typing import TYPE_CHECKING, Any, BinaryIO

import anyio
from mcp.types import INVALID_REQUEST, PARSE_ERROR, ErrorData, JSONRPCError
from pydantic import ValidationError

from rosbridge_mcp_server.server.sdk import LineSink, LineSource, answering_stream, stdio_streams

if TYPE_CHECKING:
    from mcp.server import Server

__all__ = ["MAX_LINE_BYTES", "reply_for_unreadable", "serve_stdio"]

_log = logging.getLogger(__name__)

_ID_VALUE = re.compile(r'\s*("(?:[^"\\]|\\.)*"|-?\d+)\s*[,}]')
#: How much of an unreadable line is scanned for its id from the start (clients write "id" early).
_SCAN_CHARS = 64 * 1024
_TRAILING_ID = re.compile(r'[,{]\s*"id"\s*:\s*("(?:[^"\\]|\\.)*"|-?\d+)\s*}\s*$')
#: The longest line read from stdin, in bytes (without its newline); a longer one is answered -32600.
MAX_LINE_BYTES = 64 * 1024 * 1024
#: The key of the small object that stands in for an over-long line on its way through the SDK's transport.
_TOO_LONG = "rosbridge_mcp_line_too_long"
_TAIL_BYTES = 1000
_CHUNK_BYTES = 1024 * 1024


async def serve_stdio(server: Server[Any]) -> None:
    """Serve ``server`` on this process's stdin/stdout until stdin closes."""
    async with (
        _wire() as (lines, out),
        stdio_streams(lines, out) as (read_stream, write_stream),
    ):
        answering = answering_stream(read_stream, write_stream, reply_for_unreadable)
        await server.run(answering, write_stream, server.create_initialization_options())


@contextlib.asynccontextmanager
async def _wire() -> AsyncIterator[tuple[LineSource | None, LineSink | None]]:
    """What the SDK's transport reads and writes: asyncio pipes when fd 0 and fd 1 are pipes or sockets; else
    stdin's lines read by a worker thread and stdout left to the SDK (which then diverts fd 1 itself); both
    ``None`` when stdin is not fd 0 (the SDK's own transport, whole)."""
    if sys.platform == "win32":
        yield None, None
    elif _is_pipe_or_socket(0) and _is_pipe_or_socket(1):
        async with _pipes() as streams:
            yield streams
    elif _backed_by(sys.stdin, 0):
        with _diverted(0, _null) as private:
            yield _BoundedLines.from_file(os.fdopen(private, "rb", closefd=False)), None
    else:
        yield None, None


def _backed_by(stream: Any, fd: int) -> bool:
    try:
        return stream is not None and bool(stream.buffer.fileno() == fd)
    except (AttributeError, OSError, ValueError):
        return False


def _is_pipe_or_socket(fd: int) -> bool:
    try:
        mode = os.fstat(fd).st_mode
    except OSError:
        return False
    return stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode)


def _null() -> int:
    return os.open(os.devnull, os.O_RDONLY)


def _stderr() -> int:
    return os.dup(2)


@contextlib.contextmanager
def _diverted(fd: int, diversion: Callable[[], int]) -> Iterator[int]:
    """A private duplicate of *fd* (the wire, above the standard descriptors and closed in child processes)
    while *fd* points at *diversion* (the null device for stdin, stderr for stdout), so a child process or a
    stray read or print misses the wire; *fd* is restored on the way out, blocking again.

    The SDK's transport diverts fd 0 and fd 1 so only when it is given no streams (``server/sdk.py``)."""
    import fcntl  # noqa: PLC0415 - POSIX only

    private = fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 3)
    target = diversion()
    try:
        os.dup2(target, fd)
    finally:
        os.close(target)
    try:
        yield private
    finally:
        # The event loop made the wire non-blocking; a host passing one socket as both ends shares that flag.
        with contextlib.suppress(OSError):
            os.set_blocking(private, True)
        with contextlib.suppress(OSError):
            os.dup2(private, fd)
        os.close(private)


@contextlib.asynccontextmanager
async def _pipes() -> AsyncIterator[tuple[LineSource, LineSink]]:
    """stdin's lines and a stdout writer on the event loop, from the private duplicates of fd 0 and fd 1."""
    loop = asyncio.get_running_loop()
    read_transport: asyncio.ReadTransport | None = None
    writer: asyncio.StreamWriter | None = None
    with _diverted(0, _null) as wire_in, _diverted(1, _stderr) as wire_out:
        try:
            reader = asyncio.StreamReader(limit=_CHUNK_BYTES)
            read_transport, _ = await loop.connect_read_pipe(
                lambda: asyncio.StreamReaderProtocol(reader),
                os.fdopen(wire_in, "rb", buffering=0, closefd=False),
            )
            write_transport, write_protocol = await loop.connect_write_pipe(
                asyncio.streams.FlowControlMixin, os.fdopen(wire_out, "wb", buffering=0, closefd=False)
            )
            writer = asyncio.StreamWriter(write_transport, write_protocol, None, loop)
            yield _BoundedLines.from_stream(reader), _PipeOut(writer)
        finally:
            if read_transport is not None:
                read_transport.close()
            if writer is not None:
                # What is still buffered goes out before the wire is handed back (the host may wait for it).
                with contextlib.suppress(OSError, TimeoutError):
                    await asyncio.wait_for(writer.drain(), 5)
                writer.close()


class _PipeOut:
    """stdout for the SDK's transport (a :class:`~rosbridge_mcp_server.server.sdk.LineSink`): written from the
    event loop, ``flush`` waiting only while the host reads slower than we write."""

    def __init__(self, writer: asyncio.StreamWriter) -> None:
        self._writer = writer

    async def write(self, text: str) -> None:
        self._writer.write(text.encode())

    async def flush(self) -> None:
        await self._writer.drain()


class _BoundedLines:
    """stdin for the SDK's transport (a :class:`~rosbridge_mcp_server.server.sdk.LineSource`): lines as text
    (bad UTF-8 replaced, as the SDK's transport does), none longer than :data:`MAX_LINE_BYTES`: an over-long
    line is read to its end without being kept, and handed on as a small JSON object that is no JSON-RPC
    message, which :func:`reply_for_unreadable` answers.

    ``readline(n)`` gives the next piece of a line: at most about ``n`` bytes, ending at a newline when one
    comes first; ``b""`` at the end.
    """

    def __init__(self, readline: Callable[[int], Awaitable[bytes]]) -> None:
        self._readline = readline

    @classmethod
    def from_file(cls, binary: BinaryIO) -> _BoundedLines:
        """From a blocking file: each piece read by a worker thread."""
        return cls(lambda n: anyio.to_thread.run_sync(binary.readline, n))

    @classmethod
    def from_stream(cls, reader: asyncio.StreamReader) -> _BoundedLines:
        """From an asyncio stream (whose limit bounds a piece): read on the event loop."""

        async def readline(n: int) -> bytes:
            try:
                return await reader.readuntil(b"\n")
            except asyncio.IncompleteReadError as exc:
                return exc.partial  # the end: what is left of the last line
            except asyncio.LimitOverrunError:
                return await reader.read(n)  # no newline within the reader's limit: a piece of a long line

        return cls(readline)

    def __aiter__(self) -> _BoundedLines:
        return self

    async def __anext__(self) -> str:
        line = await self._read_line()
        if line is None:
            raise StopAsyncIteration
        return line

    async def _read_line(self) -> str | None:
        # Read in pieces into one growing buffer: a line is held once (one read with a limit of 64 MiB would
        # hold its pieces and their join, twice the limit), and an over-long one is dropped at the limit.
        line = bytearray()
        while True:
            chunk = await self._readline(_CHUNK_BYTES)
            if not chunk:
                break
            line += chunk
            if chunk.endswith(b"\n"):
                break
            if len(line) > MAX_LINE_BYTES:
                return await self._skipped(line)
        if not line:
            return None
        if len(line) - line.endswith(b"\n") > MAX_LINE_BYTES:
            return await self._skipped(line)
        return line.decode("utf-8", errors="replace")

    async def _skipped(self, start: bytearray) -> str:
        """The rest of an over-long line read and dropped; what stands in for it (its size and id)."""
        head, tail, read = bytes(start[:_SCAN_CHARS]), bytes(start[-_TAIL_BYTES:]), len(start)
        start.clear()
        while not tail.endswith(b"\n"):
            chunk = await self._readline(_CHUNK_BYTES)
            if not chunk:
                break
            read += len(chunk)
            tail = (tail + chunk)[-_TAIL_BYTES:]
        size = read - tail.endswith(b"\n")
        # The tail may overlap the head (a line just over a small limit): keep each byte once.
        overlap = max(0, len(head) - (read - len(tail)))
        text = (head + tail[overlap:].rstrip(b"\r\n")).decode("utf-8", errors="replace")
        return json.dumps({"jsonrpc": "2.0", "id": _recover_id(text), _TOO_LONG: size})


def reply_for_unreadable(exc: Exception) -> JSONRPCError | None:
    """The error reply for a line the SDK's own stdio transport could not read (``None``: a blank line).

    That transport hands the parse failure on as an exception instead of the line; a pydantic error keeps
    the line (or the object it decoded) as its input, which is where the id is found.
    """
    if not isinstance(exc, ValidationError):
        return _error_reply(PARSE_ERROR, f"Parse error: {type(exc).__name__}", None)
    errors = exc.errors(include_url=False)
    first = errors[0]
    if first["type"] == "json_invalid":
        text = first.get("input")
        if isinstance(text, str) and not text.strip():
            return None
        return _parse_error(first["msg"], _recover_id(text) if isinstance(text, str) else None)
    decoded = [error["input"] for error in errors if isinstance(error.get("input"), dict)]
    request_id = next((_valid_id(d.get("id")) for d in decoded if "id" in d), None)
    too_long = next((d[_TOO_LONG] for d in decoded if isinstance(d.get(_TOO_LONG), int)), None)
    if too_long is not None:
        return _error_reply(
            INVALID_REQUEST,
            f"Invalid request: the line is {too_long:,} bytes, longer than the {_limit()} this server reads; "
            "it was skipped unread",
            request_id,
        )
    return _not_json_rpc(request_id)


def _limit() -> str:
    mib, rest = divmod(MAX_LINE_BYTES, 2**20)
    return f"{mib} MiB" if mib and not rest else f"{MAX_LINE_BYTES:,} bytes"


def _parse_error(pydantic_message: str, request_id: int | str | None) -> JSONRPCError:
    reason = pydantic_message.removeprefix("Invalid JSON: ")
    if "recursion limit" in reason:
        reason = "the JSON nests deeper than this server's parser allows (about 200 levels)"
    return _error_reply(PARSE_ERROR, f"Parse error: {reason}", request_id)


def _not_json_rpc(request_id: int | str | None) -> JSONRPCError:
    return _error_reply(
        INVALID_REQUEST, "Invalid request: not a JSON-RPC 2.0 request or notification", request_id
    )


def _error_reply(code: int, message: str, request_id: int | str | None) -> JSONRPCError:
    _log.warning("Answered an unreadable line with JSON-RPC error %d (id %r): %s", code, request_id, message)
    return JSONRPCError(jsonrpc="2.0", id=request_id, error=ErrorData(code=code, message=message))


def _valid_id(value: object) -> int | str | None:
    if isinstance(value, str) or (isinstance(value, int) and not isinstance(value, bool)):
        return value
    return None


def _recover_id(text: str) -> int | str | None:
    """The ``id`` member of the top-level object in ``text``, found without parsing the rest.

    One pass over the first :data:`_SCAN_CHARS` characters that tracks strings and bracket depth, so a request
    nested too deep (or cut short) still gets its reply under its own id; past that, an id written last (just
    before the closing brace) is still found. The work stays bounded however long the line.
    """
    found = _scan_for_id(text[:_SCAN_CHARS])
    if found is None and len(text) > _SCAN_CHARS:
        match = _TRAILING_ID.search(text, len(text) - 1000)
        if match is not None:
            found = _id_from_json(match.group(1))
    return found


def _id_from_json(token: str) -> int | str | None:
    try:
        return _valid_id(json.loads(token))
    except ValueError:
        return None


def _scan_for_id(text: str) -> int | str | None:
    depth = 0
    i = 0
    n = len(text)
    while i < n:
        ch = text[i]
        if ch == '"':
            end = _string_end(text, i)
            if end < 0:
                return None
            if depth == 1 and text[i + 1 : end] == "id":
                rest = text[end + 1 :].lstrip()
                if rest.startswith(":"):
                    match = _ID_VALUE.match(rest, 1)
                    if match is not None:
                        return _id_from_json(match.group(1))
            i = end + 1
            continue
        if ch in "{[":
            depth += 1
        elif ch in "}]":
            depth -= 1
        i += 1
    return None


def _string_end(text: str, start: int) -> int:
    """Index of the quote closing the JSON string opened at ``start``, or -1."""
    i = start + 1
    while True:
        i = text.find('"', i)
        if i < 0:
            return -1
        backslashes = 0
        j = i - 1
        while text[j] == "\\":
            backslashes += 1
            j -= 1
        if backslashes % 2 == 0:
            return i
        i += 1
