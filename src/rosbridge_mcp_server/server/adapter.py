"""Every tool as the MCP edge serves it: one definition, one model of its arguments, one handler.

:func:`edge_tool` is the one way a tool is made: the tool modules (their ``SPEC`` and ``run``, through
:func:`module_tool`), ``list_robots`` (``fleet.py``) and ``show_console`` (``console_app.py``) alike. A tool
module's tool lists ``run``'s parameters (compact, ``tools/schemas.py``) and the spec's output model, and its
handler runs ``run`` with a fresh :class:`~rosbridge_mcp_server.tools.base.ToolContext` on each robot the call
chose, its failures becoming ``isError`` results:

* a :class:`~rosbridge_mcp_server.errors.RosbridgeError` or a
  :class:`~rosbridge_mcp_server.tools.base.ToolFailure` → its sentence plus what to try (``failures.py``);
* anything else is a bug: logged with its traceback on stderr, and the model gets a generic error
  (``cancelling.py``).

The person is asked through ``asking.py``; answers leave through ``answers.py`` (images, a fleet's answers
merged, text the SDK can write).
"""

from __future__ import annotations

import asyncio
import functools
import inspect
import logging
import typing
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass
from types import ModuleType
from typing import Any

from mcp.server import ServerRequestContext
from mcp.types import CallToolResult, InputRequiredResult, TextContent, Tool, ToolAnnotations
from pydantic import BaseModel, create_model

from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.approval import call_ending
from rosbridge_mcp_server.robot.text import repaired
from rosbridge_mcp_server.server.answers import images, merged, where_set
from rosbridge_mcp_server.server.asking import Asker, AskInNextRound, question_round
from rosbridge_mcp_server.server.failures import error_text
from rosbridge_mcp_server.server.sdk import cancelled_by_client
from rosbridge_mcp_server.tools.arguments import ARGUMENTS_CONFIG
from rosbridge_mcp_server.tools.base import ToolAnswer, ToolContext, ToolFailure, ToolHints, ToolSpec
from rosbridge_mcp_server.tools.schemas import compact_input_schema, compact_output_schema, inline_refs

if typing.TYPE_CHECKING:
    from rosbridge_mcp_server.config import Config
    from rosbridge_mcp_server.robot.session import RobotSession

__all__ = [
    "EdgeTool",
    "Handler",
    "ToolCall",
    "arguments_model",
    "edge_tool",
    "module_tool",
    "tool_annotations",
]

_log = logging.getLogger("rosbridge_mcp_server.server")


class Robot(typing.Protocol):
    """A robot a call runs on, as the edge reads it (``server.fleet.Robot`` is one)."""

    @property
    def name(self) -> str: ...
    @property
    def config(self) -> Config: ...
    @property
    def session(self) -> RobotSession: ...


@dataclass(frozen=True)
class ToolCall:
    """One ``tools/call`` as the edge read it: the robots it runs on (chosen by its ``robot`` argument, or the
    only one), who makes it (the name the transport authenticated; ``None`` on stdio), the person's answers it
    carries (2026-07-28), and the MCP request (to report progress and to ask the person)."""

    request: ServerRequestContext[Any, Any]
    robots: tuple[Robot, ...]
    caller: str | None = None
    input_responses: Mapping[str, Any] | None = None


#: What runs a tool: the call and its arguments, validated once into the tool's own model.
Handler = Callable[[ToolCall, BaseModel], Awaitable[CallToolResult | InputRequiredResult]]


@dataclass(frozen=True)
class EdgeTool:
    """A tool as the edge serves it: its ``tools/list`` entry (without the fleet's ``robot`` argument), the
    strict model its arguments are validated with (once), and its handler.

    ``on_robot``: the call runs on a robot (a fleet's calls name one); ``list_robots`` and ``show_console``
    are about every robot at once. ``spec``: what a tool module declares (``None`` for the edge's own tools,
    which read); the edge reads it, never a tool's name.
    """

    definition: Tool
    arguments: type[BaseModel]
    handler: Handler
    on_robot: bool = True
    spec: ToolSpec | None = None

    @property
    def name(self) -> str:
        return self.definition.name

    @property
    def reads(self) -> bool:
        """Whether the tool only reads (its read-only hint): what a read-only robot or server allows."""
        hints = self.definition.annotations
        return hints is not None and hints.read_only_hint is True

    @property
    def input_schema(self) -> dict[str, Any]:
        return self.definition.input_schema


def arguments_model(name: str, parameters: list[inspect.Parameter]) -> type[BaseModel]:
    """The strict model of a tool's arguments: *parameters* (annotations resolved) as fields, nothing else
    (``tools/arguments.py``: every check an argument gets is this model's one validation)."""
    fields: dict[str, Any] = {
        p.name: (p.annotation, ... if p.default is inspect.Parameter.empty else p.default) for p in parameters
    }
    model: type[BaseModel] = create_model(f"{name}Arguments", __config__=ARGUMENTS_CONFIG, **fields)
    return model


