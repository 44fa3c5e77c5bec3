"""Each use of MCP SDK internals (``server/sdk.py``) still has its effect on the installed SDK.

These fail by name when an SDK upgrade changes what a function relies on, instead of somewhere in a tool call.
"""

from __future__ import annotations

import inspect
from typing import Annotated, Any

import anyio
from mcp.client.session import ClientSession
from mcp.server.mcpserver import Context, MCPServer
from mcp.shared.memory import create_client_server_memory_streams
from mcp.types import CallToolResult, TextContent, ToolAnnotations
from pydantic import BaseModel, Field, ValidationError

from mcp import Client
from rosbridge_mcp_server.server.checks import CheckedTool, ToolCallChecks
from rosbridge_mcp_server.server.sdk import (
    argument_pre_parse,
    replace_output_schema,
    serve_streams,
    tool_from_handler,
    tool_with_handler,
)


class _Doubled(BaseModel):
    value: int


PARAMETERS = [
    inspect.Parameter(
        "number",
        inspect.Parameter.POSITIONAL_OR_KEYWORD,
        annotation=Annotated[int, Field(description="a number, e.g. 2")],
    )
]
contexts: list[object] = []


async def _double(mcp_context: Context[Any, Any], **arguments: Any) -> CallToolResult:
    contexts.append(mcp_context)
    number = arguments["number"]
    return CallToolResult(
        content=[TextContent(type="text", text=str(number * 2))], structured_content={"value": number * 2}
    )


def _reword(tool: str, error: ValidationError, schema: dict[str, Any]) -> str:
    return f"{tool} wants {', '.join(schema['properties'])} ({error.error_count()} wrong)"


def _tool() -> Any:
    return tool_from_handler(
        _double,
        PARAMETERS,
        _Doubled,
        name="double",
        title="Double",
        description="Doubles a number.",
        annotations=ToolAnnotations(title="Double", read_only_hint=True),
    )


def _checked_server(
    check: Any = lambda tool, arguments, schema: None, unlisted: Any = None, **kwargs: Any
) -> MCPServer[Any]:
    tool = _tool()
    checks = ToolCallChecks(
        [CheckedTool.of("double", tool.parameters, PARAMETERS)],
        argument_check=check,
        argument_error=_reword,
        unlisted=unlisted,
    )
    return MCPServer("seam", tools=[tool], middleware=[checks], **kwargs)


async def test_argument_errors_are_worded_by_our_function() -> None:
    """A call whose arguments do not fit is an isError result with our sentence, not pydantic's dump."""
    async with Client(_checked_server()) as client:
        result = await client.call_tool("double", {"number": "many"})
    assert result.is_error
    assert isinstance(result.content[0], TextContent)
    assert result.content[0].text == "double wants number (1 wrong)"


async def test_the_argument_check_sees_the_arguments_as_sent_before_the_sdk_converts_them() -> None:
    """Unknown keys and booleans reach the check (the SDK drops the one and converts the other after)."""
    seen: list[dict[str, Any]] = []

    def check(tool: str, arguments: dict[str, Any], schema: dict[str, Any]) -> str | None:
        seen.append(dict(arguments))
        return f"{tool}: no" if "extra" in arguments else None

    async with Client(_checked_server(check)) as client:
        refused = await client.call_tool("double", {"number": True, "extra": 1})
        accepted = await client.call_tool("double", {"number": 2})
    assert seen == [{"number": True, "extra": 1}, {"number": 2}]
    assert refused.is_error
    assert isinstance(refused.content[0], TextContent)
    assert refused.content[0].text == "double: no"
    assert accepted.structured_content == {"value": 4}


async def test_the_tool_has_the_parameters_given_and_its_handler_gets_them_with_the_sdk_context() -> None:
    """The input schema is the parameters given (not the handler's **arguments nor its context); it runs."""
    contexts.clear()
    async with Client(MCPServer("seam", tools=[_tool()])) as client:
        [listed] = (await client.list_tools()).tools
        result = await client.call_tool("double", {"number": 21})
    assert list(listed.input_schema["properties"]) == ["number"]
    assert listed.input_schema["properties"]["number"]["description"] == "a number, e.g. 2"
    assert listed.input_schema["required"] == ["number"]
    assert len(contexts) == 1
    assert isinstance(contexts[0], Context)
    assert listed.annotations is not None
    assert listed.annotations.read_only_hint is True
    assert not result.is_error
    assert result.structured_content == {"value": 42}


