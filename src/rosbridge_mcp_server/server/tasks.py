"""Long work as MCP Tasks: a drive, a goal, a recording or a timed reading the host can leave running.

When a ``tools/call`` of long work comes from a client that can follow a task, the call is answered at once
with a task, and the tool runs in the server's own task group (:class:`TaskBoard`), exactly as it would have
run in the call:

* **2026-07-28** (the extension ``io.modelcontextprotocol/tasks``): the request's capabilities name the
  extension; the answer is ``resultType: "task"``; ``tasks/get`` shows the status, a one-line progress (the
  tool's own progress text) and, at the end, the tool's answer inlined; ``tasks/update`` carries the person's
  answer to a confirmation (``input_required`` with the same question and the same matching as a 2026-07-28
  call's); ``tasks/cancel`` cancels the run.
* **2025-11-25** (tasks as an experimental feature): the request carries ``params.task``; ``tasks/get``,
  ``tasks/result`` (waits for the end) and ``tasks/cancel``; a confirmation goes out as ``elicitation/create``
  on the session's channel while the task shows ``input_required`` with the question.

Long work is what a tool's spec says it is (``ToolSpec.long_work``, a
:class:`~rosbridge_mcp_server.tools.base.LongWork`): today ``navigate_to``, ``publish_action``, ``record``
(not its ``stop``), ``plot_topic``, and ``publish_topic`` / ``subscribe_topic`` given a ``duration``. Any
other call, a client that cannot follow a task, a server started with ``--no-tasks`` and a call beyond
:data:`MAX_RUNNING` running tasks run as a plain call, as before. A task's answer is kept :data:`KEEP_SECONDS`
after its end (at most :data:`MAX_KEPT` tasks); a task belongs to its caller (the token's name over HTTP):
another caller's ``tasks/*`` find nothing. Cancelling a task is cancelling its tool call, whose own path
cancels the goal, sends the stream's zero and closes the recording (the spec's ``LongWork.cancelled`` says
which); so is the server's shutdown. A stop (``stop_robot``, E-STOP) ends the goal or stream of a task whose
tool acts on the robot (its spec's ``acts_on``) as it ends a plain call's, and the task's status says who
stopped it.
"""

from __future__ import annotations

import logging
import time
import uuid
from collections.abc import AsyncIterator, Mapping, Sequence
from contextlib import asynccontextmanager
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import anyio
import anyio.abc
from mcp.server import Server, ServerRequestContext
from mcp.server.auth.middleware.auth_context import get_access_token
from mcp.server.context import CallNext, HandlerResult
from mcp.types import INTERNAL_ERROR, INVALID_PARAMS, MISSING_REQUIRED_CLIENT_CAPABILITY, RequestParams

from mcp import MCPError
from rosbridge_mcp_server.server.sdk import task_session
from rosbridge_mcp_server.server.task_state import TERMINAL, TaskState, ended_text, voided

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.gate import SendGate, Ticket
    from rosbridge_mcp_server.server.fleet import Fleet
    from rosbridge_mcp_server.tools.base import ToolSpec

__all__ = ["KEEP_SECONDS", "MAX_KEPT", "MAX_RUNNING", "TASKS_EXTENSION", "TaskBoard"]

_log = logging.getLogger("rosbridge_mcp_server.server")

TASKS_EXTENSION = "io.modelcontextprotocol/tasks"
RELATED_TASK = "io.modelcontextprotocol/related-task"
#: How long a task's answer is kept after its end.
KEEP_SECONDS = 600.0
#: Tasks running at once; a long call beyond it runs as a plain call.
MAX_RUNNING = 8
#: Tasks kept at once (running or ended); the oldest ended one goes first.
MAX_KEPT = 64
#: How long tasks/cancel waits for the run to end (its goal cancelled, its stream's zero sent).
CANCEL_WAIT = 10.0
_MODERN_FROM = "2026-07-28"


class TaskIdParams(RequestParams):
    """``tasks/get``, ``tasks/result``, ``tasks/cancel``: the task."""

    task_id: str


class TaskUpdateParams(RequestParams):
    """``tasks/update``: the task and the person's answers, keyed as its ``inputRequests``."""

    task_id: str
    input_responses: dict[str, Any]


