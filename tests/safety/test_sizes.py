"""Sizes: every source file (the simulated robot aside) at most 450 lines and every function at most 60, read
with ``ast``; the exceptions are argued in :data:`ALLOWED`, and what other branches are shrinking right now is
in :data:`PENDING` (issue 38, item 6).

A function's length runs from its first decorator to its last line, nested functions and docstring included;
a nested function is measured on its own too. A key is a file's path under the package (``robot/acting.py``)
or that and a function's qualified name (``cli/commands.py:run``, ``safety/guard.py:Audit.write``).
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "src" / "rosbridge_mcp_server"
MAX_FILE_LINES = 450
MAX_FUNCTION_LINES = 60

#: Exceptions with their reasons: each stays over its limit on purpose.
ALLOWED: dict[str, str] = {}

#: Files and functions other branches are splitting now (issue 38); the lead empties this after merging them.
PENDING: frozenset[str] = frozenset()


def _span(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    first = min([node.lineno, *(decorator.lineno for decorator in node.decorator_list)])
    return (node.end_lineno or node.lineno) - first + 1


def _functions(tree: ast.AST, prefix: str = "") -> list[tuple[str, int]]:
    """(qualified name, lines) of every function and method in *tree*, nested ones too."""
    found: list[tuple[str, int]] = []
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            name = f"{prefix}{node.name}"
            found.append((name, _span(node)))
            found += _functions(node, f"{name}.")
        elif isinstance(node, ast.ClassDef):
            found += _functions(node, f"{prefix}{node.name}.")
        else:
            found += _functions(node, prefix)
    return found


def oversized(sources: dict[str, str]) -> dict[str, int]:
    """Each file (path → text) and function over its limit, with its length."""
    over: dict[str, int] = {}
    for path, text in sources.items():
        lines = len(text.splitlines())
        if lines > MAX_FILE_LINES:
            over[path] = lines
        for name, length in _functions(ast.parse(text, path)):
            if length > MAX_FUNCTION_LINES:
                over[f"{path}:{name}"] = length
    return over


def package_sources() -> dict[str, str]:
    """Every source file of the package but the simulated robot's, by its path under the package."""
    return {
        path.relative_to(PACKAGE).as_posix(): path.read_text(encoding="utf-8")
        for path in sorted(PACKAGE.rglob("*.py"))
        if path.relative_to(PACKAGE).parts[0] != "sim"
    }


def test_every_file_and_function_is_within_its_limit() -> None:
    """No file over 450 lines and no function over 60, but for the argued and the pending ones."""
    over = {
        key: n for key, n in oversized(package_sources()).items() if key not in ALLOWED and key not in PENDING
    }
    assert not over, f"over {MAX_FILE_LINES} lines a file or {MAX_FUNCTION_LINES} a function: {over}"


def test_every_exception_is_still_needed() -> None:
    """An allowed or pending entry that is now within its limit (or gone) is struck from its list."""
    over = oversized(package_sources())
    stale = sorted((ALLOWED.keys() | PENDING) - over.keys())
    assert not stale, f"within the limits now (or renamed): strike them from ALLOWED / PENDING: {stale}"


def test_the_limits_are_not_shrunk_by_the_lists() -> None:
    """Nothing is both allowed and pending, and every allowed entry says why."""
    assert not ALLOWED.keys() & PENDING
    assert all(reason.strip() for reason in ALLOWED.values())


# --- each rule can fail ------------------------------------------------------------------------------------


def _function(name: str, body_lines: int, indent: str = "") -> str:
    body = "".join(f"{indent}    x = {n}\n" for n in range(body_lines))
    return f"{indent}def {name}() -> None:\n{body}"


def test_a_long_function_a_long_method_and_a_long_file_are_seen() -> None:
    """The measure catches a function, a nested function and a decorated method one line over, and a file."""
    method = "class Audit:\n    @property\n" + _function("write", MAX_FUNCTION_LINES - 1, "    ")
    nested = "def outer() -> None:\n" + _function("inner", MAX_FUNCTION_LINES, "    ")
    long_file = "\n" * MAX_FILE_LINES + "x = 1\n"
    sources = {
        "a.py": _function("fits", MAX_FUNCTION_LINES - 1),
        "b.py": _function("run", MAX_FUNCTION_LINES),
        "c.py": method,
        "d.py": nested,
        "e.py": long_file,
    }
    assert oversized(sources) == {
        "b.py:run": MAX_FUNCTION_LINES + 1,
        "c.py:Audit.write": MAX_FUNCTION_LINES + 1,
        "d.py:outer": MAX_FUNCTION_LINES + 2,
        "d.py:outer.inner": MAX_FUNCTION_LINES + 1,
        "e.py": MAX_FILE_LINES + 1,
    }
