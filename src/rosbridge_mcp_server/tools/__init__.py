"""The eight MCP tools, one module each (names and parameters are kept stable: prompts and clients use them).

Each module exposes ``SPEC`` (:class:`~rosbridge_mcp_server.tools.base.ToolSpec`) and
``async def run(ctx: ToolContext, <parameters>) -> ToolAnswer``. ``server/app.py`` registers them in the
order of :data:`TOOL_MODULES`.
"""

from __future__ import annotations

from types import ModuleType

from rosbridge_mcp_server.tools import (
    cancel_action,
    get_topic_info,
    list_actions,
    list_services,
    list_topics,
    publish_action,
    publish_service,
    publish_topic,
)

__all__ = ["TOOL_MODULES"]

TOOL_MODULES: tuple[ModuleType, ...] = (
    list_topics,
    get_topic_info,
    publish_topic,
    list_services,
    publish_service,
    list_actions,
    publish_action,
    cancel_action,
)
