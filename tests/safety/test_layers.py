"""Layers an import graph does not show: who imports ``wire/``, who reads frames, who tells bridges apart.

Read from the source (``ast``), so a rule broken anywhere in ``src`` fails here with the file and line.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "src" / "rosbridge_mcp_server"

#: The packages that speak the protocol: the protocol itself, the client, and the simulated robot (a bridge).
PROTOCOL_PACKAGES = ("wire", "client", "sim")

#: rosbridge's op names and the envelope's key: a module that compares or looks up one of them reads frames.
FRAME_WORDS = frozenset(
    {
        "op",
        "action_result",
        "action_feedback",
        "service_response",
        "send_action_goal",
        "cancel_action_goal",
        "fragment",
    }
)

#: What detection saw a bridge do (``RosInfo``), and RosInfo's own readings of it: only the client turns these
#: into capabilities; everyone else asks ``BridgeCapabilities``.
OBSERVATIONS = frozenset({"status_replies", "calls_threaded", "goals_threaded", "cancel_owner_only"})
INFO_READINGS = frozenset(
    {
        "goals_may_block",
        "may_be_in_order",
        "one_call_per_connection",
        "honours_service_timeout",
        "has_action_ops",
    }
)


def _modules(*, outside: tuple[str, ...] = (), inside: str | None = None) -> Iterator[tuple[str, ast.Module]]:
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(PACKAGE)
        top = relative.parts[0] if len(relative.parts) > 1 else ""
        if top in outside or (inside is not None and top != inside):
            continue
        yield str(relative), ast.parse(path.read_text(encoding="utf-8"), filename=str(path))


def _imported(tree: ast.Module) -> Iterator[tuple[int, str]]:
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom) and node.module is not None:
            yield node.lineno, node.module
            for alias in node.names:
                yield node.lineno, f"{node.module}.{alias.name}"


def test_nothing_above_the_client_imports_the_wire_protocol() -> None:
    """Only wire/, client/ and the simulated bridge import ``rosbridge_mcp_server.wire``."""
    found = [
        f"{name}:{line} imports {module}"
        for name, tree in _modules(outside=PROTOCOL_PACKAGES)
        for line, module in _imported(tree)
        if module == "rosbridge_mcp_server.wire" or module.startswith("rosbridge_mcp_server.wire.")
    ]
    assert found == []


def _frame_reads(tree: ast.Module) -> Iterator[tuple[int, str]]:
    for node in ast.walk(tree):
        words: list[ast.expr] = []
        if isinstance(node, ast.Compare):
            words = [node.left, *node.comparators]
        elif isinstance(node, ast.Subscript):
            words = [node.slice]
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get":
            words = node.args[:1]
        for word in words:
            if isinstance(word, ast.Constant) and word.value in FRAME_WORDS:
                yield node.lineno, str(word.value)


def test_the_domain_never_reads_a_rosbridge_frame() -> None:
    """robot/ compares or looks up no op name nor the ``op`` key: what the bridge said comes typed."""
    found = [
        f"{name}:{line} reads {word!r}"
        for name, tree in _modules(inside="robot")
        for line, word in _frame_reads(tree)
    ]
    assert found == []


def test_the_frame_check_catches_a_frame_read() -> None:
    """The check above sees the reads robot/goals/ros2.py did before the typed events."""
    tree = ast.parse(
        'if op == "action_result":\n    x = frame.get("values")\nelif frame["op"] == "status": pass'
    )
    assert [word for _, word in _frame_reads(tree)] == ["action_result", "op"]


def _brand_questions(tree: ast.Module) -> Iterator[tuple[int, str]]:
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute):
            continue
        owner = node.value
        owner_name = owner.attr if isinstance(owner, ast.Attribute) else getattr(owner, "id", "")
        if node.attr in INFO_READINGS or (node.attr in OBSERVATIONS and "info" in owner_name):
            yield node.lineno, f"{owner_name}.{node.attr}"


@pytest.mark.parametrize("source", ["info.status_replies", "session.info.goals_may_block"])
def test_the_brand_check_catches_a_question_about_the_bridge(source: str) -> None:
    """The check below sees a question about which bridge it is."""
    assert list(_brand_questions(ast.parse(source)))


def test_no_module_outside_the_client_asks_which_bridge_it_is() -> None:
    """Outside client/ (and wire/, sim/) what a bridge does is asked of ``BridgeCapabilities``, never read off
    what detection saw."""
    found = [
        f"{name}:{line} reads {what}"
        for name, tree in _modules(outside=PROTOCOL_PACKAGES)
        for line, what in _brand_questions(tree)
    ]
    assert found == []


#: The packages that own settings: ``config/`` reads them (flag > environment > file > default), ``cli/``
#: hands it the process's environment.
SETTING_OWNERS = ("config", "cli")
#: A variable a lookup by name reads as a setting: ours, and the platform's folders.
_SETTING_VARIABLE = re.compile(
    r"^(ROSBRIDGE_[A-Z0-9_]*|XDG_[A-Z0-9_]+|LOCALAPPDATA|APPDATA|USERPROFILE|HOME)$"
)


def _environment_reads(tree: ast.Module) -> Iterator[tuple[int, str]]:
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr in ("environ", "environb", "getenv", "getenvb"):
            yield node.lineno, f"os.{node.attr}"
        elif isinstance(node, ast.ImportFrom) and node.module == "os":
            for alias in node.names:
                if alias.name in ("environ", "environb", "getenv", "getenvb"):
                    yield node.lineno, f"from os import {alias.name}"
        elif isinstance(node, ast.Attribute) and node.attr in ("expanduser", "expandvars"):
            yield node.lineno, node.attr  # HOME (and any variable) behind a path
        elif (
            isinstance(node, ast.Attribute)
            and node.attr == "home"
            and getattr(node.value, "id", "") == "Path"
        ):
            yield node.lineno, "Path.home"
        else:
            looked_up: list[ast.expr] = []
            if isinstance(node, ast.Subscript):
                looked_up = [node.slice]
            elif (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr == "get"
            ):
                looked_up = node.args[:1]
            for key in looked_up:
                if (
                    isinstance(key, ast.Constant)
                    and isinstance(key.value, str)
                    and _SETTING_VARIABLE.match(key.value)
                ):
                    yield node.lineno, f"the variable {key.value}"


@pytest.mark.parametrize(
    "source",
    [
        'base = os.environ.get("XDG_DATA_HOME", "").strip()',  # robot/recording/files.py did
        'named = environ.get("ROSBRIDGE_MCP_RUNTIME_DIR", "").strip()',  # console/address.py did (a mapping)
        'xdg = env["XDG_RUNTIME_DIR"]',
        "from os import getenv",
        'level = os.getenv("LEVEL")',
        'root = Path.home() / ".cache"',
        'folder = Path("~/rec").expanduser()',
    ],
)
def test_the_environment_check_catches_a_read(source: str) -> None:
    """The check below sees each way a module read a setting from the environment itself."""
    assert list(_environment_reads(ast.parse(source)))


def test_no_module_outside_config_and_cli_reads_the_environment() -> None:
    """Configuration has one owner: ``config/`` chooses each setting (the recording folder's default, the
    console's runtime folder included) from the environment ``cli/`` gives it, and passes the value down."""
    found = [
        f"{name}:{line} reads {what}"
        for name, tree in _modules(outside=SETTING_OWNERS)
        for line, what in _environment_reads(tree)
    ]
    assert found == []
