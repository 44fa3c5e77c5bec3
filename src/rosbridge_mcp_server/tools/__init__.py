"""The MCP tools, one module each: the original eight, the ones that watch the robot, and the e-stop.

Each module exposes ``SPEC`` (:class:`~rosbridge_mcp_server.tools.base.ToolSpec`) and
``async def run(ctx: ToolContext, <parameters>) -> ToolAnswer``. ``server/app.py`` registers them in the order
of :data:`TOOL_MODULES`; :func:`select_tools` picks the ones a host should see.
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
    stop_robot,
    subscribe_topic,
)

__all__ = ["ORIGINAL_TOOLS", "SAFETY_TOOLS", "TOOL_GROUPS", "TOOL_MODULES", "WATCH_TOOLS", "select_tools"]

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

#: The e-stop for what this server started. Listed whenever any acting tool is (see ``server/app.py``).
SAFETY_TOOLS: tuple[ModuleType, ...] = (stop_robot,)

TOOL_MODULES: tuple[ModuleType, ...] = ORIGINAL_TOOLS + WATCH_TOOLS + SAFETY_TOOLS

#: Names a ``--tools`` list may use for several tools at once.
TOOL_GROUPS: dict[str, tuple[ModuleType, ...]] = {
    "all": TOOL_MODULES,
    "original": ORIGINAL_TOOLS,
    "watch": WATCH_TOOLS,
    "safety": SAFETY_TOOLS,
}


def select_tools(spec: str) -> tuple[str, ...]:
    """The tool names a ``--tools`` value stands for, in registration order.

    ``spec`` is a comma-separated list of group names (``all``, ``original``, ``watch``, ``safety``) and tool
    names, e.g.
    ``original,subscribe_topic,get_image``. :class:`ValueError` names anything unknown.
    """
    by_name = {module.SPEC.name: module for module in TOOL_MODULES}
    chosen: set[str] = set()
    unknown: list[str] = []
    for raw in spec.split(","):
        item = raw.strip()
        if not item:
            continue
        if item in TOOL_GROUPS:
            chosen.update(module.SPEC.name for module in TOOL_GROUPS[item])
        elif item in by_name:
            chosen.add(item)
        else:
            unknown.append(item)
    if unknown:
        raise ValueError(
            f"unknown tool or group {', '.join(repr(u) for u in unknown)}; use {', '.join(TOOL_GROUPS)} or "
            f"tool names: {', '.join(by_name)}"
        )
    if not chosen:
        raise ValueError(f"no tools chosen; use {', '.join(TOOL_GROUPS)} or tool names")
    return tuple(name for name in by_name if name in chosen)
