"""Tool modules as MCP tools: parameters from ``run``, output schema from the spec, errors as results.

Each tool module gives a ``SPEC`` and a ``run(ctx, ...)``; here each becomes an MCP tool whose parameters are
the ``run`` parameters (plus the SDK's own ``Context``), whose output schema is the spec's model, and whose
failures become ``isError`` results:

* a :class:`~rosbridge_mcp_server.errors.RosbridgeError` or a
  :class:`~rosbridge_mcp_server.tools.base.ToolFailure` → its sentence (plus what to try, for client errors);
* arguments that do not fit the parameters → one line per wrong argument, instead of pydantic's dump;
* anything else is a bug: logged with its traceback on stderr, and the model gets a generic error.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import functools
import hashlib
import inspect
import logging
import typing
from collections.abc import Awaitable, Callable
from types import ModuleType
from typing import Any

from mcp.server.elicitation import render_elicitation_schema
from mcp.server.mcpserver import Context
from mcp.server.mcpserver.tools import Tool
from mcp.types import (
    CallToolResult,
    ElicitRequest,
    ElicitRequestFormParams,
    ElicitResult,
    ImageContent,
    InputRequiredResult,
    TextContent,
    ToolAnnotations,
)
from pydantic import BaseModel, Field, ValidationError

from rosbridge_mcp_server.errors import (
    ActionError,
    ConnectionLostError,
    InvalidMessageError,
    ProtocolError,
    RequestTimeoutError,
    RosbridgeError,
    ServiceError,
)
from rosbridge_mcp_server.robot.seam import Answer, AskPerson, SendToLink
from rosbridge_mcp_server.server.advice import advised
from rosbridge_mcp_server.server.checks import CheckedTool
from rosbridge_mcp_server.server.fleet import Fleet, Robot, selected
from rosbridge_mcp_server.server.sdk import (
    argument_pre_parse,
    replace_output_schema,
    tool_from_handler,
    tool_with_handler,
)
from rosbridge_mcp_server.tools.arguments import parameter_listing
from rosbridge_mcp_server.tools.base import ToolAnswer, ToolContext, ToolFailure, ToolHints, ToolSpec
from rosbridge_mcp_server.tools.schemas import compact_input_schema, compact_output_schema

__all__ = [
    "arguments_text",
    "error_text",
    "inline_refs",
    "tool_annotations",
    "tool_from_module",
]

_log = logging.getLogger("rosbridge_mcp_server.server")

_HINTS: tuple[tuple[type[RosbridgeError], str], ...] = (
    (
        ConnectionLostError,
        "Whether it took effect on the robot is unknown: check the robot's state (e.g. with list_topics) "
        "once the connection is back, before trying again.",
    ),
    (
        RequestTimeoutError,
        "The robot may be busy or the node may not be answering: check it is running (list_services / "
        "list_actions), or try again with a longer timeout. The request may still take effect on the robot "
        "later (a busy node or a frozen bridge runs it when it gets to it): check the robot's state before "
        "repeating one that moves it.",
    ),
    (
        ServiceError,
        "Check the service name and type with list_services and the request fields, then try again.",
    ),
    (ActionError, "Check the action name and type with list_actions and the goal fields, then try again."),
    (InvalidMessageError, "Fix the fields named above and call again; nothing was sent."),
    (
        ProtocolError,
        "The bridge sent something this server does not understand; check the rosbridge version on the "
        "robot.",
    ),
)


def error_text(exc: RosbridgeError | ToolFailure) -> str:
    """The sentence a model sees for a failed tool call: the error's own text, plus what to try."""
    text = _sentence(advised(exc))
    if isinstance(exc, ConnectionLostError) and exc.goal_cancel is not None:
        return f"{text} Check the robot's state (e.g. with list_actions) before sending the goal again."
    if isinstance(exc, RosbridgeError):
        for kind, hint in _HINTS:
            if isinstance(exc, kind):
                return f"{text} {hint}"
    return text


