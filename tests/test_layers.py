"""The layers of docs/architecture.md, held from the source: each package imports only the packages below it,
Pillow is imported only where pictures are drawn, and ``robot/`` loads no picture code at run time."""

from __future__ import annotations

import ast
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import rosbridge_mcp_server

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
