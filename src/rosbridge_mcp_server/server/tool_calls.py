"""``tools/list`` and ``tools/call``: the low-level server's two handlers, with the checks every call gets.

Whatever the transport (stdio, Streamable HTTP, in-memory) and protocol era, a ``tools/call`` goes:

1. a tool the server withholds (acting tools of a read-only server) is refused with a sentence saying why,
   and audited; any other unknown name is the SDK's "Unknown tool: ..." as before;
2. arguments that are no JSON object are one sentence saying so, naming what the tool takes (the one check
   made before the SDK validates the request's shape, as server middleware: :meth:`ToolCalls.arguments_kind`);
3. with several robots, the ``robot`` argument is taken off the call and chooses the robots it runs on
   (``fleet.py``); a missing or unknown one is refused with the robots' names, and an acting tool on a
   read-only robot of the fleet is refused (the server's ``robot_check``);
4. the tool's own strict model validates the arguments as the client sent them, once (``tools/arguments.py``:
   unknown keys, booleans for numbers, sizes, JSON text for an object): what does not fit is one sentence
   naming each wrong argument (``failures.py``);
5. the tool's handler runs with a :class:`~rosbridge_mcp_server.server.adapter.ToolCall` naming the robots,
   the caller the transport authenticated (a token's name, a JWT's subject) and the person's answers, in a
   task of its own (``cancelling.py``: a cancel lets it clean up and cannot end the session; an exception it
   did not answer is an answer in our words).

A refusal is the ``isError`` result the tool itself would give; nothing reaches the tool.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from mcp.server import ServerRequestContext
from mcp.server.auth.middleware.auth_context import get_access_token
from mcp.server.context import CallNext, HandlerResult
from mcp.types import (
    CallToolRequestParams,
    CallToolResult,
    InputRequiredResult,
    ListToolsResult,
    PaginatedRequestParams,
    TextContent,
    Tool,
)
from pydantic import ValidationError

from rosbridge_mcp_server.server.adapter import EdgeTool, ToolCall
from rosbridge_mcp_server.server.answers import writable
from rosbridge_mcp_server.server.cancelling import run_call
from rosbridge_mcp_server.server.failures import arguments_text
from rosbridge_mcp_server.server.fleet import ROBOT_ARGUMENT
from rosbridge_mcp_server.tools.arguments import parameter_listing

if TYPE_CHECKING:
    from rosbridge_mcp_server.server.fleet import Fleet, Robot

__all__ = ["RobotCheck", "ToolCalls", "UnlistedAnswer", "refusal_result"]

#: Answers a call of a tool the server does not list: (name, arguments, caller) -> a refusal, or None.
UnlistedAnswer = Callable[[str, dict[str, Any], "str | None"], "str | None"]
#: Refuses a listed tool on the robots chosen for it: (tool, robots, arguments, caller) -> a refusal, or None.
RobotCheck = Callable[[EdgeTool, "tuple[Robot, ...]", dict[str, Any], "str | None"], "str | None"]


def refusal_result(text: str) -> CallToolResult:
    """A tool's error answer: ``isError`` with the sentence as its text."""
    return CallToolResult(content=[TextContent(type="text", text=text)], is_error=True)


class ToolCalls:
    """The tools one server lists and the handling of every call of them (see the module docstring)."""

    def __init__(
        self,
        tools: Sequence[EdgeTool],
        fleet: Fleet,
        *,
        unlisted: UnlistedAnswer | None = None,
        robot_check: RobotCheck | None = None,
    ) -> None:
        self._tools = {tool.name: tool for tool in tools}
        self._fleet = fleet
        self._unlisted = unlisted
        self._robot_check = robot_check
        self._listed: list[Tool] = [self._listed_as(tool) for tool in tools]
        self._schemas = {tool.name: tool.input_schema for tool in self._listed}

    def _listed_as(self, tool: EdgeTool) -> Tool:
        if not tool.on_robot or not self._fleet.several:
            return tool.definition
        schema = self._fleet.schema_with_robot(tool)
        return tool.definition.model_copy(update={"input_schema": schema})

    def input_schema(self, name: str) -> dict[str, Any] | None:
        """The input schema *name* is listed with (``None``: not listed)."""
        return self._schemas.get(name)

    async def list_tools(
        self, ctx: ServerRequestContext[Any, Any], params: PaginatedRequestParams | None
    ) -> ListToolsResult:
        return ListToolsResult(tools=self._listed)

    async def arguments_kind(self, ctx: ServerRequestContext[Any, Any], call_next: CallNext) -> HandlerResult:
        """Server middleware: a listed tool called with arguments that are no JSON object gets a tool's error
        naming what it takes, instead of the SDK's bare "Invalid request parameters" (the SDK checks the
        request's shape before any handler runs; middleware runs before that)."""
        if ctx.method == "tools/call" and isinstance(ctx.params, Mapping):
            name = ctx.params.get("name")
            arguments = ctx.params.get("arguments")
            tool = self._tools.get(name) if isinstance(name, str) else None
            if tool is not None and arguments is not None and not isinstance(arguments, dict):
                takes = parameter_listing(tool.input_schema)
                return refusal_result(
                    f"Invalid arguments for {tool.name}: the arguments must be a JSON object of named "
                    f"arguments, not {_kind(arguments)}; nothing was sent. It takes: {takes}."
                )
        return await call_next(ctx)

    async def call_tool(
        self, ctx: ServerRequestContext[Any, Any], params: CallToolRequestParams
    ) -> CallToolResult | InputRequiredResult:
        name = params.name
        arguments: dict[str, Any] = params.arguments or {}
        tool = self._tools.get(name)
        caller = _caller()
        if tool is None:
            refusal = self._unlisted(name, arguments, caller) if self._unlisted is not None else None
            refusal = refusal or self._fleet.not_listed(name)
            return refusal_result(refusal or f"Unknown tool: {name}")
        robots: tuple[Robot, ...] = self._fleet.robots[:1]
        if tool.on_robot:
            if self._fleet.several:
                arguments = dict(arguments)
                every_robot = tool.spec is not None and tool.spec.every_robot
                robots, refusal = self._fleet.choose(
                    name, arguments.pop(ROBOT_ARGUMENT, None), every_robot=every_robot
                )
                if refusal is not None:
                    return refusal_result(refusal)
            if self._robot_check is not None:
                refusal = self._robot_check(tool, robots, arguments, caller)
                if refusal is not None:
                    return refusal_result(refusal)
        try:
            validated = tool.arguments.model_validate(arguments, strict=True)
        except ValidationError as exc:
            return refusal_result(arguments_text(name, exc, tool.input_schema))
        call = ToolCall(ctx, robots, caller, params.input_responses)
        # Its own task: a cancel lets it clean up and cannot end the session; a bug is an answer in our words.
        result = writable(await run_call(name, tool.handler(call, validated)))
        if tool.on_robot and len(robots) == 1 and isinstance(result, CallToolResult):
            # The calls an answer suggests go to the robot it came from.
            return self._fleet.calls_on(result, robots[0].name, self._tools)
        return result


def _caller() -> str | None:
    """The authenticated caller of the request being handled: a token's name or a JWT's subject (HTTP)."""
    token = get_access_token()
    if token is None:
        return None
    return token.subject or token.client_id


def _kind(value: Any) -> str:
    """What a JSON value is, in words: "a list", "a string", ..."""
    if isinstance(value, bool):
        return "true or false"
    if isinstance(value, int | float):
        return "a number"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, str):
        return "a string"
    return f"a {type(value).__name__}"