def _sentence(text: str) -> str:
    """End the text as a sentence: the bridge's own texts (quoted in errors) end without a full stop."""
    stripped = text.rstrip()
    return stripped if not stripped or stripped[-1] in ".!?" else stripped + "."


def arguments_text(tool: str, error: ValidationError, schema: dict[str, Any]) -> str:
    problems: list[str] = []
    union_kinds: dict[str, list[str]] = {}
    union_inputs: dict[str, Any] = {}
    for item in error.errors(include_url=False):
        loc = [str(part) for part in item["loc"]]
        where = loc[0] if loc else "(arguments)"
        if item["type"] == "missing":
            problems.append(f"{where}: required but missing")
        elif len(loc) == 2 and loc[1] in _UNION_KINDS:
            # pydantic reports each arm of `dict | str` separately, named by its type; say it once.
            if where not in union_kinds:
                problems.append(where)
            union_kinds.setdefault(where, []).append(_UNION_KINDS[loc[1]])
            union_inputs[where] = item.get("input")
        else:
            problems.append(
                f"{'.'.join(loc) or where}: {item['msg'].lower()} (got {_short(item.get('input'))})"
            )
    for where, kinds in union_kinds.items():
        index = problems.index(where)
        problems[index] = f"{where}: expected {' or '.join(kinds)} (got {_short(union_inputs[where])})"
    return f"Invalid arguments for {tool}: {'; '.join(problems)}. It takes: {parameter_listing(schema)}."


_UNION_KINDS = {"dict[str,any]": "a JSON object", "str": "a string", "float": "a number", "int": "an integer"}


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def tool_from_module(module: ModuleType, fleet: Fleet) -> tuple[Tool, CheckedTool]:
    """*module* (its ``SPEC`` and ``run``) as an MCP tool; every call gets a fresh :class:`ToolContext`.

    A call runs on the robot the server's checks chose for it (the only one, without a fleet), with that
    robot's client, guard and activity (shared by every tool of the robot, so that stop_robot sees what the
    others started); stop_robot chosen for every robot runs on each and says what it did on each.
    With the tool comes what the server's checks (``checks.py``) need to check its arguments first.
    """
    spec: ToolSpec = module.SPEC
    run: Callable[..., Awaitable[ToolAnswer]] = module.run
    template, checked = _template(module)

    async def call_tool(
        mcp_context: Context[Any, Any], **arguments: Any
    ) -> CallToolResult | InputRequiredResult:
        robots = selected(fleet)
        if len(robots) == 1:
            return await call_on(robots[0], mcp_context, arguments)
        answers = await asyncio.gather(*(call_on(robot, mcp_context, arguments) for robot in robots))
        return _merged([robot.name for robot in robots], answers)

    async def call_on(
        robot: Robot, mcp_context: Context[Any, Any], arguments: dict[str, Any]
    ) -> CallToolResult | InputRequiredResult:
        async def report_progress(progress: float, total: float | None, message: str | None) -> None:
            try:
                await mcp_context.report_progress(progress, total, message)
            except Exception:
                # Progress is a courtesy; a client that went away must not fail the goal.
                _log.debug("could not send a progress notification", exc_info=True)

        ctx = ToolContext(
            robot=robot.session,
            config=robot.config,
            report_progress=report_progress,
            ask_person=_asker(mcp_context),
        )
        try:
            answer = await run(ctx, **arguments)
        except _AskInNextRound as asking:
            return _question_round(asking)
        except (RosbridgeError, ToolFailure) as exc:
            _log.info("%s failed: %s", spec.name, exc)
            # A failure may show why (navigate_to draws a refused goal on the map).
            pictures = [
                ImageContent(
                    type="image", data=base64.b64encode(image.data).decode("ascii"), mime_type=image.mime_type
                )
                for image in getattr(exc, "images", ())
            ]
            return CallToolResult(
                content=[TextContent(type="text", text=error_text(exc)), *pictures], is_error=True
            )
        images = [
            ImageContent(
                type="image", data=base64.b64encode(image.data).decode("ascii"), mime_type=image.mime_type
            )
            for image in answer.images
        ]
        return CallToolResult(
            content=[TextContent(type="text", text=answer.text), *images],
            structured_content=answer.data.model_dump(mode="json"),
        )

    tool = tool_with_handler(template, call_tool)
    tool.parameters = fleet.schema_with_robot(checked.schema, spec.name, acting=not spec.hints.read_only)
    return tool, checked


