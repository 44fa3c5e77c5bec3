"""The MCP tools, one module each, named after its tool.

Each module exposes ``SPEC`` (:class:`~rosbridge_mcp_server.tools.base.ToolSpec`) and
``async def run(ctx: ToolContext, <parameters>) -> ToolAnswer``. The catalogue (which tools there are, in
what order, in which ``--tools`` group) is ``catalogue.py``'s: :data:`TOOL_MODULES` is its names as modules,
in that order, and ``server/app.py`` registers the ones the configuration chose.
"""

from __future__ import annotations

import importlib
import inspect
from types import ModuleType

from rosbridge_mcp_server.catalogue import CATALOGUE, Entry

__all__ = ["TOOL_MODULES", "check_module"]


def _modules() -> tuple[ModuleType, ...]:
    """The catalogue's tool modules, each held to its entry (:func:`check_module`)."""
    modules = tuple(importlib.import_module(f"{__name__}.{entry.name}") for entry in CATALOGUE)
    for entry, module in zip(CATALOGUE, modules, strict=True):
        check_module(entry, module)
    return modules


def check_module(entry: Entry, module: ModuleType) -> None:
    """Raise ``ImportError`` unless *module* is *entry*'s tool: named after it, read-only exactly when the
    catalogue says it does not act (the ``--tools`` groups go by it), and its long work told by arguments
    its ``run`` takes."""
    if module.SPEC.name != entry.name:
        raise ImportError(f"tools/{entry.name}.py declares the tool {module.SPEC.name!r}")
    if module.SPEC.hints.read_only == entry.acts:
        raise ImportError(f"catalogue.py says {entry.name} acts={entry.acts}; its spec says otherwise")
    long = module.SPEC.long_work
    taken = inspect.signature(module.run).parameters
    for argument in (long.given, long.unless) if long is not None else ():
        if argument is not None and argument not in taken:
            raise ImportError(f"{entry.name}'s long_work names {argument!r}, which its run does not take")


#: Every tool module, in the catalogue's order (``catalogue.ALL_TOOL_NAMES``).
TOOL_MODULES: tuple[ModuleType, ...] = _modules()
