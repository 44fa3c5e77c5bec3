"""The tool catalogue, the one list of the tools: their names by ``--tools`` group, in registration order.

``tools/__init__.py`` imports the module of each name (failing at import when one has none), and
``config.py`` resolves a ``--tools`` value with :func:`select_tools`, so neither the configuration nor this
list needs any tool's code.
"""

from __future__ import annotations

__all__ = [
    "ALL_TOOL_NAMES",
    "ARM_TOOL_NAMES",
    "NAVIGATION_TOOL_NAMES",
    "ORIGINAL_TOOL_NAMES",
    "RECORD_TOOL_NAMES",
    "SAFETY_TOOL_NAMES",
    "TOOL_GROUPS",
    "VIEW_TOOL_NAMES",
    "WATCH_TOOL_NAMES",
    "select_tools",
]

#: The tools the server started with.
ORIGINAL_TOOL_NAMES = (
    "list_topics",
    "get_topic_info",
    "publish_topic",
    "list_services",
    "publish_service",
    "list_actions",
    "publish_action",
    "cancel_action",
)
WATCH_TOOL_NAMES = (
    "subscribe_topic",
    "get_image",
    "describe_type",
    "list_nodes",
    "get_node_info",
    "list_parameters",
    "get_parameter",
    "set_parameter",
    "get_transform",
    "read_logs",
    "diagnose",
)
#: Pictures of the robot's world: its map, its scan, a topic over time.
VIEW_TOOL_NAMES = ("view_map", "view_scan", "plot_topic")
SAFETY_TOOL_NAMES = ("stop_robot",)
#: Sending the robot somewhere on its map.
NAVIGATION_TOOL_NAMES = ("navigate_to",)
#: Recordings: MCAP files written from topics, and read back.
RECORD_TOOL_NAMES = ("record", "read_recording")
#: A robot arm: seeing it, and moving its joints and gripper within the URDF's limits and the policy's [arm].
ARM_TOOL_NAMES = ("view_arm", "move_arm", "move_gripper")
ALL_TOOL_NAMES = (
    ORIGINAL_TOOL_NAMES
    + WATCH_TOOL_NAMES
    + VIEW_TOOL_NAMES
    + SAFETY_TOOL_NAMES
    + NAVIGATION_TOOL_NAMES
    + RECORD_TOOL_NAMES
    + ARM_TOOL_NAMES
)
TOOL_GROUPS: dict[str, tuple[str, ...]] = {
    "all": ALL_TOOL_NAMES,
    "original": ORIGINAL_TOOL_NAMES,
    "watch": WATCH_TOOL_NAMES,
    "view": VIEW_TOOL_NAMES,
    "safety": SAFETY_TOOL_NAMES,
    "navigation": NAVIGATION_TOOL_NAMES,
    "record": RECORD_TOOL_NAMES,
    "arm": ARM_TOOL_NAMES,
}


def select_tools(spec: str) -> tuple[str, ...]:
    """The tool names a ``--tools`` value stands for, in registration order.

    ``spec`` is a comma-separated list of group names (``all``, ``original``, ``watch``, ``view``, ``safety``,
    ``navigation``, ``record``, ``arm``)
    and tool names, e.g. ``original,subscribe_topic,get_image``. :class:`ValueError` names anything unknown.
    """
    chosen: set[str] = set()
    unknown: list[str] = []
    for raw in spec.split(","):
        item = raw.strip()
        if not item:
            continue
        if item in TOOL_GROUPS:
            chosen.update(TOOL_GROUPS[item])
        elif item in ALL_TOOL_NAMES:
            chosen.add(item)
        else:
            unknown.append(item)
    if unknown:
        raise ValueError(
            f"unknown tool or group {', '.join(repr(u) for u in unknown)}; use {', '.join(TOOL_GROUPS)} or "
            f"tool names: {', '.join(ALL_TOOL_NAMES)}"
        )
    if not chosen:
        raise ValueError(f"no tools chosen; use {', '.join(TOOL_GROUPS)} or tool names")
    return tuple(name for name in ALL_TOOL_NAMES if name in chosen)