@functools.cache
def _template(module: ModuleType) -> tuple[Tool, CheckedTool]:
    """*module*'s tool as every server lists it, with no handler yet, and its argument checks.

    Made once per process: deriving a tool's schemas from its parameters builds pydantic models (~4 ms a
    tool), and every server (one per MCP session over HTTP, one per test) lists the same tools.
    """
    spec: ToolSpec = module.SPEC
    run: Callable[..., Awaitable[ToolAnswer]] = module.run
    # The tool's parameters are run()'s, minus its ToolContext. Annotations are resolved here: the modules
    # use postponed annotations.
    hints = typing.get_type_hints(run, include_extras=True)
    run_parameters = list(inspect.signature(run).parameters.values())[1:]
    parameters = [p.replace(annotation=hints[p.name]) for p in run_parameters]

    async def unbound(mcp_context: Context[Any, Any], **arguments: Any) -> CallToolResult:
        raise RuntimeError(f"{spec.name}: a tool template is never called")

    tool = tool_from_handler(
        unbound,
        parameters,
        spec.output,
        name=spec.name,
        title=spec.title,
        description=spec.description,
        annotations=tool_annotations(spec.hints),
    )
    # What the argument checks hold every call to, said where clients read it.
    own = {**compact_input_schema(tool.parameters), "additionalProperties": False}
    tool.parameters = own
    replace_output_schema(tool, lambda schema: compact_output_schema(inline_refs(schema)))
    return tool, CheckedTool.of(spec.name, own, parameters, argument_pre_parse(tool))


def _merged(names: list[str], answers: list[CallToolResult | InputRequiredResult]) -> CallToolResult:
    """One answer for a call made on several robots: each robot's text under its name, and every list of
    the structured content joined with each entry prefixed by its robot (stop_robot's answer is lists)."""
    texts: list[str] = []
    data: dict[str, Any] = {}
    failed = False
    for name, answer in zip(names, answers, strict=True):
        if not isinstance(answer, CallToolResult):
            # Only stop_robot runs on several robots, and it never asks the person.
            texts.append(f"{name}: could not run here")
            failed = True
            continue
        failed = failed or bool(answer.is_error)
        text = "\n".join(block.text for block in answer.content if isinstance(block, TextContent))
        texts.append(f"{name}: {text}")
        for key, value in (answer.structured_content or {}).items():
            if isinstance(value, list):
                data.setdefault(key, []).extend(f"{name}: {item}" for item in value)
    return CallToolResult(
        content=[TextContent(type="text", text="\n".join(texts))],
        structured_content=None if failed else data,
        is_error=failed,
    )


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


def inline_refs(schema: dict[str, Any]) -> dict[str, Any]:
    """``schema`` with every ``$ref`` into ``$defs`` replaced by the definition itself, and no ``$defs``.

    MCP clients validate structured content against the output schema on every call; the Python SDK's
    ``jsonschema`` spends ~35 % more on a schema that resolves references (measured, docs/performance.md).
    Our answer models nest but never recurse, so inlining always ends.
    """
    definitions: dict[str, Any] = schema.get("$defs", {})

    def resolve(node: Any) -> Any:
        if isinstance(node, dict):
            ref = node.get("$ref")
            if isinstance(ref, str) and ref.startswith("#/$defs/"):
                siblings = {k: resolve(v) for k, v in node.items() if k != "$ref"}
                return {**resolve(definitions[ref.removeprefix("#/$defs/")]), **siblings}
            return {k: resolve(v) for k, v in node.items() if k != "$defs"}
        if isinstance(node, list):
            return [resolve(item) for item in node]
        return node

    resolved: dict[str, Any] = resolve(schema)
    return resolved