class TaskBoard:
    """The tasks of one server: started by :meth:`middleware`, run in the group :meth:`running` holds open
    (the server's lifespan), answered by the ``tasks/*`` methods :meth:`register` adds."""

    def __init__(
        self,
        fleet: Fleet,
        *,
        keep_seconds: float = KEEP_SECONDS,
        max_running: int = MAX_RUNNING,
        max_kept: int = MAX_KEPT,
    ) -> None:
        self._fleet = fleet
        self._keep = keep_seconds
        self._max_running = max_running
        self._max_kept = max_kept
        self._tasks: dict[str, TaskState] = {}
        self._group: anyio.abc.TaskGroup | None = None
        #: The served tools whose spec says a call may be long work, by name.
        self._long: dict[str, ToolSpec] = {}

    def register(self, server: Server[Any], specs: Sequence[ToolSpec]) -> None:
        """Serve tasks on *server*: its methods, its capability, and the middleware that starts them; the
        tools of *specs* (the served ones) whose spec says ``long_work`` may run as tasks."""
        self._long = {spec.name: spec for spec in specs if spec.long_work is not None}
        server.add_request_handler("tasks/get", TaskIdParams, self._get)
        server.add_request_handler("tasks/result", TaskIdParams, self._result)
        server.add_request_handler("tasks/cancel", TaskIdParams, self._cancel)
        server.add_request_handler("tasks/update", TaskUpdateParams, self._update)
        server.extensions[TASKS_EXTENSION] = {}
        server.middleware.append(self.middleware)

    @asynccontextmanager
    async def running(self) -> AsyncIterator[None]:
        """Hold the group the tasks run in; on leaving (the server's shutdown) every running one is cancelled
        (its goal cancelled, its stream's zero sent) before the robots' connections close."""
        async with anyio.create_task_group() as group:
            self._group = group
            try:
                yield
            finally:
                self._group = None
                for task in self._tasks.values():
                    if task.status not in TERMINAL:
                        task.cancelled_by = "the server shut down"
                group.cancel_scope.cancel()

    def running_tasks(self) -> list[dict[str, Any]]:
        """The tasks running now, a row each (the operator console's list): tool, status, line, caller."""
        now = time.time()
        return [
            {
                "id": task.task_id,
                "tool": task.tool,
                "status": task.status,
                "message": task.message,
                "caller": task.caller,
                "seconds": round(now - task.created, 1),
            }
            for task in self._running()
        ]

    # --- starting ------------------------------------------------------------------------------------

    async def middleware(self, ctx: ServerRequestContext[Any, Any], call_next: CallNext) -> HandlerResult:
        """Server middleware: a long ``tools/call`` from a client that follows tasks becomes a task; the
        2025-11-25 handshake and tool list say which tools may."""
        params = ctx.params if isinstance(ctx.params, Mapping) else {}
        if ctx.method == "tools/call":
            name, arguments = params.get("name"), params.get("arguments")
            modern = _modern(ctx)
            wants = _declares_tasks(ctx) if modern else isinstance(params.get("task"), Mapping)
            if (
                wants
                and isinstance(name, str)
                and isinstance(arguments, Mapping)
                and self._long_work(name, arguments)
                and self._group is not None
                and len(self._running()) < self._max_running
            ):
                return self._start(ctx, call_next, name, arguments, modern=modern)
        result = await call_next(ctx)
        if (
            ctx.method == "initialize"
            and isinstance(result, dict)
            and result.get("protocolVersion") == "2025-11-25"
        ):
            capabilities = result.setdefault("capabilities", {})
            capabilities["tasks"] = {"cancel": {}, "requests": {"tools": {"call": {}}}}
        elif ctx.method == "tools/list" and isinstance(result, dict) and _legacy_tasks_client(ctx):
            for tool in result.get("tools", []):
                if tool.get("name") in self._long:
                    tool["execution"] = {"taskSupport": "optional"}
        return result

    def _long_work(self, name: str, arguments: Mapping[str, Any]) -> bool:
        """Whether a call of *name* with *arguments* (as sent) is long work, run as a task when it can be."""
        spec = self._long.get(name)
        return spec is not None and spec.long_work is not None and spec.long_work.applies(arguments)

    def _start(
        self,
        ctx: ServerRequestContext[Any, Any],
        call_next: CallNext,
        name: str,
        arguments: Mapping[str, Any],
        *,
        modern: bool,
    ) -> dict[str, Any]:
        assert self._group is not None
        self._prune()
        task = TaskState(uuid.uuid4().hex, name, _caller(), modern, message=f"{name} started")
        task.gates = self._gates(name, arguments)
        self._tasks[task.task_id] = task
        self._group.start_soon(self._run, task, ctx, call_next)
        _log.info("%s runs as task %s", name, task.task_id)
        shown = task.view(self._keep, modern=modern)
        return {"resultType": "task", **shown} if modern else {"task": shown}

    def _gates(self, name: str, arguments: Mapping[str, Any]) -> list[tuple[SendGate, Ticket]]:
        """The send gates of the robots a call that acts on them runs on, with their stop count now (a stop
        ends its run); a reading tool's run goes on after a stop."""
        if self._long[name].acts_on is None:
            return []
        robots = self._fleet.robots[:1]
        if self._fleet.several:
            robots, _ = self._fleet.choose(name, arguments.get("robot"))
        return [(robot.session.gate, robot.session.gate.ticket()) for robot in robots]

    async def _run(
        self,
        task: TaskState,
        ctx: ServerRequestContext[Any, Any],
        call_next: CallNext,
    ) -> None:
        params: dict[str, Any] = dict(ctx.params or {})
        params.pop("task", None)
        session = task_session(ctx.session, lambda text: self._progress(task, text), task.asking)
        call = replace(ctx, session=session)
        try:
            with anyio.CancelScope() as task.scope:
                while True:
                    result = await call_next(replace(call, params=params))
                    asked = _input_requests(result)
                    if not asked:
                        break
                    answers = await self._ask(task, asked)
                    if (who := task.stopped_by()) is not None:
                        # A stop voids every call begun before it: a yes given after it sends nothing.
                        task.result = voided(who)
                        task.end(
                            "completed", f"Stopped by {who}: {task.tool} ended before anything was sent."
                        )
                        return
                    params = {**params, "inputResponses": answers}
                task.result = dict(result) if isinstance(result, Mapping) else {}
                task.result.pop("resultType", None)
                task.end("completed", ended_text(task.tool, task.result, task.stopped_by()))
                return
        except MCPError as exc:
            task.error = exc.error.model_dump(mode="json", exclude_none=True)
            task.end("failed", f"{task.tool} failed: {exc.error.message}")
            return
        except Exception:
            _log.exception("task %s (%s) raised", task.task_id, task.tool)
            task.error = {"code": INTERNAL_ERROR, "message": f"Error executing tool {task.tool}"}
            task.end("failed", task.error["message"])
            return
        finally:
            if task.status not in TERMINAL:
                by = task.cancelled_by or "the server shut down"
                long = self._long[task.tool].long_work
                what = long.cancelled if long is not None else "its run ended"
                task.end("cancelled", f"Cancelled by {by}: {task.tool} stopped; {what}.")
        # Left the scope without an answer: tasks/cancel cancelled it (the finally above said so).

    def _progress(self, task: TaskState, text: str) -> None:
        if task.status == "working":
            task.change("working", f"{task.tool}: {text}")

    async def _ask(self, task: TaskState, asked: dict[str, Any]) -> dict[str, Any]:
        """Wait for the person's answers to *asked* through ``tasks/update``; the answers so far."""
        task.input_requests = asked
        task.answered = anyio.Event()
        questions = [
            str(r.get("params", {}).get("message", "")) for r in asked.values() if isinstance(r, dict)
        ]
        task.change(
            "input_required", " ".join(q for q in questions if q) or "Waiting for the person's answer"
        )
        await task.answered.wait()
        task.input_requests = {}
        task.change("working", f"{task.tool}: answered, going on")
        return dict(task.answers)

    # --- the tasks/* methods -------------------------------------------------------------------------

    def _find(self, ctx: ServerRequestContext[Any, Any], task_id: str) -> TaskState:
        if _modern(ctx) and not _declares_tasks(ctx):
            raise MCPError(
                code=MISSING_REQUIRED_CLIENT_CAPABILITY,
                message="Missing required client capability",
                data={"requiredCapabilities": {"extensions": {TASKS_EXTENSION: {}}}},
            )
        self._prune()
        task = self._tasks.get(task_id)
        # Another caller's task is as unknown as one that never was.
        if task is None or task.caller != _caller():
            raise MCPError(
                code=INVALID_PARAMS,
                message=(
                    f"Task not found: {task_id!r} is no task of yours (an answer is kept "
                    f"{self._keep / 60:g} minutes after its task ends)."
                ),
            )
        return task

    async def _get(self, ctx: ServerRequestContext[Any, Any], params: TaskIdParams) -> dict[str, Any]:
        task = self._find(ctx, params.task_id)
        if task.status == "input_required" and task.stopped_by() is not None:
            # Stopped while the person was asked: the question is void; the run ends (and says so).
            task.answered.set()
            with anyio.move_on_after(CANCEL_WAIT):
                await task.done.wait()
        return task.view(self._keep, modern=_modern(ctx))

    async def _result(self, ctx: ServerRequestContext[Any, Any], params: TaskIdParams) -> dict[str, Any]:
        task = self._find(ctx, params.task_id)
        await task.done.wait()
        if task.status == "completed" and task.result is not None:
            meta = {**task.result.get("_meta", {}), RELATED_TASK: {"taskId": task.task_id}}
            return {**task.result, "_meta": meta}
        if task.error is not None:
            raise MCPError(
                code=int(task.error.get("code", INTERNAL_ERROR)), message=str(task.error["message"])
            )
        raise MCPError(code=INVALID_PARAMS, message=task.message or f"Task {task.task_id} was cancelled.")

    async def _cancel(self, ctx: ServerRequestContext[Any, Any], params: TaskIdParams) -> dict[str, Any]:
        task = self._find(ctx, params.task_id)
        modern = _modern(ctx)
        if task.status in TERMINAL:
            if modern:
                return {}
            raise MCPError(
                code=INVALID_PARAMS, message=f"Task {task.task_id} has already ended ({task.status})."
            )
        task.cancelled_by = "the client (tasks/cancel)"
        if task.scope is not None:
            task.scope.cancel()
        with anyio.move_on_after(CANCEL_WAIT):
            await task.done.wait()
        return {} if modern else task.view(self._keep, modern=False)

    async def _update(self, ctx: ServerRequestContext[Any, Any], params: TaskUpdateParams) -> dict[str, Any]:
        task = self._find(ctx, params.task_id)
        # Answers only to what is asked now; any other key is ignored.
        for key, answer in params.input_responses.items():
            if key in task.input_requests:
                task.answers[key] = answer
        if task.input_requests and all(key in task.answers for key in task.input_requests):
            task.answered.set()
        return {}

    # --- bounds --------------------------------------------------------------------------------------

    def _running(self) -> list[TaskState]:
        return [task for task in self._tasks.values() if task.status not in TERMINAL]

    def _prune(self) -> None:
        now = time.monotonic()
        for task_id, task in list(self._tasks.items()):
            if task.ended_at is not None and now - task.ended_at > self._keep:
                del self._tasks[task_id]
        ended = sorted(
            (t for t in self._tasks.values() if t.ended_at is not None), key=lambda t: t.ended_at or 0
        )
        while len(self._tasks) >= self._max_kept and ended:
            del self._tasks[ended.pop(0).task_id]


def _modern(ctx: ServerRequestContext[Any, Any]) -> bool:
    version = ctx.protocol_version
    return version is not None and version >= _MODERN_FROM


def _declares_tasks(ctx: ServerRequestContext[Any, Any]) -> bool:
    capabilities = ctx.session.client_capabilities
    return capabilities is not None and TASKS_EXTENSION in (capabilities.extensions or {})


def _legacy_tasks_client(ctx: ServerRequestContext[Any, Any]) -> bool:
    capabilities = ctx.session.client_capabilities
    return not _modern(ctx) and capabilities is not None and capabilities.tasks is not None


def _caller() -> str | None:
    """The authenticated caller (HTTP: a token's name or a JWT's subject; stdio: ``None``)."""
    token = get_access_token()
    return None if token is None else token.subject or token.client_id


def _input_requests(result: HandlerResult) -> dict[str, Any] | None:
    if isinstance(result, Mapping) and result.get("resultType") == "input_required":
        asked = result.get("inputRequests")
        return dict(asked) if isinstance(asked, Mapping) else None
    return None
