"""Each use of MCP SDK internals (``server/sdk.py``) still has its effect on the installed SDK, and no other
module of the product uses one.

These fail by name when an SDK upgrade changes what a function relies on, instead of somewhere in a tool call.
"""

from __future__ import annotations

import ast
import contextlib
import contextvars
import dataclasses
import json
import os
from pathlib import Path
from typing import Any

import anyio
import pytest
from mcp.client.session import ClientSession
from mcp.server import Server
from mcp.server.stdio import stdio_server
from mcp.shared.memory import create_client_server_memory_streams
from mcp.types import INVALID_REQUEST, CallToolResult, JSONRPCError, ListToolsResult, TextContent, Tool

import rosbridge_mcp_server
from mcp import Client
from rosbridge_mcp_server.server.sdk import answering_stream, stdio_streams, task_session
from rosbridge_mcp_server.server.stdio import reply_for_unreadable

SRC = Path(rosbridge_mcp_server.__file__).parent


def _server() -> Server[Any]:
    async def list_tools(ctx: Any, params: Any) -> ListToolsResult:
        return ListToolsResult(tools=[Tool(name="noop", input_schema={"type": "object"})])

    return Server("seam", on_list_tools=list_tools)


async def test_an_unreadable_line_is_answered_on_the_write_stream_and_serving_goes_on() -> None:
    """The transport hands an unreadable line on as an exception: answered under its id with the reply
    given, as a message the client reads; the next requests on the same streams are served."""
    server = _server()
    unreadable = ValueError("not JSON")
    answered: list[Exception] = []

    def reply_for(exc: Exception) -> JSONRPCError | None:
        answered.append(exc)
        return JSONRPCError(jsonrpc="2.0", id=7, error={"code": INVALID_REQUEST, "message": "unreadable"})

    async with (
        create_client_server_memory_streams() as ((client_read, client_write), (server_read, server_write)),
        anyio.create_task_group() as group,
    ):
        answering = answering_stream(server_read, server_write, reply_for)
        group.start_soon(server.run, answering, server_write, server.create_initialization_options())
        with anyio.fail_after(10):
            await client_write.send(unreadable)  # type: ignore[arg-type]
            reply = await client_read.receive()
            async with ClientSession(client_read, client_write) as session:
                await session.initialize()
                listed = await session.list_tools()
        group.cancel_scope.cancel()
    assert answered == [unreadable]
    assert not isinstance(reply, Exception)
    assert isinstance(reply.message, JSONRPCError)
    assert (reply.message.id, reply.message.error.message) == (7, "unreadable")
    assert [tool.name for tool in listed.tools] == ["noop"]


async def test_the_sdk_stdio_transport_hands_on_unreadable_lines_as_exceptions_with_the_senders_context() -> (
    None
):
    """What the wrapper relies on: the SDK's stdio read stream yields an exception for a line it cannot read
    (answered by our ``reply_for_unreadable`` under the line's id) and keeps the sender's context in
    ``last_context``, which the wrapper shows the server's runner."""

    class Lines:
        def __init__(self, lines: list[str]) -> None:
            self._lines = iter(lines)

        def __aiter__(self) -> Lines:
            return self

        async def __anext__(self) -> str:
            await anyio.lowlevel.checkpoint()
            try:
                return next(self._lines)
            except StopIteration:
                raise StopAsyncIteration from None

    written: list[str] = []

    class Out:
        async def write(self, text: str) -> None:
            written.append(text)

        async def flush(self) -> None:
            return None

    stdin: Any = Lines(['{"jsonrpc": "2.0", "id": 3, "method": "tools/list", \n', "\n"])
    stdout: Any = Out()
    async with stdio_server(stdin=stdin, stdout=stdout) as (read_stream, write_stream):
        answering = answering_stream(read_stream, write_stream, reply_for_unreadable)
        with anyio.fail_after(5):
            item = await read_stream.receive()
            assert isinstance(item, Exception)
            reply = reply_for_unreadable(item)
            assert reply is not None
            assert reply.id == 3
            assert isinstance(read_stream.last_context, contextvars.Context)
            assert answering.last_context is read_stream.last_context
            blank = await read_stream.receive()  # the second line, read before the streams close
            assert isinstance(blank, Exception)
            assert reply_for_unreadable(blank) is None
            with anyio.fail_after(5), contextlib.suppress(anyio.EndOfStream):
                await read_stream.receive()  # stdin's end, after its two lines
        await write_stream.aclose()
        await read_stream.aclose()


class _OnlyLines:
    """stdin as ``sdk.LineSource`` lists it: ``async for`` and nothing else (no read, readline or fileno)."""

    __slots__ = ("_lines",)

    def __init__(self, lines: list[str]) -> None:
        self._lines = iter(lines)

    def __aiter__(self) -> _OnlyLines:
        return self

    async def __anext__(self) -> str:
        await anyio.lowlevel.checkpoint()
        try:
            return next(self._lines)
        except StopIteration:
            raise StopAsyncIteration from None


class _OnlyWrites:
    """stdout as ``sdk.LineSink`` lists it: ``write`` and ``flush``, each call recorded in order."""

    __slots__ = ("calls", "flushed")

    def __init__(self) -> None:
        self.calls: list[str] = []
        self.flushed = anyio.Event()

    async def write(self, text: str, /) -> None:
        self.calls.append(text)

    async def flush(self) -> None:
        self.calls.append("<flush>")
        self.flushed.set()


