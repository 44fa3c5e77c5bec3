"""The operator console's read-only view as an MCP App: the ``show_console`` tool and its ``ui://`` page.

Hosts that render MCP Apps (the SDK's ``mcp.server.apps``) show the page beside the conversation: each robot's
connection, the acting calls newest first, the streams and goals running, whether E-STOP is latched, the
confirmations waiting, and a camera (through ``get_image``). It only reads. Approve, Deny, E-STOP and Release
stay on the console itself, where the session secret is: the model's host must never hold a way to approve.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from mcp.server.apps import Apps
from mcp.types import CallToolResult, TextContent, ToolAnnotations

from rosbridge_mcp_server.console import static_text, summary_text

__all__ = ["CONSOLE_APP_TOOL", "CONSOLE_APP_URI", "console_app"]

CONSOLE_APP_URI = "ui://rosbridge/console.html"
CONSOLE_APP_TOOL = "show_console"
#: Acting calls in the tool's structured answer (the console page keeps more).
APP_AUDIT_LINES = 20


def console_app(view: Callable[[], dict[str, Any]]) -> Apps:
    """The MCP Apps extension: ``show_console`` (reads ``view()``, the console's snapshot) and its page."""
    apps = Apps()

    @apps.tool(
        resource_uri=CONSOLE_APP_URI,
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
    )
    def show_console() -> CallToolResult:
        snapshot = view()
        snapshot = {**snapshot, "audit": snapshot["audit"][:APP_AUDIT_LINES]}
        return CallToolResult(
            content=[TextContent(type="text", text=summary_text(snapshot))], structured_content=snapshot
        )

    apps.add_html_resource(
        CONSOLE_APP_URI,
        static_text("app.html"),
        name="operator-console",
        title="Operator console (read-only)",
        description="The robot's connection, acting calls, streams, goals, E-STOP state and camera",
        prefers_border=True,
    )
    return apps
