"""MCP over stdin/stdout through asyncio pipes: the SDK's stdio transport without its worker threads.

The SDK's own transport (``mcp.server.stdio``) hands every line it reads and every write and flush to an
anyio worker thread: three thread hand-offs per tool call, measured at 0.3-0.7 ms of a call's latency on
our machines (``docs/performance.md``). When the MCP host gives us pipes or sockets, as every host does, we
read and write them from the event loop instead, with our own framing: every line gets an answer, and one the
SDK cannot read (not JSON, JSON nested deeper than its parser allows, not JSON-RPC, longer than we read) gets
the JSON-RPC error reply (-32700 / -32600) under the request's id when the text shows it, where the SDK only
logs it at debug level and the client waits forever. Anything else (a terminal, a regular file) goes through
the SDK's transport (a person typing JSON needs no speed, and a terminal's file description is shared with the
shell, which must not be left non-blocking), with the lines it cannot read answered the same way.

Like the SDK, we keep stray output off the wire: while serving, fd 1 points at stderr and fd 0 at the null
device; the wire is served from private duplicates, and both descriptors are restored on the way out.
"""

from __future__ import annotations

import asyncio
import contextlib
import fcntl
import json
import logging
import os
import re
import stat
from collections.abc import AsyncIterator, Iterator
from typing import TYPE_CHECKING, Any, cast

import anyio
from mcp.server.stdio import stdio_server
from mcp.shared.message import SessionMessage
from mcp.types import (
    INVALID_REQUEST,
    PARSE_ERROR,
    ErrorData,
    JSONRPCError,
    JSONRPCMessage,
    jsonrpc_message_adapter,
)
from pydantic import ValidationError

from rosbridge_mcp_server.server.sdk import serve_streams

if TYPE_CHECKING:
    from mcp.server.mcpserver import MCPServer

__all__ = [
    "MAX_LINE_BYTES",
    "Overlong",
    "parse_line",
    "read_lines",
    "reply_for_unreadable",
    "serve_lines",
    "serve_stdio",
]

_log = logging.getLogger(__name__)

#: One JSON-RPC message per line; a tool call carrying a large message (an image, a map) can be long. A longer
#: line is answered with an error and dropped as it is read, so memory stays bounded.
MAX_LINE_BYTES = 64 * 1024 * 1024
_CHUNK = 64 * 1024
#: How much of an overlong line is kept to find its id (clients write "id" before "params").
_HEAD_BYTES = 4096
_ID_VALUE = re.compile(r'\s*("(?:[^"\\]|\\.)*"|-?\d+)\s*[,}]')
#: How much of an unreadable line is scanned for its id from the start (clients write "id" early).
_SCAN_CHARS = 64 * 1024
_TRAILING_ID = re.compile(r'[,{]\s*"id"\s*:\s*("(?:[^"\\]|\\.)*"|-?\d+)\s*}\s*$')


async def serve_stdio(server: MCPServer[Any]) -> None:
    """Serve ``server`` on this process's stdin/stdout until stdin closes."""
    if not (_is_pipe_or_socket(0) and _is_pipe_or_socket(1)):
        async with stdio_server() as (read_stream, write_stream):
            await serve_streams(server, _Answering(read_stream, write_stream), write_stream)
        return
    with _claim_std_fds() as (wire_in, wire_out):
        loop = asyncio.get_running_loop()
        reader = asyncio.StreamReader(limit=_CHUNK)
        read_transport, _ = await loop.connect_read_pipe(
            lambda: asyncio.StreamReaderProtocol(reader), os.fdopen(wire_in, "rb", buffering=0, closefd=False)
        )
        write_transport, write_protocol = await loop.connect_write_pipe(
            asyncio.streams.FlowControlMixin, os.fdopen(wire_out, "wb", buffering=0, closefd=False)
        )
        writer = asyncio.StreamWriter(write_transport, write_protocol, None, loop)
        try:
            await serve_lines(server, read_lines(reader), writer)
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


class Overlong:
    """A line longer than the limit: only its first bytes are kept (enough to find the request's id)."""

    __slots__ = ("head",)

    def __init__(self, head: bytes) -> None:
        self.head = head


async def read_lines(
    reader: asyncio.StreamReader, limit: int = MAX_LINE_BYTES
) -> AsyncIterator[bytes | Overlong]:
    """Lines of ``reader`` without their newline; a line over ``limit`` bytes becomes an :class:`Overlong`.

    Memory stays bounded by ``limit``: the rest of an overlong line is read and dropped, and the lines
    after it are read as usual.
    """
    pending: list[bytes] = []
    size = 0
    overlong: bytes | None = None
    while chunk := await reader.read(_CHUNK):
        start = 0
        while True:
            newline = chunk.find(b"\n", start)
            piece = chunk[start:] if newline < 0 else chunk[start:newline]
            if overlong is None:
                if size + len(piece) > limit:
                    overlong = _head([*pending, piece])
                    pending.clear()
                    size = 0
                elif piece:
                    pending.append(piece)
                    size += len(piece)
            if newline < 0:
                break
            if overlong is not None:
                yield Overlong(overlong)
                overlong = None
            else:
                yield pending[0] if len(pending) == 1 else b"".join(pending)
                pending.clear()
                size = 0
            start = newline + 1
    if overlong is not None:
        yield Overlong(overlong)
    elif pending:
        yield b"".join(pending)


