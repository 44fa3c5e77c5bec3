"""The operator console's read-only view as an MCP App: the ``show_console`` tool and its ``ui://`` page.

Hosts that render MCP Apps (the extension ``mcp.server.apps`` names) show the page beside the conversation:
each robot's connection, the acting calls newest first, the streams and goals running, whether E-STOP is
latched, the confirmations waiting, and a camera (through ``get_image``). It only reads. Approve, Deny, E-STOP
and Release stay on the console itself, where the session secret is: the model's host must never hold a way to
approve.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from mcp.server.apps import APP_MIME_TYPE, EXTENSION_ID
from mcp.types import CallToolResult, Resource, TextContent, TextResourceContents, ToolAnnotations
from pydantic import BaseModel

from rosbridge_mcp_server.console import static_text, summary_text
from rosbridge_mcp_server.server.adapter import EdgeTool, ToolCall, arguments_model, edge_tool

__all__ = ["APPS_EXTENSION", "CONSOLE_APP_TOOL", "CONSOLE_APP_URI", "ConsoleApp", "console_app"]

CONSOLE_APP_URI = "ui://rosbridge/console.html"
CONSOLE_APP_TOOL = "show_console"
#: Acting calls in the tool's structured answer (the console page keeps more).
APP_AUDIT_LINES = 20
#: The MCP Apps extension, as the server's capabilities name it (no settings of its own).
APPS_EXTENSION = EXTENSION_ID


class ConsoleApp:
    """The ``show_console`` tool and its ``ui://`` page, the page read once."""

    def __init__(self, view: Callable[[], dict[str, Any]]) -> None:
        self.tool = _show_console(view)
        self.resource = Resource(
            uri=CONSOLE_APP_URI,
            name="operator-console",
            title="Operator console (read-only)",
            description="The robot's connection, acting calls, streams, goals, E-STOP state and camera",
            mime_type=APP_MIME_TYPE,
            _meta={"ui": {"prefersBorder": True}},
        )
        self._html = static_text("app.html")

    def read(self, uri: str) -> TextResourceContents | None:
        """The page, when *uri* is its address."""
        if uri != CONSOLE_APP_URI:
            return None
        return TextResourceContents(
            uri=CONSOLE_APP_URI,
            text=self._html,
            mime_type=APP_MIME_TYPE,
            _meta={"ui": {"prefersBorder": True}},
        )


def console_app(view: Callable[[], dict[str, Any]]) -> ConsoleApp:
    """The MCP App: ``show_console`` (reads ``view()``, the console's snapshot) and its page."""
    return ConsoleApp(view)


def _show_console(view: Callable[[], dict[str, Any]]) -> EdgeTool:
    async def handler(call: ToolCall, arguments: BaseModel) -> CallToolResult:
        snapshot = view()
        snapshot = {**snapshot, "audit": snapshot["audit"][:APP_AUDIT_LINES]}
        return CallToolResult(
            content=[TextContent(type="text", text=summary_text(snapshot))], structured_content=snapshot
        )

    return edge_tool(
        name=CONSOLE_APP_TOOL,
        title="Show the operator console",
        description=(
            "What the operator console shows: the robot's connection, the last acting calls, running "
            "streams and goals, whether E-STOP is latched, confirmations waiting. Read-only: it sends "
            "nothing to the robot."
        ),
        annotations=ToolAnnotations(
            title="Show the operator console", read_only_hint=True, idempotent_hint=True, open_world_hint=True
        ),
        arguments=arguments_model(CONSOLE_APP_TOOL, []),
        output=None,
        handler=handler,
        on_robot=False,
        meta={"ui": {"resourceUri": CONSOLE_APP_URI}},
    )
