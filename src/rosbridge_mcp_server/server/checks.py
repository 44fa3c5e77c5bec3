"""The checks every tool call gets before the SDK reads its arguments, as the SDK's server middleware.

Middleware runs on every inbound message whatever the transport (stdio, Streamable HTTP, in-memory), before
the SDK validates the parameters, so stdio and HTTP share each check here:

* a tool the server withholds (acting tools of a read-only server) is refused with a sentence saying why,
  and audited, instead of the SDK's "Unknown tool";
* the arguments as the client sent them go through ``tools/arguments.py`` (unknown keys, booleans for numbers,
  sizes) before the SDK's lenient conversion would drop or convert them;
* arguments that do not fit the tool's parameters are one sentence naming each, instead of pydantic's dump
  (validated against our own model of the parameters, the same annotations the SDK's model is built from,
  after the SDK's own reading of JSON inside strings, so that ``"request": "null"`` is named too);
* the caller the transport authenticated (a token's name, a JWT's subject) is named for the audit;
* with several robots, the ``robot`` argument is taken off the call and chooses the robot it runs on
  (``fleet.py``); a missing or unknown one is refused with the robots' names;
* a call on the robots it runs on may be refused whatever its arguments (an acting tool on a read-only robot
  of a fleet), by the server's ``robot_check``.

A refusal is the ``isError`` result the tool itself would give; nothing reaches the tool.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from mcp.server.auth.middleware.auth_context import get_access_token
from mcp.server.context import CallNext, HandlerResult, ServerRequestContext
from mcp.types import CallToolResult, TextContent
from pydantic import BaseModel, ConfigDict, ValidationError, create_model

from rosbridge_mcp_server.safety import calling_as
from rosbridge_mcp_server.server.fleet import LIST_ROBOTS, ROBOT_ARGUMENT, selecting
from rosbridge_mcp_server.tools.arguments import parameter_listing

if TYPE_CHECKING:
    from rosbridge_mcp_server.server.fleet import Fleet, Robot

__all__ = ["ArgumentCheck", "ArgumentErrorText", "CheckedTool", "ToolCallChecks", "refusal_result"]

#: Rewords an argument error: (tool name, the pydantic error, the tool's input schema) -> one sentence.
ArgumentErrorText = Callable[[str, ValidationError, dict[str, Any]], str]
#: Checks arguments before any conversion: (tool name, arguments, input schema) -> a refusal or None.
ArgumentCheck = Callable[[str, dict[str, Any], dict[str, Any]], str | None]
#: Answers a call of a tool the server does not list: (name, arguments) -> a refusal, or None.
UnlistedAnswer = Callable[[str, dict[str, Any]], str | None]
#: Refuses a listed tool on the robots chosen for it ((), one robot): (name, robots, arguments) -> a refusal.
RobotCheck = Callable[[str, "tuple[Robot, ...]", dict[str, Any]], str | None]


@dataclass(frozen=True)
class CheckedTool:
    """What the checks need of one listed tool: its input schema and a model of its parameters."""

    name: str
    schema: dict[str, Any]
    arguments: type[BaseModel]
    #: What the SDK does to the arguments before it validates them (``sdk.argument_pre_parse``).
    pre_parse: Callable[[dict[str, Any]], dict[str, Any]] | None = None

    @classmethod
    def of(
        cls,
        name: str,
        schema: dict[str, Any],
        parameters: list[inspect.Parameter],
        pre_parse: Callable[[dict[str, Any]], dict[str, Any]] | None = None,
    ) -> CheckedTool:
        """The tool named *name* whose parameters (annotations resolved) are *parameters*."""
        fields: dict[str, Any] = {
            p.name: (p.annotation, ... if p.default is inspect.Parameter.empty else p.default)
            for p in parameters
        }
        model = create_model(
            f"{name}_arguments", __config__=ConfigDict(arbitrary_types_allowed=True), **fields
        )
        return cls(name, schema, model, pre_parse)


def refusal_result(text: str) -> CallToolResult:
    """A tool's error answer: ``isError`` with the sentence as its text."""
    return CallToolResult(content=[TextContent(type="text", text=text)], is_error=True)