def _head(pieces: list[bytes]) -> bytes:
    head = bytearray()
    for piece in pieces:
        head += piece[: _HEAD_BYTES - len(head)]
        if len(head) >= _HEAD_BYTES:
            break
    return bytes(head)


def parse_line(line: bytes | Overlong) -> JSONRPCMessage | JSONRPCError | None:
    """The JSON-RPC message on one line, or the error reply JSON-RPC requires for it (``None``: a blank line).

    A line that is not JSON (or nests deeper than the parser allows) is a parse error (-32700); JSON that is
    not a JSON-RPC message, or a line too long to read, is an invalid request (-32600). The reply carries the
    request's id when the text shows it, so the client does not wait forever for an answer; otherwise null.
    """
    if isinstance(line, Overlong):
        return _error_reply(
            INVALID_REQUEST,
            f"Invalid request: the line is longer than {MAX_LINE_BYTES // (1024 * 1024)} MiB, the most this "
            "server reads as one message",
            _recover_id(line.head.decode("utf-8", errors="replace")),
        )
    try:
        return jsonrpc_message_adapter.validate_json(line, by_name=False)
    except ValidationError as exc:
        text = line.decode("utf-8", errors="replace")
        if not text.strip():
            return None
        first = exc.errors(include_url=False)[0]
        if first["type"] == "json_invalid":
            return _parse_error(first["msg"], _recover_id(text))
        return _not_json_rpc(_parsed_id(text))


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
    return _not_json_rpc(next((_valid_id(d.get("id")) for d in decoded if "id" in d), None))


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


def _parsed_id(text: str) -> int | str | None:
    try:
        value = json.loads(text)
    except (ValueError, RecursionError):
        return None
    if isinstance(value, dict):
        return _valid_id(value.get("id"))
    return None


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


async def serve_lines(
    server: MCPServer[Any], lines: AsyncIterator[bytes | Overlong], writer: asyncio.StreamWriter
) -> None:
    """Run ``server`` on JSON-RPC ``lines``, writing its messages (and our error replies) to ``writer``.

    The SDK's stdio framing, plus what it leaves out: a line it cannot read gets the error reply JSON-RPC
    requires instead of a log line at debug level and a client waiting forever.
    """
    to_server, from_lines = anyio.create_memory_object_stream[SessionMessage | Exception](0)
    to_wire, from_server = anyio.create_memory_object_stream[SessionMessage](0)
    replies = to_wire.clone()

    async def read() -> None:
        async with to_server, replies:
            async for line in lines:
                message = parse_line(line)
                if message is None:
                    continue
                if isinstance(message, JSONRPCError):
                    await replies.send(SessionMessage(message))
                else:
                    await to_server.send(SessionMessage(message))

    async def write() -> None:
        async with from_server:
            async for session_message in from_server:
                text = session_message.message.model_dump_json(by_alias=True, exclude_unset=True)
                writer.write(text.encode("utf-8") + b"\n")
                await writer.drain()

    async with anyio.create_task_group() as tasks:
        tasks.start_soon(read)
        tasks.start_soon(write)
        try:
            await serve_streams(server, from_lines, to_wire)
        finally:
            await to_wire.aclose()


class _Answering:
    """The SDK stdio transport's read stream, with every line it could not read answered, not dropped."""

    def __init__(self, inner: Any, write_stream: Any) -> None:
        self._inner = inner
        self._write_stream = write_stream

    @property
    def last_context(self) -> Any:
        # The SDK restores the sender's context variables from its own stream, when it has one.
        return getattr(self._inner, "last_context", None)

    async def receive(self) -> SessionMessage:
        while True:
            item = await self._inner.receive()
            if not isinstance(item, Exception):
                return cast("SessionMessage", item)
            reply = reply_for_unreadable(item)
            if reply is not None:
                await self._write_stream.send(SessionMessage(reply))

    def __aiter__(self) -> _Answering:
        return self

    async def __anext__(self) -> SessionMessage:
        try:
            return await self.receive()
        except anyio.EndOfStream:
            raise StopAsyncIteration from None

    async def aclose(self) -> None:
        await self._inner.aclose()

    async def __aenter__(self) -> _Answering:
        return self

    async def __aexit__(self, *exc_info: object) -> None:
        await self.aclose()