def edge_tool(
    *,
    name: str,
    title: str | None,
    description: str,
    annotations: ToolAnnotations,
    arguments: type[BaseModel],
    output: type[BaseModel] | None,
    handler: Handler,
    on_robot: bool = True,
    spec: ToolSpec | None = None,
    meta: dict[str, Any] | None = None,
) -> EdgeTool:
    """The one way a tool is made: its definition as listed (compact input and output schemas, said where
    clients read them: no argument beyond the model's), its arguments' model and its handler."""
    input_schema = {**compact_input_schema(arguments.model_json_schema()), "additionalProperties": False}
    output_schema = None if output is None else compact_output_schema(inline_refs(output.model_json_schema()))
    definition = Tool(
        name=name,
        title=title,
        description=description,
        input_schema=input_schema,
        output_schema=output_schema,
        annotations=annotations,
        _meta=meta,
    )
    return EdgeTool(definition, arguments, handler, on_robot, spec)


@functools.cache
def module_tool(module: ModuleType) -> EdgeTool:
    """*module* (its ``SPEC`` and ``run``) as a tool: every call gets a fresh :class:`ToolContext` on each
    robot it runs on.

    A call runs on the robots the edge chose for it, with each robot's client, guard and activity (shared by
    every tool of the robot, so that the stop sees what the others started); a tool whose spec says
    ``every_robot``, chosen for every robot, runs on each and says what it did on each. Made once per process:
    every server (one per MCP session over HTTP, one per test) serves the same tools.
    """
    spec: ToolSpec = module.SPEC
    run: Callable[..., Awaitable[ToolAnswer]] = module.run
    # The tool's parameters are run()'s, minus its ToolContext. Annotations are resolved here: the modules
    # use postponed annotations.
    hints = typing.get_type_hints(run, include_extras=True)
    run_parameters = list(inspect.signature(run).parameters.values())[1:]
    model = arguments_model(spec.name, [p.replace(annotation=hints[p.name]) for p in run_parameters])
    names = tuple(model.model_fields)

    async def handle(call: ToolCall, arguments: BaseModel) -> CallToolResult | InputRequiredResult:
        values = {name: getattr(arguments, name) for name in names}
        if len(call.robots) == 1:
            return await _run_on(spec, run, call, call.robots[0], values)
        answers = await asyncio.gather(*(_run_on(spec, run, call, robot, values) for robot in call.robots))
        return merged([robot.name for robot in call.robots], answers)

    return edge_tool(
        name=spec.name,
        title=spec.title,
        description=spec.description,
        annotations=tool_annotations(spec.hints),
        arguments=model,
        output=spec.output,
        handler=handle,
        spec=spec,
    )


async def _run_on(
    spec: ToolSpec,
    run: Callable[..., Awaitable[ToolAnswer]],
    call: ToolCall,
    robot: Robot,
    arguments: dict[str, Any],
) -> CallToolResult | InputRequiredResult:
    session = call.request.session

    async def report_progress(progress: float, total: float | None, message: str | None) -> None:
        try:
            await session.report_progress(progress, total, None if message is None else repaired(message))
        except Exception:
            # Progress is a courtesy; a client that went away must not fail the goal.
            _log.debug("could not send a progress notification", exc_info=True)

    ctx = ToolContext(
        robot=robot.session,
        config=robot.config,
        report_progress=report_progress,
        ask_person=Asker(call.request, call.input_responses),
        caller=call.caller,
    )
    ending = call_ending.set(functools.partial(_cancelled_why, session))
    try:
        answer = await run(ctx, **arguments)
    except AskInNextRound as asking:
        return question_round(asking)
    except (RosbridgeError, ToolFailure) as exc:
        _log.info("%s failed: %s", spec.name, exc)
        # A failure may show why (navigate_to draws a refused goal on the map).
        pictures = images(getattr(exc, "images", ()))
        return CallToolResult(
            content=[TextContent(type="text", text=where_set(error_text(exc), robot)), *pictures],
            is_error=True,
        )
    finally:
        call_ending.reset(ending)
    return CallToolResult(
        content=[TextContent(type="text", text=where_set(answer.text, robot)), *images(answer.images)],
        structured_content=answer.data.model_dump(mode="json"),
    )


def _cancelled_why(session: Any) -> str:
    if cancelled_by_client(session):
        return "cancelled by the client"
    # No cancel from the client: it went away (stdin closed, its HTTP session ended) or the server stops.
    return "cancelled: the client went away or the server is stopping"


def tool_annotations(hints: ToolHints) -> ToolAnnotations:
    """The hints that differ from MCP's defaults, which a client assumes for a hint not given (read-only
    false, destructive true, idempotent false, open world true); destructive and idempotent mean something
    only for a tool that acts. Each hint left out saves some 20 bytes of tools/list in every conversation."""
    if hints.read_only:
        return ToolAnnotations(read_only_hint=True, open_world_hint=None if hints.open_world else False)
    return ToolAnnotations(
        destructive_hint=None if hints.destructive else False,
        idempotent_hint=True if hints.idempotent else None,
        open_world_hint=None if hints.open_world else False,
    )
