"""The tool catalogue, the one list of the tools: each tool's name, the family it came with and whether it
acts, in registration order; the ``--tools`` groups are derived from it.

``tools/__init__.py`` imports the module of each name (failing at import when one has none, or when a tool's
spec and its entry here disagree on whether it acts), and ``config.py`` resolves a ``--tools`` value with
:func:`select_tools`, so neither the configuration nor this list needs any tool's code. ``--help`` words the
groups with :func:`groups_help`.
"""

from __future__ import annotations

from typing import Final, NamedTuple

__all__ = [
    "ALL_TOOL_NAMES",
    "ARM_TOOL_NAMES",
    "CATALOGUE",
    "GROUP_HELP",
    "NAVIGATION_TOOL_NAMES",
    "ORIGINAL_TOOL_NAMES",
    "RECORD_TOOL_NAMES",
    "SAFETY_TOOL_NAMES",
    "TOOL_GROUPS",
    "VIEW_TOOL_NAMES",
    "WATCH_TOOL_NAMES",
    "Entry",
    "groups_help",
    "select_tools",
]


class Entry(NamedTuple):
    """One tool: its name, the family it came with, and whether it acts (its spec is not read-only: it
    changes the robot, or with ``record`` the host's disk)."""

    name: str
    family: str
    acts: bool


#: Every tool, in registration order.
CATALOGUE: Final[tuple[Entry, ...]] = (
    # The tools the server started with.
    Entry("list_topics", "original", acts=False),
    Entry("get_topic_info", "original", acts=False),
    Entry("publish_topic", "original", acts=True),
    Entry("list_services", "original", acts=False),
    Entry("publish_service", "original", acts=True),
    Entry("list_actions", "original", acts=False),
    Entry("publish_action", "original", acts=True),
    Entry("cancel_action", "original", acts=True),
    # Reading the robot (and setting a parameter).
    Entry("subscribe_topic", "robot", acts=False),
    Entry("get_image", "robot", acts=False),
    Entry("describe_type", "robot", acts=False),
    Entry("list_nodes", "robot", acts=False),
    Entry("get_node_info", "robot", acts=False),
    Entry("list_parameters", "robot", acts=False),
    Entry("get_parameter", "robot", acts=False),
    Entry("set_parameter", "robot", acts=True),
    Entry("get_transform", "robot", acts=False),
    Entry("read_logs", "robot", acts=False),
    Entry("diagnose", "robot", acts=False),
    # Pictures of the robot's world: its map, its scan, a topic over time.
    Entry("view_map", "view", acts=False),
    Entry("view_scan", "view", acts=False),
    Entry("plot_topic", "view", acts=False),
    Entry("stop_robot", "safety", acts=True),
    # Sending the robot somewhere on its map.
    Entry("navigate_to", "navigation", acts=True),
    # Recordings: MCAP files written from topics, and read back.
    Entry("record", "record", acts=True),
    Entry("read_recording", "record", acts=False),
    # A robot arm: seeing it, and moving its joints and gripper within the URDF's limits and [arm].
    Entry("view_arm", "arm", acts=False),
    Entry("move_arm", "arm", acts=True),
    Entry("move_gripper", "arm", acts=True),
)


def _names(keep: set[str] | None = None, *, reading: bool = False) -> tuple[str, ...]:
    return tuple(e.name for e in CATALOGUE if (keep is None or e.family in keep) and not (reading and e.acts))


ALL_TOOL_NAMES: Final = _names()
ORIGINAL_TOOL_NAMES: Final = _names({"original"})
#: Every tool that reads the robot's graph and state (not the pictures or recordings): nothing that acts.
WATCH_TOOL_NAMES: Final = _names({"original", "robot"}, reading=True)
VIEW_TOOL_NAMES: Final = _names({"view"})
SAFETY_TOOL_NAMES: Final = _names({"safety"})
NAVIGATION_TOOL_NAMES: Final = _names({"navigation"})
RECORD_TOOL_NAMES: Final = _names({"record"})
ARM_TOOL_NAMES: Final = _names({"arm"})
TOOL_GROUPS: Final[dict[str, tuple[str, ...]]] = {
    "all": ALL_TOOL_NAMES,
    "original": ORIGINAL_TOOL_NAMES,
    "watch": WATCH_TOOL_NAMES,
    "view": VIEW_TOOL_NAMES,
    "safety": SAFETY_TOOL_NAMES,
    "navigation": NAVIGATION_TOOL_NAMES,
    "record": RECORD_TOOL_NAMES,
    "arm": ARM_TOOL_NAMES,
}
#: What each group holds, in a few words (``--help``; a group of one or two tools is named by its tools).
GROUP_HELP: Final[dict[str, str]] = {
    "all": "every tool",
    "original": "the first eight, with stop_robot whenever a tool acts",
    "watch": "reading the robot, nothing that acts: topics, services, actions, cameras, types, nodes, "
    "parameters, frames, its log, diagnose",
    "view": "pictures: map, scan, charts",
}


def groups_help() -> str:
    """Every group and what it holds: ``all (every tool); ...; record (record, read_recording)``."""
    return "; ".join(
        f"{group} ({GROUP_HELP.get(group) or ', '.join(names)})" for group, names in TOOL_GROUPS.items()
    )


def select_tools(spec: str) -> tuple[str, ...]:
    """The tool names a ``--tools`` value stands for, in registration order.

    ``spec`` is a comma-separated list of group names (those of :data:`TOOL_GROUPS`) and tool names, e.g.
    ``original,subscribe_topic,get_image``. :class:`ValueError` names anything unknown.
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
