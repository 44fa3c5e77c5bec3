"""Every use of the MCP SDK beyond its documented API, each behind one named function.

The server is the SDK's low-level ``mcp.server.Server`` (``on_list_tools``, ``on_call_tool``,
``add_request_handler``, ``run``, ``streamable_http_app``), which is documented and owns our schemas and
results exactly; the tools' handlers use the request context's session (progress, elicitation) and
``mcp.server.elicitation``. What has no documented way stays here; ``tests/mcp/test_sdk_seam.py``
holds it to its effect, so an SDK upgrade that changes it fails there, by name, instead of somewhere in a
call:

* :func:`answering_stream`: the SDK stdio transport's read stream, with every line it could not read
  answered. The transport hands such a line on as an exception, which the server only logs; the reply goes
  out on the write stream as a ``mcp.shared.message.SessionMessage`` (the transport's message type, not
  exported), and the server's runner restores the sender's context variables from the read stream's
  ``last_context`` when it has one (``mcp.shared._stream_protocols``), which the wrapper passes through.
* :func:`task_session`: a tool call run as a task (``server/tasks.py``) is the same call handed on through the
  documented server middleware (``call_next(replace(ctx, ...))``) with a request context whose ``session``
  is this stand-in: the request's own session in everything but ``report_progress``, which becomes the task's
  status line, and ``elicit_form`` / ``elicit_url``, during which the task waits for the person, sent on the
  session's own channel (``related_request_id=None``: the call's request was answered with the task). It
  relies on the tool handlers reaching progress and the person only through ``ctx.session`` (ours do:
  ``adapter.py``) and on the runner handing ``ctx.session`` on untouched.
* :func:`stdio_streams`: the SDK's stdio transport (``mcp.server.stdio.stdio_server``, documented) given
  streams of ours (``stdio.py``: lines bounded, pipes on the event loop). Its parameters are typed
  ``anyio.AsyncFile[str]``, but all it uses of them is this contract, which :class:`LineSource` and
  :class:`LineSink` list: it reads stdin only by ``async for line in stdin`` (one JSON-RPC message a line;
  the end of iteration is the end of the session) and writes each message to stdout as
  ``await stdout.write(json + "\n")`` then ``await stdout.flush()``. Given a stream, it leaves fd 0 and fd 1
  alone ("explicit streams skip the claim"): the caller diverts them itself (``stdio.py``).
* :func:`cancelled_by_client`: whether the client sent ``notifications/cancelled`` for the request being
  handled. The dispatch context has it (``cancel_requested``, documented), but the low-level server's request
  context reaches it only through its session's private ``_request_outbound``
  (``tests/mcp/test_mcp_cancel_audit.py`` holds it: a cancel from the client is audited as such).
"""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any, Protocol, cast

import anyio
from mcp.server.stdio import stdio_server
from mcp.shared.message import SessionMessage
from mcp.types import JSONRPCError

__all__ = [
    "LineSink",
    "LineSource",
    "answering_stream",
    "cancelled_by_client",
    "stdio_streams",
    "task_session",
]


class LineSource(Protocol):
    """What the SDK's stdio transport reads as stdin: text lines, by ``async for`` alone."""

    def __aiter__(self) -> AsyncIterator[str]: ...


class LineSink(Protocol):
    """What the SDK's stdio transport writes to as stdout: each message ``write(json + "\n")``, then
    ``flush()``."""

    async def write(self, text: str, /) -> object: ...

    async def flush(self) -> object: ...


@contextlib.asynccontextmanager
async def stdio_streams(lines: LineSource | None, out: LineSink | None) -> AsyncIterator[tuple[Any, Any]]:
    """The SDK's stdio transport reading *lines* and writing to *out* (``None``: the process's stdin or
    stdout, which the SDK then diverts itself); its read and write streams, as ``stdio_server`` yields
    them."""
    stdin = cast("anyio.AsyncFile[str] | None", lines)
    stdout = cast("anyio.AsyncFile[str] | None", out)
    async with stdio_server(stdin=stdin, stdout=stdout) as streams:
        yield streams


#: The reply for an unreadable line (the exception the transport handed on), or None to answer nothing.
ReplyFor = Callable[[Exception], JSONRPCError | None]


def answering_stream(read_stream: Any, write_stream: Any, reply_for: ReplyFor) -> Any:
    """*read_stream* (the SDK stdio transport's) for ``Server.run``: each item that is an exception (a line
    the transport could not read) is answered on *write_stream* with ``reply_for(exc)`` and skipped."""
    return _Answering(read_stream, write_stream.send, reply_for)


class _Answering:
    def __init__(
        self, inner: Any, send: Callable[[SessionMessage], Awaitable[None]], reply_for: ReplyFor
    ) -> None:
        self._inner = inner
        self._send = send
        self._reply_for = reply_for

    @property
    def last_context(self) -> Any:
        # The SDK restores the sender's context variables from its own stream, when it has one.
        return getattr(self._inner, "last_context", None)

    async def receive(self) -> SessionMessage:
        while True:
            item = await self._inner.receive()
            if not isinstance(item, Exception):
                return cast("SessionMessage", item)
            reply = self._reply_for(item)
            if reply is not None:
                await self._send(SessionMessage(reply))

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


def task_session(
    inner: Any, on_progress: Callable[[str], None], on_asking: Callable[[str | None], None] | None = None
) -> Any:
    """*inner* (a request's ``ServerSession``) with its ``report_progress`` told to *on_progress* as one line
    (the message, else "progress of total") instead of sent to the client; *on_asking* is told the question
    when an elicitation is sent, and ``None`` when its answer came (or it failed)."""
    return _TaskSession(inner, on_progress, on_asking or (lambda question: None))


class _TaskSession:
    def __init__(
        self, inner: Any, on_progress: Callable[[str], None], on_asking: Callable[[str | None], None]
    ) -> None:
        self._inner = inner
        self._on_progress = on_progress
        self._on_asking = on_asking

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    async def report_progress(
        self, progress: float, total: float | None = None, message: str | None = None
    ) -> None:
        self._on_progress(message or (f"{progress:g} of {total:g}" if total else f"{progress:g}"))

    async def elicit_form(self, message: str, *args: Any, **kwargs: Any) -> Any:
        self._on_asking(message)
        try:
            return await self._inner.elicit_form(message, *args, **_standalone(kwargs))
        finally:
            self._on_asking(None)

    async def elicit_url(self, message: str, *args: Any, **kwargs: Any) -> Any:
        self._on_asking(message)
        try:
            return await self._inner.elicit_url(message, *args, **_standalone(kwargs))
        finally:
            self._on_asking(None)


def _standalone(kwargs: dict[str, Any]) -> dict[str, Any]:
    """A task's question goes on the session's own channel: the request it came with was answered long ago
    (with the task), so its back-channel is gone (``NoBackChannelError``)."""
    return {**kwargs, "related_request_id": None}


def cancelled_by_client(session: Any) -> bool:
    """Whether the client asked to cancel the request whose ``ServerSession`` *session* is (False when the SDK
    no longer says: the call is then said to have ended without a cancel from the client)."""
    dispatch = getattr(session, "_request_outbound", None)
    requested = getattr(dispatch, "cancel_requested", None)
    return isinstance(requested, anyio.Event) and requested.is_set()
