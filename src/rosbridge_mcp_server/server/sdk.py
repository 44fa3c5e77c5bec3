"""Every use of the MCP SDK beyond its documented API, each behind one named function.

The SDK (``mcp`` 2.3) documents ``MCPServer(tools=..., middleware=...)``, the stdio and Streamable HTTP
transports and the auth settings, which is what the rest of ``server/`` uses. Five things have no documented
way; each function here says what it relies on, and ``tests/mcp/test_sdk_seam.py`` holds each to its effect,
so an SDK upgrade that changes one fails there, by name, instead of somewhere in a tool call:

* :func:`tool_from_handler`: a ``Tool`` for a handler that takes ``**arguments``, with the parameters we give
  it. The SDK reads a tool's parameters from ``inspect.signature`` of the function (which honours
  ``__signature__``, so we hand it one) and finds the ``Context`` parameter by its annotation.
* :func:`tool_with_handler`: a copy of such a ``Tool`` calling another handler (``Tool.run`` calls
  ``Tool.fn``), so the schemas and argument model, built once, serve every server.
* :func:`replace_output_schema`: the output schema the SDK derived from the return annotation, replaced
  (``Tool.output_schema`` reads ``Tool.fn_metadata.output_schema``).
* :func:`argument_pre_parse`: the SDK's own reading of a tool's arguments before it validates them: a string
  given for a parameter that is not a plain ``str`` is parsed as JSON when it holds an object, a list,
  ``null`` or a boolean (``FuncMetadata.pre_parse_json``), so ``"request": "null"`` reaches validation as
  ``None``. The server's checks validate what the SDK will, so that such a call gets our sentence too.
* :func:`serve_streams`: ``MCPServer`` on streams we give it (the SDK's stdio transport's, with unreadable
  lines answered). ``MCPServer.run_stdio_async`` opens the transport itself; what it runs is its low-level
  server's ``run`` with the streams.
"""

from __future__ import annotations

import inspect
from collections.abc import Awaitable, Callable
from typing import Annotated, Any

from mcp.server.mcpserver import Context, MCPServer
from mcp.server.mcpserver.tools import Tool
from mcp.types import CallToolResult, InputRequiredResult, ToolAnnotations
from pydantic import BaseModel

__all__ = [
    "argument_pre_parse",
    "replace_output_schema",
    "serve_streams",
    "tool_from_handler",
    "tool_with_handler",
]


def tool_from_handler(
    handler: Callable[..., Awaitable[CallToolResult | InputRequiredResult]],
    parameters: list[inspect.Parameter],
    output: type[BaseModel],
    *,
    name: str,
    title: str,
    description: str,
    annotations: ToolAnnotations,
) -> Tool:
    """A structured-output ``Tool``: ``await handler(mcp_context=<the SDK's Context>, **arguments)``.

    *parameters* (annotations resolved) are the tool's input schema; *output* is the model of its structured
    content. Relies on the SDK taking the parameters from ``inspect.signature`` (which honours
    ``__signature__``) and leaving a ``Context``-annotated one out of the schema.
    An ``InputRequiredResult`` from the handler (a question for the person, 2026-07-28) goes out unchanged.
    """
    returns = Annotated[CallToolResult, output]
    every = [
        *parameters,
        inspect.Parameter("mcp_context", inspect.Parameter.KEYWORD_ONLY, annotation=Context),
    ]
    handler.__name__ = name
    handler.__qualname__ = name
    handler.__doc__ = description
    setattr(handler, "__signature__", inspect.Signature(every, return_annotation=returns))  # noqa: B010
    handler.__annotations__ = {p.name: p.annotation for p in every} | {"return": returns}
    return Tool.from_function(
        handler,
        name=name,
        title=title,
        description=description,
        annotations=annotations,
        structured_output=True,
    )


def tool_with_handler(template: Tool, handler: Callable[..., Awaitable[Any]]) -> Tool:
    """A copy of *template* (from :func:`tool_from_handler`) that calls *handler* instead.

    Relies on ``Tool.run`` calling ``self.fn`` with the arguments ``self.fn_metadata`` validated, so one
    template's argument model and schemas serve every server's tool. The copy is shallow: the copy's
    ``parameters`` may be replaced, never changed in place.
    """
    return template.model_copy(update={"fn": handler})


def replace_output_schema(tool: Tool, schema: Callable[[dict[str, Any]], dict[str, Any]]) -> None:
    """Replace *tool*'s output schema by ``schema(derived)``, before anything has read it.

    Relies on ``Tool.output_schema`` being read from ``Tool.fn_metadata.output_schema`` (a cached property,
    so this must run before the tool is listed or called).
    """
    derived = tool.fn_metadata.output_schema
    if derived is not None:
        tool.fn_metadata.output_schema = schema(derived)


def argument_pre_parse(tool: Tool) -> Callable[[dict[str, Any]], dict[str, Any]]:
    """The SDK's reading of *tool*'s arguments before validation (``Tool.fn_metadata.pre_parse_json``): the
    arguments as the SDK will validate them, a new dict (the one given is left alone)."""
    pre_parse: Callable[[dict[str, Any]], dict[str, Any]] = tool.fn_metadata.pre_parse_json
    return pre_parse


async def serve_streams(server: MCPServer[Any], read_stream: Any, write_stream: Any) -> None:
    """Serve *server* on the given message streams until the read stream ends.

    What ``MCPServer.run_stdio_async`` does with the streams of the SDK's own stdio transport; it relies on
    ``MCPServer._lowlevel_server`` (a ``mcp.server.lowlevel.Server``).
    """
    lowlevel = server._lowlevel_server
    await lowlevel.run(read_stream, write_stream, lowlevel.create_initialization_options())
