"""Every tool as the MCP edge serves it: one definition, one model of its arguments, one handler.

:func:`edge_tool` is the one way a tool is made: the tool modules (their ``SPEC`` and ``run``, through
:func:`module_tool`), ``list_robots`` (``fleet.py``) and ``show_console`` (``console_app.py``) alike. A tool
module's tool lists ``run``'s parameters (compact, ``tools/schemas.py``) and the spec's output model, and its
handler runs ``run`` with a fresh :class:`~rosbridge_mcp_server.tools.base.ToolContext` on each robot the call
chose, its failures becoming ``isError`` results:

* a :class:`~rosbridge_mcp_server.errors.RosbridgeError` or a
  :class:`~rosbridge_mcp_server.tools.base.ToolFailure` → its sentence (plus what to try, for client errors);
* arguments that do not fit the parameters → one line per wrong argument (:func:`arguments_text`, used by
  ``checks.py``), instead of pydantic's dump;
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
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass
from types import ModuleType
from typing import Any

from mcp.server import ServerRequestContext
from mcp.server.elicitation import elicit_url, elicit_with_validation, render_elicitation_schema
from mcp.types import (
    CallToolResult,
    ElicitRequest,
    ElicitRequestFormParams,
    ElicitResult,
    ImageContent,
    InputRequiredResult,
    TextContent,
    Tool,
    ToolAnnotations,
)
from pydantic import BaseModel, ConfigDict, Field, ValidationError, create_model

from rosbridge_mcp_server.errors import (
    ActionError,
    ConnectionLostError,
    InvalidMessageError,
    NotConnectedError,
    ProtocolError,
    RequestTimeoutError,
    RosbridgeError,
    ServiceError,
)
from rosbridge_mcp_server.robot.seam import Answer, AnswerNotInForm, AskPerson, call_ending
from rosbridge_mcp_server.robot.text import repaired, shown
from rosbridge_mcp_server.server.advice import advised
from rosbridge_mcp_server.server.sdk import cancelled_by_client
from rosbridge_mcp_server.tools.arguments import parameter_listing
from rosbridge_mcp_server.tools.base import (
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolHints,
    ToolImage,
    ToolSpec,
)
from rosbridge_mcp_server.tools.schemas import compact_input_schema, compact_output_schema

if typing.TYPE_CHECKING:
    from rosbridge_mcp_server.config import Config
    from rosbridge_mcp_server.robot.session import RobotSession

__all__ = [
    "EdgeTool",
    "Handler",
    "ToolCall",
    "arguments_model",
    "arguments_text",
    "edge_tool",
    "error_text",
    "inline_refs",
    "module_tool",
    "tool_annotations",
    "writable",
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
    """The strict model of a tool's arguments: *parameters* (annotations resolved) as fields, nothing else."""
    fields: dict[str, Any] = {
        p.name: (p.annotation, ... if p.default is inspect.Parameter.empty else p.default) for p in parameters
    }
    model: type[BaseModel] = create_model(
        f"{name}Arguments", __config__=ConfigDict(extra="forbid", arbitrary_types_allowed=True), **fields
    )
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
        return _merged([robot.name for robot in call.robots], answers)

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
        ask_person=_Asker(call),
        caller=call.caller,
    )
    ending = call_ending.set(functools.partial(_cancelled_why, session))
    try:
        answer = await run(ctx, **arguments)
    except _AskInNextRound as asking:
        return _question_round(asking)
    except (RosbridgeError, ToolFailure) as exc:
        _log.info("%s failed: %s", spec.name, exc)
        # A failure may show why (navigate_to draws a refused goal on the map).
        pictures = _images(getattr(exc, "images", ()))
        return CallToolResult(
            content=[TextContent(type="text", text=_where_set(error_text(exc), robot)), *pictures],
            is_error=True,
        )
    finally:
        call_ending.reset(ending)
    return CallToolResult(
        content=[TextContent(type="text", text=_where_set(answer.text, robot)), *_images(answer.images)],
        structured_content=answer.data.model_dump(mode="json"),
    )


def _cancelled_why(session: Any) -> str:
    if cancelled_by_client(session):
        return "cancelled by the client"
    # No cancel from the client: it went away (stdin closed, its HTTP session ended) or the server stops.
    return "cancelled: the client went away or the server is stopping"


def writable(result: CallToolResult | InputRequiredResult) -> CallToolResult | InputRequiredResult:
    """*result* with no unpaired UTF-16 surrogate left in its texts and structured content: the last line
    before an answer is written. The SDK's JSON writer refuses such a string, and on stdio that ends the
    server; robot text is repaired where frames are decoded (``wire/protocol.py``), this catches any other
    way one could come (a file, a path we missed). The very result when it holds none."""
    if not isinstance(result, CallToolResult):
        return result
    texts = [block.text for block in result.content if isinstance(block, TextContent)]
    structured = result.structured_content
    if repaired(texts) is texts and repaired(structured) is structured:
        return result
    content = [
        block.model_copy(update={"text": repaired(block.text)}) if isinstance(block, TextContent) else block
        for block in result.content
    ]
    return result.model_copy(update={"content": content, "structured_content": repaired(structured)})


def _where_set(text: str, robot: Robot) -> str:
    """*text* with a fleet robot's own entry (``[robots.base] in --robots fleet.toml``) named where a robot
    that cannot be reached points at the server's ROSBRIDGE_HOST/PORT settings, which it does not use."""
    if robot.config.url_source is None:
        return text
    return text.replace(NotConnectedError.SETTINGS, f"{robot.config.url_source} (robot {robot.name})")


