"""The layers of docs/architecture.md, held from the source: each package imports only the packages below it,
Pillow is imported only where pictures are drawn, ``robot/`` loads no picture code at run time, and its
texts name no MCP tool (what to try next is worded at the MCP edge, ``server/advice.py``)."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import rosbridge_mcp_server
from rosbridge_mcp_server.catalogue import ALL_TOOL_NAMES

PACKAGE = Path(rosbridge_mcp_server.__file__).parent

#: Bottom to top; a package may import those on lower rows. ``safety/`` and ``pictures/`` share a row: both
#: stand on ``robot/`` and neither imports the other.
LAYERS: tuple[frozenset[str], ...] = (
    frozenset({"wire"}),
    frozenset({"client"}),
    frozenset({"robot"}),
    frozenset({"safety", "pictures"}),
    frozenset({"tools"}),
    frozenset({"console"}),
    frozenset({"server"}),
    frozenset({"cli"}),
)
#: Modules beside the layers that any layer may import (the exception tree, the tool catalogue, the
#: configuration); what they themselves import is not a layer's business here.
SHARED = frozenset({"errors", "catalogue", "config", "http_config", "fleet_config"})
#: The simulated robot stands beside the layers; only the command (``--demo``) starts it.
SIMULATOR = "sim"


def _imports(path: Path) -> Iterator[tuple[int, str]]:
    """Every module *path* imports (``TYPE_CHECKING`` and function-level imports included), with its line."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            yield node.lineno, node.module
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name


def _top(path: Path) -> str:
    """The top-level package (or module) of ours that *path* belongs to."""
    return path.relative_to(PACKAGE).parts[0].removesuffix(".py")


def _ours(module: str) -> str | None:
    """The top-level package of ours that *module* names, or ``None`` for a third-party or standard one."""
    parts = module.split(".")
    if parts[0] != "rosbridge_mcp_server":
        return None
    return parts[1] if len(parts) > 1 else "__init__"


def _layer_of(package: str) -> int | None:
    return next((row for row, names in enumerate(LAYERS) if package in names), None)


def test_each_layer_imports_only_the_layers_below_it_and_the_shared_modules() -> None:
    """No upward arrow and no sideways one (``pictures/`` ↔ ``safety/``), ``TYPE_CHECKING`` included."""
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        source = _top(path)
        row = _layer_of(source)
        if row is None:
            continue
        for line, module in _imports(path):
            target = _ours(module)
            if target is None or target == source or target in SHARED or target == "__init__":
                continue
            if target == SIMULATOR and source == "cli":
                continue
            target_row = _layer_of(target)
            if target_row is None or target_row >= row:
                offenders.append(f"{path.relative_to(PACKAGE)}:{line} imports {module}")
    assert offenders == []


def test_the_layer_table_knows_every_package_of_ours() -> None:
    """A new package is placed in the table (or among the shared modules, or the simulated robot's) before
    its imports go unchecked."""
    tops = {_top(path) for path in PACKAGE.rglob("*.py")}
    placed = set().union(*LAYERS) | SHARED | {SIMULATOR, "__init__", "__main__"}
    assert sorted(tops - placed) == []


def test_pillow_is_imported_only_by_the_pictures_and_the_simulated_robot() -> None:
    """``robot/`` reads grids, scans and frames as data; drawing and encoding them is ``pictures/``'s."""
    offenders = [
        f"{path.relative_to(PACKAGE)}:{line}"
        for path in sorted(PACKAGE.rglob("*.py"))
        if _top(path) not in {"pictures", "sim"}
        for line, module in _imports(path)
        if module == "PIL" or module.startswith("PIL.")
    ]
    assert offenders == []


def test_the_domain_loads_neither_pictures_nor_pillow() -> None:
    """Every module of ``robot/`` imported in a fresh interpreter leaves Pillow and ``pictures/`` unloaded."""
    modules = sorted(
        ".".join(("rosbridge_mcp_server", *path.relative_to(PACKAGE).with_suffix("").parts)).removesuffix(
            ".__init__"
        )
        for path in (PACKAGE / "robot").rglob("*.py")
    )
    program = (
        "import importlib, sys\n"
        f"for name in {modules!r}: importlib.import_module(name)\n"
        "picture = ('PIL.', 'rosbridge_mcp_server.pictures')\n"
        "print(sorted(m for m in sys.modules if m == 'PIL' or m.startswith(picture)))"
    )
    done = subprocess.run(
        [sys.executable, "-c", program], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 0, done.stderr
    assert len(modules) > 30  # the walk found robot/'s modules, so the empty list below means something
    assert done.stdout.strip() == "[]"


def test_the_simulated_robot_imports_nothing_of_the_server() -> None:
    """``sim/`` shares nothing with the layers but the wire's protocol: it imports no module of ours."""
    offenders = [
        f"{path.relative_to(PACKAGE)}:{line} imports {module}"
        for path in sorted((PACKAGE / SIMULATOR).rglob("*.py"))
        for line, module in _imports(path)
        if _ours(module) not in {None, SIMULATOR}
    ]
    assert offenders == []


#: Where robot/ still names MCP tools in its texts, by file, and how often each. The list only shrinks: what
#: to try next is a typed hint (errors.Hint) that server/advice.py words, and diagnose's next calls typed
#: steps that tools/diagnose.py words. ``list_parameters`` in known_types.py is the ROS service of that name,
#: not the tool.
TOOL_NAMES_LEFT: dict[str, dict[str, int]] = {
    "robot/known_types.py": {"list_parameters": 1},
}
#: A goal's canceller is named by a value the answers carry (``canceled_by``: "cancel_action", "stop_robot"),
#: not by advice: the goal records' texts are not counted.
NOT_COUNTED = ("robot/goals/",)


def _texts(path: Path) -> Iterator[ast.Constant]:
    """The string constants of *path* that can reach a reader: not docstrings, not ``__all__``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skipped: set[int] = set()
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) and body:
            first = body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                skipped.add(id(first.value))
        if isinstance(node, ast.Assign) and any(
            isinstance(target, ast.Name) and target.id == "__all__" for target in node.targets
        ):
            skipped.update(id(item) for item in ast.walk(node.value))
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in skipped:
            yield node


def test_the_domain_names_no_mcp_tool_but_the_listed_ones() -> None:
    """robot/ and errors.py say what went wrong; the tools to call next are named at the MCP edge."""
    names = "|".join(sorted(ALL_TOOL_NAMES, key=len, reverse=True))
    tool = re.compile(rf"(?<![\w/])({names})(?![\w/])")
    found: dict[str, dict[str, int]] = {}
    for path in sorted([*(PACKAGE / "robot").rglob("*.py"), PACKAGE / "errors.py"]):
        where = path.relative_to(PACKAGE).as_posix()
        if where.startswith(NOT_COUNTED):
            continue
        for text in _texts(path):
            for match in tool.finditer(text.value):
                counts = found.setdefault(where, {})
                counts[match.group(1)] = counts.get(match.group(1), 0) + 1
    assert found == TOOL_NAMES_LEFT