class _Confirmation(BaseModel):
    approve: bool = Field(description="Let the robot do this")


#: From this protocol version on a server cannot send a request in the middle of a call: it answers with
#: ``InputRequiredResult`` and the client calls again with the person's answers (``input_responses``).
_INPUT_ROUNDS_FROM = "2026-07-28"


class _AskInNextRound(BaseException):
    """The person must be asked before this call can go on: answer with an ``InputRequiredResult``.

    A ``BaseException`` so that no ``except Exception`` on the way (the guard treats a failed question as a
    "no") turns "not asked yet" into a refusal; nothing has been sent when it is raised, because the guard
    asks before anything is sent.
    """

    def __init__(self, key: str, question: str) -> None:
        super().__init__(key)
        self.key = key
        self.question = question


class _Asker:
    """The person at the MCP client, asked through elicitation (``unsupported`` when the client cannot).

    Handshake sessions (up to 2025-11-25) get an ``elicitation/create`` request in the middle of the call.
    In 2026-07-28 sessions the call ends with an ``InputRequiredResult`` holding the question; the client asks
    the person and calls again, the tool runs again up to the same question, and the answer is found by a key
    made from the question's text, so a "yes" only ever approves exactly what it was shown.

    ``by_link`` is set when the client can open a URL for the person (URL-mode elicitation, handshake
    sessions): the guard then sends the person to this call's approval on the operator console, when one runs.
    """

    def __init__(self, mcp_context: Context[Any, Any]) -> None:
        self._context = mcp_context
        capabilities = mcp_context.client_capabilities
        version = mcp_context.protocol_version
        can_link = (
            capabilities is not None
            and capabilities.elicitation is not None
            and capabilities.elicitation.url is not None
            and (version is None or version < _INPUT_ROUNDS_FROM)
        )
        self.by_link: SendToLink | None = self._send_to_link if can_link else None

    async def __call__(self, question: str) -> Answer:
        mcp_context = self._context
        capabilities = mcp_context.client_capabilities
        if capabilities is None or capabilities.elicitation is None:
            return "unsupported"
        version = mcp_context.protocol_version
        if version is not None and version >= _INPUT_ROUNDS_FROM:
            key = "confirm-" + hashlib.sha256(question.encode()).hexdigest()[:24]
            response = (mcp_context.input_responses or {}).get(key)
            if not isinstance(response, ElicitResult):
                raise _AskInNextRound(key, question)
            if response.action != "accept":
                return response.action
            return "accept" if (response.content or {}).get("approve") is True else "decline"
        if capabilities.elicitation.form is None and capabilities.elicitation.url is not None:
            return "unsupported"  # a URL-only client answers by link, or not at all
        try:
            result = await mcp_context.elicit(question, schema=_Confirmation)
        except Exception:
            _log.info("asking the person failed", exc_info=True)
            return "unsupported"
        if result.action == "accept":
            return "accept" if result.data.approve else "decline"
        return result.action

    async def _send_to_link(self, question: str, url: str, elicitation_id: str) -> Answer:
        message = f"Approve or deny this on the robot's operator console:\n{question}"
        try:
            result = await self._context.elicit_url(message, url, elicitation_id)
        except asyncio.CancelledError:
            # Answered on the console (or the call ended) while the client still shows the link: tell it the
            # out-of-band part is over, so it can close its prompt.
            with contextlib.suppress(Exception):
                await self._context.session.send_elicit_complete(elicitation_id)
            raise
        except Exception:
            _log.info("sending the person to the console failed", exc_info=True)
            return "unsupported"
        return result.action


def _asker(mcp_context: Context[Any, Any]) -> AskPerson:
    return _Asker(mcp_context)


def _question_round(asking: _AskInNextRound) -> InputRequiredResult:
    request = ElicitRequest(
        params=ElicitRequestFormParams(
            message=asking.question, requested_schema=render_elicitation_schema(_Confirmation)
        )
    )
    return InputRequiredResult(input_requests={asking.key: request})
