"""The MCP tools, one module each, named after its tool.

Each module exposes ``SPEC`` (:class:`~rosbridge_mcp_server.tools.base.ToolSpec`) and
``async def run(ctx: ToolContext, <parameters>) -> ToolAnswer``. The catalogue (which tools there are, in
what order, in which ``--tools`` group) is ``catalogue.py``'s: :data:`TOOL_MODULES` is its names as modules,
in that order, and ``server/app.py`` registers the ones the configuration chose.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from rosbridge_mcp_server.catalogue import ALL_TOOL_NAMES

__all__ = ["TOOL_MODULES"]


def _modules(names: tuple[str, ...]) -> tuple[ModuleType, ...]:
    """The tool modules for *names*: each tool's module is named after the tool."""
    modules = tuple(importlib.import_module(f"{__name__}.{name}") for name in names)
    for name, module in zip(names, modules, strict=True):
        if module.SPEC.name != name:
            raise ImportError(f"tools/{name}.py declares the tool {module.SPEC.name!r}")
    return modules


#: Every tool module, in the catalogue's order (``catalogue.ALL_TOOL_NAMES``).
TOOL_MODULES: tuple[ModuleType, ...] = _modules(ALL_TOOL_NAMES)
