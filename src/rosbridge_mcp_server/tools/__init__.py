"""The MCP tools, one module each: the original eight, the ones that watch the robot, pictures, the e-stop.

Each module exposes ``SPEC`` (:class:`~rosbridge_mcp_server.tools.base.ToolSpec`) and
``async def run(ctx: ToolContext, <parameters>) -> ToolAnswer``. ``server/app.py`` registers them in the order
of :data:`TOOL_MODULES`; :func:`select_tools` (from ``config.py``) picks the ones a host should see.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from rosbridge_mcp_server.config import (
    ORIGINAL_TOOL_NAMES,
    SAFETY_TOOL_NAMES,
    VIEW_TOOL_NAMES,
    WATCH_TOOL_NAMES,
    select_tools,
)

__all__ = [
    "ORIGINAL_TOOLS",
    "SAFETY_TOOLS",
    "TOOL_GROUPS",
    "TOOL_MODULES",
    "VIEW_TOOLS",
    "WATCH_TOOLS",
    "select_tools",
]


def _modules(names: tuple[str, ...]) -> tuple[ModuleType, ...]:
    """The tool modules for *names*: each tool's module is named after the tool."""
    modules = tuple(importlib.import_module(f"{__name__}.{name}") for name in names)
    for name, module in zip(names, modules, strict=True):
        if module.SPEC.name != name:
            raise ImportError(f"tools/{name}.py declares the tool {module.SPEC.name!r}")
    return modules


#: The eight tools the server started with.
ORIGINAL_TOOLS: tuple[ModuleType, ...] = _modules(ORIGINAL_TOOL_NAMES)

#: Tools that read the robot's state: topics, cameras, types, nodes, parameters, frames.
WATCH_TOOLS: tuple[ModuleType, ...] = _modules(WATCH_TOOL_NAMES)

#: Pictures of the robot's world: the map with the robot on it, the scan from above, topics over time.
VIEW_TOOLS: tuple[ModuleType, ...] = _modules(VIEW_TOOL_NAMES)

#: The e-stop for what this server started. Listed whenever any acting tool is (see ``server/app.py``).
SAFETY_TOOLS: tuple[ModuleType, ...] = _modules(SAFETY_TOOL_NAMES)

TOOL_MODULES: tuple[ModuleType, ...] = ORIGINAL_TOOLS + WATCH_TOOLS + VIEW_TOOLS + SAFETY_TOOLS

#: Names a ``--tools`` list may use for several tools at once.
TOOL_GROUPS: dict[str, tuple[ModuleType, ...]] = {
    "all": TOOL_MODULES,
    "original": ORIGINAL_TOOLS,
    "watch": WATCH_TOOLS,
    "view": VIEW_TOOLS,
    "safety": SAFETY_TOOLS,
}
