"""A tool call run so that neither its cancel nor its bugs can end the session: :func:`run_call`.

The SDK runs each request's handler in an anyio cancel scope, and a ``notifications/cancelled`` (or the
client going away, or the server shutting down) cancels that scope. Two things then went wrong inside tools:

* anyio's cancellation is *level-triggered*: every ``await`` in the cancelled scope is cancelled again, so a
  tool's cleanup in ``finally`` (a recording's index written, a stream's zero, a goal's cancel) was cut off at
  its first ``await``;
* a ``CancelledError`` that is not the scope's own (``raise asyncio.CancelledError``, or one that a cancelled
  ``asyncio.gather`` hands on from a child) is not absorbed by the scope: it escaped the request's task into
  the session's task group and ended the session (the stdio server exited, an HTTP session was gone).

So the handler runs in a task of its own, which a cancel reaches once (edge-triggered, as asyncio cancels):
the call's cleanup runs to its end, for at most :data:`CLEANUP_GRACE` seconds, while the request waits
shielded; then the request ends with the scope's own cancellation, whatever the tool raised. An exception a
tool did not turn into an answer becomes an ``isError`` answer in our words, its traceback logged on stderr.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable
from typing import Any, TypeVar

import anyio
from mcp.types import CallToolResult, TextContent

__all__ = ["CLEANUP_GRACE", "run_call", "unexpected_error"]

_log = logging.getLogger("rosbridge_mcp_server.server")

#: Seconds a cancelled call has to clean up (a goal's cancel, a stream's zero, a recording's index) before the
#: request ends without it; the cleanup goes on in the background.
CLEANUP_GRACE = 10.0

#: Cancelled calls still cleaning up after their request ended (kept referenced until they finish).
_LINGERING: set[asyncio.Task[Any]] = set()

Result = TypeVar("Result")


async def run_call(name: str, call: Awaitable[Result]) -> Result | CallToolResult:
    """Run *call* (tool *name*'s handler) in a task of its own; see the module docstring."""
    task = asyncio.ensure_future(call)
    try:
        return await asyncio.shield(task)
    except asyncio.CancelledError:
        if task.done():
            # The tool itself ended cancelled while the request was not: fall through to the answer below.
            if task.cancelled() and not _request_cancelled():
                return _interrupted(name)
            raise
        task.cancel()
        with anyio.CancelScope(shield=True):
            await asyncio.wait({task}, timeout=CLEANUP_GRACE)
        if not task.done():
            _log.warning("%s still cleaning up %g s after its cancel; left to finish", name, CLEANUP_GRACE)
            _LINGERING.add(task)
            task.add_done_callback(_LINGERING.discard)
        elif not task.cancelled() and task.exception() is not None:
            _log.error("%s failed while it was cancelled", name, exc_info=task.exception())
        raise
    except Exception as exc:
        _log.exception("%s raised an unexpected exception", name)
        return unexpected_error(name, exc)


def _request_cancelled() -> bool:
    """Whether this task (the request's) has been asked to cancel."""
    current = asyncio.current_task()
    return current is not None and current.cancelling() > 0


def _interrupted(name: str) -> CallToolResult:
    _log.error("%s ended cancelled although its call was not", name)
    return _error(
        f"{name} was interrupted inside this server before it could answer (logged on the server's stderr); "
        "the server goes on. Check the robot's state before calling it again."
    )


def unexpected_error(name: str, exc: BaseException) -> CallToolResult:
    """The answer for a bug: what failed, in our words (the exception's type, never its text, which may
    carry the robot's)."""
    return _error(
        f"{name} failed on an unexpected error in this server ({type(exc).__name__}; its traceback is on the "
        "server's stderr); the server goes on. If the call was to move the robot, check the robot's state "
        "before calling it again."
    )


def _error(text: str) -> CallToolResult:
    return CallToolResult(content=[TextContent(type="text", text=text)], is_error=True)