class ToolCallChecks:
    """``ServerMiddleware`` running the checks above on every ``tools/call``; other messages pass by."""

    def __init__(
        self,
        tools: Iterable[CheckedTool],
        *,
        argument_check: ArgumentCheck,
        argument_error: ArgumentErrorText,
        unlisted: UnlistedAnswer | None = None,
        fleet: Fleet | None = None,
        fleet_wide: Iterable[str] = (),
        robot_check: RobotCheck | None = None,
    ) -> None:
        self._robot_check = robot_check
        self._fleet = fleet
        # Tools about every robot at once (list_robots, show_console): no ``robot`` argument is taken off.
        self._fleet_wide = {LIST_ROBOTS, *fleet_wide}
        self._tools = {tool.name: tool for tool in tools}
        self._argument_check = argument_check
        self._argument_error = argument_error
        self._unlisted = unlisted

    async def __call__(self, ctx: ServerRequestContext[Any, Any], call_next: CallNext) -> HandlerResult:
        if ctx.method != "tools/call" or not isinstance(ctx.params, Mapping):
            return await call_next(ctx)
        name = ctx.params.get("name")
        arguments = ctx.params.get("arguments")
        if arguments is None:
            arguments = {}
        if isinstance(name, str) and name in self._tools and not isinstance(arguments, dict):
            # A tool we list, called with arguments that are no object: a tool's error naming it, as for any
            # wrong argument, rather than the SDK's bare "Invalid request parameters".
            takes = parameter_listing(self._tools[name].schema)
            return refusal_result(
                f"Invalid arguments for {name}: the arguments must be a JSON object of named arguments, not "
                f"{_kind(arguments)}; nothing was sent. It takes: {takes}."
            )
        if not isinstance(name, str) or not isinstance(arguments, dict):
            # Malformed params: the SDK's own validation answers them.
            return await call_next(ctx)
        robots: tuple[Robot, ...] = ()
        choosing = name in self._tools and name not in self._fleet_wide
        if self._fleet is not None and self._fleet.several and choosing:
            arguments = dict(arguments)
            robots, refusal = self._fleet.choose(name, arguments.pop(ROBOT_ARGUMENT, None))
            if refusal is not None:
                return refusal_result(refusal)
            ctx = replace(ctx, params={**ctx.params, "arguments": arguments})
        if self._robot_check is not None and choosing:
            with calling_as(caller()):
                refusal = self._robot_check(name, robots, arguments)
            if refusal is not None:
                return refusal_result(refusal)
        refusal = self.refusal(name, arguments)
        if refusal is not None:
            return refusal_result(refusal)
        with calling_as(caller()), selecting(robots):
            return await call_next(ctx)

    def refusal(self, name: str, arguments: dict[str, Any]) -> str | None:
        """Why a call of *name* with *arguments* must not reach the tool, or ``None``."""
        tool = self._tools.get(name)
        if tool is None:
            if self._unlisted is None:
                return None
            with calling_as(caller()):
                return self._unlisted(name, arguments)
        problem = self._argument_check(name, arguments, tool.schema)
        if problem is not None:
            return problem
        # What the SDK validates: strings holding JSON objects, lists, null or booleans read as JSON.
        validated = tool.pre_parse(arguments) if tool.pre_parse is not None else arguments
        try:
            tool.arguments.model_validate(validated)
        except ValidationError as exc:
            text = self._argument_error(name, exc, tool.schema)
            wrong = {str(error["loc"][0]) for error in exc.errors() if error["loc"]}
            read = [key for key in arguments if key in wrong and validated[key] is not arguments[key]]
            for key in read:
                text += f" {key} was given as the text {_short(arguments[key])}, which is read as JSON."
            return text
        return None


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


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def caller() -> str | None:
    """The authenticated caller of the request being handled: a token's name or a JWT's subject (HTTP)."""
    token = get_access_token()
    if token is None:
        return None
    return token.subject or token.client_id
