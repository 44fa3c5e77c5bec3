"""The MCP tools, one module each: the original eight, the ones that watch the robot, and the e-stop.

Each module exposes ``SPEC`` (:class:`~rosbridge_mcp_server.tools.base.ToolSpec`) and
``async def run(ctx: ToolContext, <parameters>) -> ToolAnswer``. ``server/app.py`` registers them in the order
of :data:`TOOL_MODULES`; :func:`select_tools` (from ``config.py``) picks the ones a host should see.
"""

from __future__ import annotations

from types import ModuleType

from rosbridge_mcp_server.config import (
    ALL_TOOL_NAMES,
    ORIGINAL_TOOL_NAMES,
    SAFETY_TOOL_NAMES,
    WATCH_TOOL_NAMES,
    select_tools,
)
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
    stop_robot,
    subscribe_topic,
)

__all__ = ["ORIGINAL_TOOLS", "SAFETY_TOOLS", "TOOL_GROUPS", "TOOL_MODULES", "WATCH_TOOLS", "select_tools"]

_BY_NAME: dict[str, ModuleType] = {
    module.SPEC.name: module
    for module in (
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
        stop_robot,
        subscribe_topic,
    )
}

#: The eight tools the server started with.
ORIGINAL_TOOLS: tuple[ModuleType, ...] = tuple(_BY_NAME[name] for name in ORIGINAL_TOOL_NAMES)

#: Tools that read the robot's state: topics, cameras, types, nodes, parameters, frames.
WATCH_TOOLS: tuple[ModuleType, ...] = tuple(_BY_NAME[name] for name in WATCH_TOOL_NAMES)

#: The e-stop for what this server started. Listed whenever any acting tool is (see ``server/app.py``).
SAFETY_TOOLS: tuple[ModuleType, ...] = tuple(_BY_NAME[name] for name in SAFETY_TOOL_NAMES)

TOOL_MODULES: tuple[ModuleType, ...] = ORIGINAL_TOOLS + WATCH_TOOLS + SAFETY_TOOLS

#: Names a ``--tools`` list may use for several tools at once.
TOOL_GROUPS: dict[str, tuple[ModuleType, ...]] = {
    "all": TOOL_MODULES,
    "original": ORIGINAL_TOOLS,
    "watch": WATCH_TOOLS,
    "safety": SAFETY_TOOLS,
}
if len(_BY_NAME) != len(TOOL_MODULES):  # a tool module the configuration does not name would never be listed
    raise ImportError(
        f"tools missing from config.ALL_TOOL_NAMES: {sorted(set(_BY_NAME) - set(ALL_TOOL_NAMES))}"
    )