def _images(images: typing.Iterable[ToolImage]) -> list[ImageContent]:
    return [
        ImageContent(
            type="image", data=base64.b64encode(image.data).decode("ascii"), mime_type=image.mime_type
        )
        for image in images
    ]


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


#: The longest error that quotes the bridge is shown whole up to this many characters.
_QUOTED_CHARS = 2_000


def error_text(exc: RosbridgeError | ToolFailure) -> str:
    """The sentence a model sees for a failed tool call: the error's own text, plus what to try."""
    text = advised(exc)
    if isinstance(exc, ServiceError | ActionError | ProtocolError):
        # They quote the bridge's (the robot's) own words: robot text, shown escaped and capped.
        text = shown(text, _QUOTED_CHARS)
    text = _sentence(text)
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


def _merged(names: list[str], answers: list[CallToolResult | InputRequiredResult]) -> CallToolResult:
    """One answer for a call made on several robots: each robot's text under its name, and every list of
    the structured content joined with each entry prefixed by its robot (stop_robot's answer is lists)."""
    texts: list[str] = []
    data: dict[str, Any] = {}
    failed = False
    for name, answer in zip(names, answers, strict=True):
        if not isinstance(answer, CallToolResult):
            # Only a tool whose spec says every_robot gets here, and none asks the person.
            texts.append(f"{name}: could not run here")
            failed = True
            continue
        failed = failed or bool(answer.is_error)
        text = "\n".join(block.text for block in answer.content if isinstance(block, TextContent))
        # Every line under its robot: a robot's answer may take several.
        texts += [f"{name}: {line}" for line in text.splitlines() or [""]]
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


class _Asker(AskPerson):
    """The person at the MCP client, asked through elicitation (``unsupported`` when the client cannot).

    Handshake sessions (up to 2025-11-25) get an ``elicitation/create`` request in the middle of the call.
    In 2026-07-28 sessions the call ends with an ``InputRequiredResult`` holding the question; the client asks
    the person and calls again, the tool runs again up to the same question, and the answer is found by a key
    made from the question's text, so a "yes" only ever approves exactly what it was shown.

    ``by_link`` is set when the client can open a URL for the person (URL-mode elicitation, handshake
    sessions): the guard then sends the person to this call's approval on the operator console, when one runs.
    """

    def __init__(self, call: ToolCall) -> None:
        self._call = call
        request = call.request
        capabilities = request.session.client_capabilities
        version = request.protocol_version
        can_link = (
            capabilities is not None
            and capabilities.elicitation is not None
            and capabilities.elicitation.url is not None
            and (version is None or version < _INPUT_ROUNDS_FROM)
        )
        self.by_link = self._send_to_link if can_link else None

    async def __call__(self, question: str) -> Answer:
        request = self._call.request
        capabilities = request.session.client_capabilities
        if capabilities is None or capabilities.elicitation is None:
            return "unsupported"
        version = request.protocol_version
        if version is not None and version >= _INPUT_ROUNDS_FROM:
            key = "confirm-" + hashlib.sha256(question.encode()).hexdigest()[:24]
            response = (self._call.input_responses or {}).get(key)
            if not isinstance(response, ElicitResult):
                raise _AskInNextRound(key, question)
            if response.action != "accept":
                return response.action
            return "accept" if _confirmed(response.content) else "decline"
        if capabilities.elicitation.form is None and capabilities.elicitation.url is not None:
            return "unsupported"  # a URL-only client answers by link, or not at all
        try:
            result = await elicit_with_validation(
                request.session, question, _Confirmation, related_request_id=request.request_id
            )
        except ValueError as exc:
            # The SDK's words for an accepted answer without content, or (caused by a ValidationError) with
            # content off the form.
            cause = exc.__cause__
            raise AnswerNotInForm(
                _form_problems(cause) if isinstance(cause, ValidationError) else "it accepted with no answer"
            ) from None
        except Exception:
            _log.info("asking the person failed", exc_info=True)
            return "unsupported"
        if result.action == "accept":
            return "accept" if result.data.approve else "decline"
        return result.action

    async def _send_to_link(self, question: str, url: str, elicitation_id: str) -> Answer:
        request = self._call.request
        message = f"Approve or deny this on the robot's operator console:\n{question}"
        try:
            result = await elicit_url(
                request.session, message, url, elicitation_id, related_request_id=request.request_id
            )
        except asyncio.CancelledError:
            # Answered on the console (or the call ended) while the client still shows the link: tell it the
            # out-of-band part is over, so it can close its prompt.
            with contextlib.suppress(Exception):
                await request.session.send_elicit_complete(elicitation_id)
            raise
        except Exception:
            _log.info("sending the person to the console failed", exc_info=True)
            return "unsupported"
        return result.action


def _confirmed(content: Mapping[str, Any] | None) -> bool:
    """Whether an accepted answer of a 2026 input round ticks ``approve``; :class:`AnswerNotInForm` when it
    does not fit the form."""
    if content is None:
        raise AnswerNotInForm("it accepted with no answer")
    try:
        return _Confirmation.model_validate(content).approve
    except ValidationError as exc:
        raise AnswerNotInForm(_form_problems(exc)) from None


def _form_problems(exc: ValidationError) -> str:
    """What was wrong with an answer, by field and pydantic's words, without the client's values."""
    problems = [f"{'.'.join(map(str, e['loc'])) or 'answer'}: {e['msg']}" for e in exc.errors()[:3]]
    return "; ".join(problems)[:200]


def _question_round(asking: _AskInNextRound) -> InputRequiredResult:
    request = ElicitRequest(
        params=ElicitRequestFormParams(
            message=asking.question, requested_schema=render_elicitation_schema(_Confirmation)
        )
    )
    return InputRequiredResult(input_requests={asking.key: request})
