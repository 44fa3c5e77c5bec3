"""The stdio framing: lines in, JSON-RPC messages or the error replies JSON-RPC requires out."""

from __future__ import annotations

import asyncio

from mcp.types import JSONRPCError, JSONRPCRequest, jsonrpc_message_adapter

from rosbridge_mcp_server.server.stdio import Overlong, parse_line, read_lines, reply_for_unreadable


async def _lines(data: bytes, limit: int) -> list[bytes | Overlong]:
    reader = asyncio.StreamReader()
    reader.feed_data(data)
    reader.feed_eof()
    return [line async for line in read_lines(reader, limit)]


async def test_lines_are_split_on_newlines_and_a_last_line_needs_none() -> None:
    """Two lines and an unterminated last one come out whole, without their newlines."""
    assert await _lines(b'{"a": 1}\n{"b": 2}\n{"c": 3}', 100) == [b'{"a": 1}', b'{"b": 2}', b'{"c": 3}']


async def test_a_line_over_the_limit_becomes_overlong_and_the_next_line_is_read() -> None:
    """Only the head of an overlong line is kept; the line after it is read as usual."""
    big = b'{"jsonrpc": "2.0", "id": 9, "params": "' + b"x" * 300_000 + b'"}'
    lines = await _lines(big + b"\n" + b'{"ok": true}\n', 1000)
    assert isinstance(lines[0], Overlong)
    assert lines[0].head.startswith(b'{"jsonrpc": "2.0", "id": 9')
    assert len(lines[0].head) <= 4096
    assert lines[1] == b'{"ok": true}'


def test_an_overlong_line_is_an_invalid_request_under_its_own_id() -> None:
    """The id is read from the head of the line; the reply says what the limit is."""
    reply = parse_line(Overlong(b'{"jsonrpc": "2.0", "id": "big-1", "method": "tools/call", "params": {"x'))
    assert isinstance(reply, JSONRPCError)
    assert (reply.id, reply.error.code) == ("big-1", -32600)
    assert "64 MiB" in reply.error.message


def test_a_valid_request_is_parsed() -> None:
    """A JSON-RPC request line becomes the request."""
    message = parse_line(b'{"jsonrpc": "2.0", "id": 1, "method": "tools/list"}')
    assert isinstance(message, JSONRPCRequest)
    assert message.id == 1


def test_the_id_of_a_request_nested_too_deep_is_the_top_level_one() -> None:
    """An "id" inside params (or inside a string) is not taken for the request's id."""
    deep = "[" * 400 + "]" * 400
    line = (
        '{"jsonrpc": "2.0", "method": "tools/call", "params": {"id": 5, "note": "\\"id\\": 6", "x": '
        + deep
        + '}, "id": 7}'
    )
    reply = parse_line(line.encode())
    assert isinstance(reply, JSONRPCError)
    assert (reply.id, reply.error.code) == (7, -32700)


def test_a_boolean_or_float_id_is_not_recovered() -> None:
    """JSON-RPC ids are strings or integers; anything else is answered with a null id."""
    for raw in (
        b'{"id": true, "jsonrpc": "2.0", "method": 1}',
        b'{"id": 1.5, "jsonrpc": "2.0", "method": 1}',
        b'{"id": 1.5, "jsonrpc": "2.0", "method": "x", not json',
    ):
        reply = parse_line(raw)
        assert isinstance(reply, JSONRPCError)
        assert reply.id is None


def test_a_blank_line_is_no_request() -> None:
    """Whitespace alone is skipped, not answered."""
    assert parse_line(b"  \r") is None


def test_an_id_written_last_after_megabytes_of_nesting_is_still_found() -> None:
    """Past the scanned head, an id just before the closing brace is found (the scan itself stays short)."""
    deep = "[" * 2_000_000 + "]" * 2_000_000
    reply = parse_line(
        f'{{"jsonrpc": "2.0", "method": "tools/call", "params": {deep}, "id": "last"}}'.encode()
    )
    assert isinstance(reply, JSONRPCError)
    assert (reply.id, reply.error.code) == ("last", -32700)


def _failure(line: str) -> Exception:
    try:
        jsonrpc_message_adapter.validate_json(line, by_name=False)
    except Exception as exc:
        return exc
    raise AssertionError(f"{line!r} parsed")


def test_the_sdk_transports_failures_are_answered_with_the_id_they_carry() -> None:
    """From the exception alone: parse errors and invalid requests keep their ids; a blank line is skipped."""
    deep = '{"jsonrpc": "2.0", "id": 3, "method": "x", "params": ' + "[" * 300 + "]" * 300 + "}"
    parse = reply_for_unreadable(_failure(deep))
    invalid = reply_for_unreadable(_failure('{"jsonrpc": "2.0", "id": "q", "method": 7}'))
    assert parse is not None
    assert (parse.id, parse.error.code) == (3, -32700)
    assert invalid is not None
    assert (invalid.id, invalid.error.code) == ("q", -32600)
    assert reply_for_unreadable(_failure("\n")) is None