async def test_a_replaced_output_schema_is_the_one_clients_see() -> None:
    """replace_output_schema changes the listed output schema, given the one the SDK derived."""
    tool = _tool()
    seen: list[dict[str, Any]] = []

    def replace(derived: dict[str, Any]) -> dict[str, Any]:
        seen.append(derived)
        return {**derived, "description": "replaced"}

    replace_output_schema(tool, replace)
    async with Client(MCPServer("seam", tools=[tool])) as client:
        [listed] = (await client.list_tools()).tools
    assert seen
    assert seen[0]["properties"] == {"value": {"title": "Value", "type": "integer"}}
    assert listed.output_schema is not None
    assert listed.output_schema["description"] == "replaced"


async def test_a_tool_copied_with_another_handler_runs_that_handler_with_the_templates_schemas() -> None:
    """Two servers from one template: each call reaches its own server's handler, validated by the template's
    argument model, and both list the template's replaced output schema."""
    template = _tool()
    replace_output_schema(template, lambda derived: {**derived, "description": "shared"})
    tripled: list[int] = []

    async def _triple(mcp_context: Context[Any, Any], **arguments: Any) -> CallToolResult:
        tripled.append(arguments["number"])
        value = arguments["number"] * 3
        return CallToolResult(
            content=[TextContent(type="text", text=str(value))], structured_content={"value": value}
        )

    doubling = MCPServer("seam", tools=[tool_with_handler(template, _double)])
    tripling = MCPServer("seam", tools=[tool_with_handler(template, _triple)])
    async with Client(doubling) as first, Client(tripling) as second:
        doubled = await first.call_tool("double", {"number": 5})
        thrice = await second.call_tool("double", {"number": "5"})
        wrong = await second.call_tool("double", {"number": "many"})
        [listed] = (await second.list_tools()).tools
    assert (doubled.structured_content, thrice.structured_content) == ({"value": 10}, {"value": 15})
    assert tripled == [5]  # converted by the template's argument model before the handler saw it
    assert wrong.is_error
    assert listed.output_schema is not None
    assert listed.output_schema["description"] == "shared"


async def test_serve_streams_serves_an_mcp_server_on_the_streams_it_is_given() -> None:
    """A client on the other end of the streams initializes, lists and calls tools."""
    server = MCPServer("seam", tools=[_tool()])
    async with (
        create_client_server_memory_streams() as (client_streams, server_streams),
        anyio.create_task_group() as group,
    ):
        group.start_soon(serve_streams, server, *server_streams)
        async with ClientSession(*client_streams) as session:
            with anyio.fail_after(10):
                await session.initialize()
                listed = await session.list_tools()
                result = await session.call_tool("double", {"number": 2})
        group.cancel_scope.cancel()
    assert [tool.name for tool in listed.tools] == ["double"]
    assert result.structured_content == {"value": 4}


async def test_the_checks_answer_unlisted_tools_they_know_and_leave_others_to_the_sdk() -> None:
    """A withheld tool gets our answer; any other unknown name still gets the SDK's "Unknown tool"."""

    def unlisted(name: str, arguments: dict[str, Any]) -> str | None:
        return f"withheld, arguments {sorted(arguments)}" if name == "withheld" else None

    async with Client(_checked_server(unlisted=unlisted), mode="legacy") as client:
        ours = await client.call_tool("withheld", {"a": 1})
        theirs = await client.call_tool("other", {})
    assert ours.is_error
    assert ours.content[0].text == "withheld, arguments ['a']"  # type: ignore[union-attr]
    assert theirs.is_error
    assert "Unknown tool: other" in theirs.content[0].text  # type: ignore[union-attr]


async def test_the_sdk_reads_json_text_as_the_pre_parse_says_and_the_checks_name_it() -> None:
    """The SDK's pre-parse turns "null" for an int into None (and leaves "7" alone); the checks validate
    that, so the call gets our sentence (naming the text) instead of the SDK's own validation error."""
    pre_parse = argument_pre_parse(_tool())
    assert pre_parse({"number": "null"}) == {"number": None}
    assert pre_parse({"number": "7"}) == {"number": "7"}
    tool = _tool()
    checks = ToolCallChecks(
        [CheckedTool.of("double", tool.parameters, PARAMETERS, argument_pre_parse(tool))],
        argument_check=lambda tool, arguments, schema: None,
        argument_error=_reword,
    )
    async with Client(MCPServer("seam", tools=[tool], middleware=[checks])) as client:
        result = await client.call_tool("double", {"number": "null"})
    assert result.is_error
    assert isinstance(result.content[0], TextContent)
    assert result.content[0].text == (
        "double wants number (1 wrong) number was given as the text 'null', which is read as JSON."
    )