def _descriptor(fd: int) -> tuple[int, int]:
    status = os.fstat(fd)
    return status.st_dev, status.st_ino


async def test_the_sdk_stdio_transport_keeps_to_the_listed_stream_contract() -> None:
    """What ``sdk.stdio_streams`` lists: given streams that only iterate lines and only write and flush, the
    SDK's transport reads a request from a line, writes each message as one ``write`` of its JSON and a
    newline followed by one ``flush``, and leaves fd 0 and fd 1 where they were (``stdio.py`` diverts
    them)."""
    request = '{"jsonrpc": "2.0", "id": 1, "method": "ping"}\n'
    out = _OnlyWrites()
    before = (_descriptor(0), _descriptor(1))
    async with stdio_streams(_OnlyLines([request]), out) as (read_stream, write_stream):
        assert (_descriptor(0), _descriptor(1)) == before
        with anyio.fail_after(5):
            item = await read_stream.receive()
            assert not isinstance(item, Exception)
            assert item.message.id == 1
            await write_stream.send(item)  # any message: the request itself, echoed
            await out.flushed.wait()
        await write_stream.aclose()
        await read_stream.aclose()
    assert (_descriptor(0), _descriptor(1)) == before
    assert len(out.calls) == 2
    written, flush = out.calls
    assert flush == "<flush>"
    assert written.endswith("\n")
    assert written.count("\n") == 1
    assert json.loads(written) == {"jsonrpc": "2.0", "id": 1, "method": "ping"}


def test_no_module_but_sdk_py_reaches_the_stdio_transport() -> None:
    """The one place our streams meet the SDK's stdio transport is ``sdk.stdio_streams``."""
    users: list[str] = []
    for path in sorted(SRC.rglob("*.py")):
        if path == SRC / "server" / "sdk.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            imported = [node.module] if isinstance(node, ast.ImportFrom) else []
            if isinstance(node, ast.Import):
                imported = [alias.name for alias in node.names]
            users += [str(path.relative_to(SRC)) for name in imported if name == "mcp.server.stdio"]
    assert users == []


def test_no_module_but_sdk_py_uses_an_sdk_private_name() -> None:
    """No ``mcp`` import outside ``server/sdk.py`` names a private module or attribute (``_name``), or the
    undocumented ``mcp.shared.message``, and nothing reaches an SDK object's private attribute."""
    offenders: list[str] = []
    for path in sorted(SRC.rglob("*.py")):
        if path == SRC / "server" / "sdk.py":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "mcp":
                parts = node.module.split(".")
                names = [alias.name for alias in node.names]
                if any(p.startswith("_") for p in parts) or any(n.startswith("_") for n in names):
                    offenders.append(f"{path.relative_to(SRC)}: from {node.module} import {', '.join(names)}")
                if node.module == "mcp.shared.message":
                    offenders.append(f"{path.relative_to(SRC)}: mcp.shared.message")
            if isinstance(node, ast.Attribute) and node.attr in {
                "_lowlevel_server",
                "fn_metadata",
                "_tool_manager",
            }:
                offenders.append(f"{path.relative_to(SRC)}:{node.lineno}: .{node.attr}")
    assert offenders == []


@pytest.mark.parametrize("mode", ["legacy", "auto"])
async def test_a_call_handed_on_with_the_task_session_reports_progress_to_the_task_alone(mode: str) -> None:
    """What ``server/tasks.py`` relies on: server middleware may hand a ``tools/call`` on with a request
    context whose session is :func:`task_session`'s; the handler's ``report_progress`` then reaches the task's
    line and not the client, everything else of the session still works (the client's capabilities), and
    ``call_next`` gives the call's answer in its wire form."""
    lines: list[str] = []
    wire: list[Any] = []

    async def call_tool(ctx: Any, params: Any) -> CallToolResult:
        await ctx.session.report_progress(1, 4, "one of four")
        await ctx.session.report_progress(2, 4)
        assert ctx.session.client_capabilities is not None
        return CallToolResult(content=[TextContent(type="text", text="done")])

    async def middleware(ctx: Any, call_next: Any) -> Any:
        if ctx.method != "tools/call":
            return await call_next(ctx)
        answer = await call_next(dataclasses.replace(ctx, session=task_session(ctx.session, lines.append)))
        wire.append(answer)
        return answer

    async def list_tools(ctx: Any, params: Any) -> ListToolsResult:
        return ListToolsResult(tools=[Tool(name="noop", input_schema={"type": "object"})])

    server: Server[Any] = Server("seam", on_list_tools=list_tools, on_call_tool=call_tool)
    server.middleware.append(middleware)
    progress: list[Any] = []

    async def on_progress(*args: Any) -> None:
        progress.append(args)

    async with Client(server, mode=mode) as client:
        result = await client.call_tool("noop", {}, progress_callback=on_progress)
    assert lines == ["one of four", "2 of 4"]
    assert progress == []
    assert isinstance(wire[0], dict)
    assert wire[0]["content"] == [{"type": "text", "text": "done"}]
    assert isinstance(result.content[0], TextContent)
