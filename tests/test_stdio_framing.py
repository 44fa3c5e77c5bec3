"""Lines the SDK's stdio transport cannot read: the error replies JSON-RPC requires, under their id."""

from __future__ import annotations

import asyncio
import io
from collections.abc import Callable

import pytest
from mcp.types import JSONRPCError, jsonrpc_message_adapter

from rosbridge_mcp_server.server import stdio
from rosbridge_mcp_server.server.stdio import reply_for_unreadable


def _failure(line: str | bytes) -> Exception:
    """What the SDK's transport hands on for *line* instead of a message (it reads lines as text)."""
    text = line.decode("utf-8", errors="replace") if isinstance(line, bytes) else line
    try:
        jsonrpc_message_adapter.validate_json(text, by_name=False)
    except Exception as exc:
        return exc
    raise AssertionError(f"{line!r} parsed")


def _reply(line: str | bytes) -> JSONRPCError:
    reply = reply_for_unreadable(_failure(line))
    assert reply is not None
    return reply


def test_the_id_of_a_request_nested_too_deep_is_the_top_level_one() -> None:
    """An "id" inside params (or inside a string) is not taken for the request's id."""
    deep = "[" * 400 + "]" * 400
    line = (
        '{"jsonrpc": "2.0", "method": "tools/call", "params": {"id": 5, "note": "\\"id\\": 6", "x": '
        + deep
        + '}, "id": 7}'
    )
    reply = _reply(line)
    assert (reply.id, reply.error.code) == (7, -32700)
    assert "nests deeper" in reply.error.message


def test_a_boolean_or_float_id_is_not_recovered() -> None:
    """JSON-RPC ids are strings or integers; anything else is answered with a null id."""
    for raw in (
        '{"id": true, "jsonrpc": "2.0", "method": 1}',
        '{"id": 1.5, "jsonrpc": "2.0", "method": 1}',
        '{"id": 1.5, "jsonrpc": "2.0", "method": "x", not json',
    ):
        assert _reply(raw).id is None


def test_a_blank_line_is_no_request() -> None:
    """Whitespace alone is skipped, not answered."""
    assert reply_for_unreadable(_failure("  \r\n")) is None


def test_an_id_written_last_after_megabytes_of_nesting_is_still_found() -> None:
    """Past the scanned head, an id just before the closing brace is found (the scan itself stays short)."""
    deep = "[" * 2_000_000 + "]" * 2_000_000
    reply = _reply(f'{{"jsonrpc": "2.0", "method": "tools/call", "params": {deep}, "id": "last"}}')
    assert (reply.id, reply.error.code) == ("last", -32700)


def test_not_utf8_is_a_parse_error() -> None:
    """Bytes that are not UTF-8 (read by the transport with replacement characters) are a parse error."""
    reply = _reply(b"\xff\xfe not utf-8")
    assert (reply.id, reply.error.code) == (None, -32700)


def test_the_sdk_transports_failures_are_answered_with_the_id_they_carry() -> None:
    """Parse errors and invalid requests keep their ids; JSON that is not JSON-RPC gets a null id."""
    deep = '{"jsonrpc": "2.0", "id": 3, "method": "x", "params": ' + "[" * 300 + "]" * 300 + "}"
    parse = _reply(deep)
    invalid = _reply('{"jsonrpc": "2.0", "id": "q", "method": 7}')
    array = _reply("[1, 2]")
    assert (parse.id, parse.error.code) == (3, -32700)
    assert (invalid.id, invalid.error.code) == ("q", -32600)
    assert (array.id, array.error.code) == (None, -32600)


def _from_stream(data: bytes) -> stdio._BoundedLines:
    """The lines a pipe gives (on the event loop, a piece bounded by the reader's limit), fed in 7 bytes."""
    reader = asyncio.StreamReader(limit=stdio._CHUNK_BYTES)
    for start in range(0, len(data), 7):
        reader.feed_data(data[start : start + 7])
    reader.feed_eof()
    return stdio._BoundedLines.from_stream(reader)


def _from_file(data: bytes) -> stdio._BoundedLines:
    """The lines a terminal or a regular file gives (read by a worker thread)."""
    return stdio._BoundedLines.from_file(io.BytesIO(data))


@pytest.mark.parametrize("source", [_from_stream, _from_file], ids=["pipe", "file"])
async def test_lines_up_to_the_limit_pass_and_a_longer_one_is_answered_naming_it(
    monkeypatch: pytest.MonkeyPatch, source: Callable[[bytes], stdio._BoundedLines]
) -> None:
    """With the limit at 40 bytes: a 40-byte line passes whole; a longer one (its id last, read after the
    limit) stands in as -32600 naming its size under its id; the next line is read as it was sent, and a
    last line without its newline too."""
    monkeypatch.setattr(stdio, "MAX_LINE_BYTES", 40)
    monkeypatch.setattr(stdio, "_CHUNK_BYTES", 16)
    exact = b'{"jsonrpc": "2.0", "method": "x", "a":1}'
    over = b'{"jsonrpc": "2.0", "method": "tools/list", "params": {"x": "' + b"y" * 100 + b'"}, "id": 9}'
    after = b'{"jsonrpc":"2.0","id":10,"method":"p"}'
    last = b'{"jsonrpc":"2.0","id":11,"method":"q"}'
    assert len(exact) == 40
    read = [line async for line in source(exact + b"\n" + over + b"\n" + after + b"\n" + last)]
    assert len(read) == 4
    assert read[3] == last.decode()
    assert read[0] == exact.decode() + "\n"
    assert read[2] == after.decode() + "\n"
    reply = _reply(read[1])
    assert (reply.id, reply.error.code) == (9, -32600)
    assert reply.error.message == (
        f"Invalid request: the line is {len(over):,} bytes, longer than the 40 bytes this server reads; it "
        "was skipped unread"
    )
