"""The MCP tools, one module each: the original eight, then the ones that watch the robot.

Each module exposes ``SPEC`` (:class:`~rosbridge_mcp_server.tools.base.ToolSpec`) and
``async def run(ctx: ToolContext, <parameters>) -> ToolAnswer``. ``server.py`` registers them in the order of
:data:`TOOL_MODULES`; :func:`select_tools` picks the ones a host should see.
"""

from __future__ import annotations

from types import ModuleType

from rosbridge_mcp_server.tools import (
    cancel_action,
    describe_type,
    get_image,
    get_node_info,
    get_parameter,
    get_topic_info,
    get_transform,
    list_actions,
    list_nodes,
    list_parameters,
    list_services,
    list_topics,
    publish_action,
    publish_service,
    publish_topic,
    set_parameter,
    subscribe_topic,
)

__all__ = ["ORIGINAL_TOOLS", "TOOL_MODULES", "WATCH_TOOLS"]

#: The eight tools the server started with (names and parameters of the project this one replaces).
ORIGINAL_TOOLS: tuple[ModuleType, ...] = (
    list_topics,
    get_topic_info,
    publish_topic,
    list_services,
    publish_service,
    list_actions,
    publish_action,
    cancel_action,
)

#: Tools that read the robot's state: topics, cameras, types, nodes, parameters, frames.
WATCH_TOOLS: tuple[ModuleType, ...] = (
    subscribe_topic,
    get_image,
    describe_type,
    list_nodes,
    get_node_info,
    list_parameters,
    get_parameter,
    set_parameter,
    get_transform,
)

TOOL_MODULES: tuple[ModuleType, ...] = ORIGINAL_TOOLS + WATCH_TOOLS
