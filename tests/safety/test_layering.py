"""The layers of docs/architecture.md, held from the source, every rule in one place:

* each package imports only the packages below it (``TYPE_CHECKING`` and function-level imports included),
  the table of layers knows every package of ours, and the simulated robot imports nothing of the server;
* only ``wire/``, ``client/`` and the simulated bridge import ``wire/``; ``robot/`` reads no rosbridge frame;
  no module outside ``client/`` asks which bridge it is (what detection saw), it asks ``BridgeCapabilities``;
  no module outside ``client/`` reads a client's ``session`` or what only a session holds (it asks the
  client: ``session_facts``, ``ordering_known(timeout)``, ``calls_share_connection``, ``capabilities()``);
* Pillow is imported only where pictures are drawn, and ``robot/`` loads no picture code at run time;
* ``robot/``'s texts name no MCP tool but the listed ones (what to try next is worded at the MCP edge,
  ``server/advice.py``);
* the acting layer, the safety seam and the safety package each import first in a fresh interpreter (no
  import cycle).

Every file is read once (``ast``) by one scanner, so a rule broken anywhere in ``src`` fails here with the
file and line; each rule is a function of the files it reads, and each is shown catching what it forbids on a
few lines written for it (the tests after ``--- each rule can fail``).
"""

from __future__ import annotations

import ast
import functools
import re
import subprocess
import sys
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

import rosbridge_mcp_server
from rosbridge_mcp_server.catalogue import ALL_TOOL_NAMES

PACKAGE = Path(rosbridge_mcp_server.__file__).parent
ROOT = "rosbridge_mcp_server"

# --- the one scanner --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Source:
    """One module of ours, parsed."""

    where: str  #: its path in the package, e.g. ``robot/acting.py``
    tree: ast.Module

    @property
    def top(self) -> str:
        """The top-level package (or module) of ours it belongs to: ``robot``, ``errors``, ``__init__``."""
        return self.where.split("/")[0].removesuffix(".py")

    @property
    def module(self) -> str:
        """Its dotted name, ``rosbridge_mcp_server.robot.acting`` (a package's ``__init__``: the package)."""
        parts = [ROOT, *self.where.removesuffix(".py").split("/")]
        return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def source(where: str, text: str) -> Source:
    """*text* as if it were the module at *where* (for showing a rule catch what it forbids)."""
    return Source(where, ast.parse(text, filename=where))


#: A scan of one module: (line, what it found) for each finding.
Scan = Callable[[ast.Module], Iterator[tuple[int, str]]]


@functools.cache
def package_sources() -> tuple[Source, ...]:
    """Every module of ours, each parsed once."""
    return tuple(
        source(path.relative_to(PACKAGE).as_posix(), path.read_text(encoding="utf-8"))
        for path in sorted(PACKAGE.rglob("*.py"))
    )


def _is_our_module(name: str) -> bool:
    parts = name.split(".")
    if parts[0] != ROOT:
        return False
    path = PACKAGE.joinpath(*parts[1:])
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def imports(src: Source) -> Iterator[tuple[int, str]]:
    """Every module *src* imports, with its line: relative imports made absolute, and the modules of ours that
    ``from package import module`` names (``from rosbridge_mcp_server import wire`` imports ``…wire``)."""
    package = src.module if src.where.endswith("__init__.py") else src.module.rpartition(".")[0]
    for node in ast.walk(src.tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                module = ".".join([*base, *([node.module] if node.module else [])])
            else:
                assert node.module is not None
                module = node.module
            yield node.lineno, module
            for alias in node.names:
                if _is_our_module(f"{module}.{alias.name}"):
                    yield node.lineno, f"{module}.{alias.name}"


def ours(module: str) -> str | None:
    """The top-level package of ours that *module* names, or ``None`` for a third-party or standard one."""
    parts = module.split(".")
    if parts[0] != ROOT:
        return None
    return parts[1] if len(parts) > 1 else "__init__"


# --- the layers -------------------------------------------------------------------------------------------

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
SHARED = frozenset({"errors", "catalogue", "config", "mcapfile"})
#: What the simulated robot may share with the server: the MCAP file format read within a budget (pure file
#: reading, importing nothing of ours), so ``--play`` refuses the hostile files ``read_recording`` refuses.
SIMULATOR_SHARES = frozenset({"mcapfile"})
#: The simulated robot stands beside the layers; only the command (``--demo``) starts it.
SIMULATOR = "sim"
#: What the package holds besides: its own ``__init__`` and ``python -m``.
BESIDE = frozenset({"__init__", "__main__"})


def _layer_of(package: str) -> int | None:
    return next((row for row, names in enumerate(LAYERS) if package in names), None)


def upward_imports(sources: Iterable[Source]) -> list[str]:
    """Imports of a package on the same row or a higher one (the simulated robot's allowed to ``cli/``)."""
    offenders = []
    for src in sources:
        row = _layer_of(src.top)
        if row is None:
            continue
        for line, module in imports(src):
            target = ours(module)
            if target is None or target == src.top or target in SHARED or target == "__init__":
                continue
            if target == SIMULATOR and src.top == "cli":
                continue
            target_row = _layer_of(target)
            if target_row is None or target_row >= row:
                offenders.append(f"{src.where}:{line} imports {module}")
    return offenders


def unplaced(sources: Iterable[Source]) -> list[str]:
    """Packages of ours the table does not place, and names it places that are no package of ours."""
    tops = {src.top for src in sources}
    placed = set().union(*LAYERS) | SHARED | BESIDE | {SIMULATOR}
    return [f"not placed: {name}" for name in sorted(tops - placed)] + [
        f"placed but absent: {name}" for name in sorted(placed - tops)
    ]


def simulator_imports(sources: Iterable[Source]) -> list[str]:
    """Modules of ours, outside ``sim/``, that the simulated robot imports."""
    return [
        f"{src.where}:{line} imports {module}"
        for src in sources
        if src.top == SIMULATOR
        for line, module in imports(src)
        if ours(module) not in {None, SIMULATOR, *SIMULATOR_SHARES}
    ]


def test_each_layer_imports_only_the_layers_below_it_and_the_shared_modules() -> None:
    """No upward arrow and no sideways one (``pictures/`` ↔ ``safety/``), ``TYPE_CHECKING`` included."""
    assert upward_imports(package_sources()) == []


def test_the_layer_table_knows_every_package_of_ours() -> None:
    """A new package is placed in the table (or among the shared modules, or the simulated robot's) before
    its imports go unchecked; a name the table places is a package of ours (a stale one would let a future
    module of that name go unchecked)."""
    assert unplaced(package_sources()) == []


def test_the_simulated_robot_imports_nothing_of_the_server() -> None:
    """``sim/`` shares nothing with the layers: it imports no module of ours but the MCAP file reader, which
    imports nothing of ours outside itself."""
    assert simulator_imports(package_sources()) == []
    shared = [src for src in package_sources() if src.top in SIMULATOR_SHARES]
    assert shared
    outside = [
        f"{src.where}:{line} imports {module}"
        for src in shared
        for line, module in imports(src)
        if ours(module) not in {None, src.top}
    ]
    assert outside == []


# --- the protocol stays in wire/ and client/ ----------------------------------------------------------------

#: The packages that speak the protocol: the protocol itself, the client, and the simulated robot (a bridge).
PROTOCOL_PACKAGES = frozenset({"wire", "client", "sim"})

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


def wire_imports(sources: Iterable[Source]) -> list[str]:
    """Imports of ``wire/`` outside the packages that speak the protocol."""
    return [
        f"{src.where}:{line} imports {module}"
        for src in sources
        if src.top not in PROTOCOL_PACKAGES
        for line, module in imports(src)
        if ours(module) == "wire"
    ]


#: The client's public face: what ``rosbridge_mcp_server.client`` exports. ``robot/`` imports these names and
#: nothing else of the client, so the connections (``BridgeSession``, the lanes) never reach the domain.
CLIENT_FACE = "rosbridge_mcp_server.client"
#: Names that are connections, never part of that face.
CONNECTIONS = frozenset({"Session", "BridgeSession", "GoalLane", "GoalLanes", "Connection", "LanePool"})


def client_reaches(sources: Iterable[Source], face: Iterable[str]) -> list[str]:
    """Imports by ``robot/`` of a client submodule, or of a name the client's face does not export."""
    exported = frozenset(face)
    found = []
    for src in sources:
        if src.top != "robot":
            continue
        for node in ast.walk(src.tree):
            if not isinstance(node, ast.ImportFrom | ast.Import):
                continue
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names if ours(alias.name) == "client"]
                found += [f"{src.where}:{node.lineno} imports {name}" for name in names]
            elif node.module is not None and ours(node.module) == "client":
                if node.module != CLIENT_FACE:
                    found.append(f"{src.where}:{node.lineno} imports {node.module}")
                    continue
                found += [
                    f"{src.where}:{node.lineno} imports {CLIENT_FACE}.{alias.name}"
                    for alias in node.names
                    if alias.name not in exported
                ]
    return found


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
                yield word.lineno, str(word.value)


def frame_reads(sources: Iterable[Source]) -> list[str]:
    """Op names or the ``op`` key compared or looked up in ``robot/``."""
    return [
        f"{src.where}:{line} reads {word!r}"
        for src in sources
        if src.top == "robot"
        for line, word in _frame_reads(src.tree)
    ]


def _brand_questions(tree: ast.Module) -> Iterator[tuple[int, str]]:
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute):
            continue
        owner = node.value
        owner_name = owner.attr if isinstance(owner, ast.Attribute) else getattr(owner, "id", "")
        if node.attr in INFO_READINGS or (node.attr in OBSERVATIONS and "info" in owner_name):
            yield node.lineno, f"{owner_name}.{node.attr}"


def reads(sources: Iterable[Source], scan: Scan, *, outside: frozenset[str]) -> list[str]:
    """``where:line reads what`` for each finding of *scan* in the modules outside the packages *outside*."""
    return [
        f"{src.where}:{line} reads {what}"
        for src in sources
        if src.top not in outside
        for line, what in scan(src.tree)
    ]


def brand_questions(sources: Iterable[Source]) -> list[str]:
    """What detection saw, read outside the packages that speak the protocol."""
    return reads(sources, _brand_questions, outside=PROTOCOL_PACKAGES)


#: What a client's ``BridgeSession`` holds beyond the facts a watcher reads (``SessionFacts``): how calls
#: are routed on its connection. Outside client/ these are asked of the client itself:
#: ``ordering_known(timeout)``, ``calls_share_connection``, ``await capabilities()``, ``session_facts``.
SESSION_INTERNALS = frozenset(
    {
        "lanes_by_default",
        "ordering_known",
        "spread_calls",
        "send_service_timeout",
        "learn_cancel_by_owner_only",
    }
)


def _is_client(node: ast.expr) -> bool:
    """*node* names a ``RosbridgeClient`` as we spell one: ``client``, ``self._client``, ``ros``."""
    name = node.attr if isinstance(node, ast.Attribute) else getattr(node, "id", "")
    return name == "ros" or name.lstrip("_").endswith("client")


def _session_reads(tree: ast.Module) -> Iterator[tuple[int, str]]:
    called = {id(node.func) for node in ast.walk(tree) if isinstance(node, ast.Call)}
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute):
            continue
        if node.attr == "session" and _is_client(node.value):
            found.append((node.lineno, "client.session"))
        elif node.attr in SESSION_INTERNALS and id(node) not in called:
            # ``client.ordering_known(5.0)`` is the client's face; ``session.ordering_known.wait()`` is not.
            found.append((node.lineno, f"session.{node.attr}"))
    yield from sorted(found)


def session_reads(sources: Iterable[Source]) -> list[str]:
    """A client's session, or what only a session holds, read outside the client."""
    return reads(sources, _session_reads, outside=frozenset({"client"}))


def test_nothing_above_the_client_imports_the_wire_protocol() -> None:
    """Only wire/, client/ and the simulated bridge import ``rosbridge_mcp_server.wire``."""
    assert wire_imports(package_sources()) == []


def test_the_domain_never_reads_a_rosbridge_frame() -> None:
    """robot/ compares or looks up no op name nor the ``op`` key: what the bridge said comes typed."""
    assert frame_reads(package_sources()) == []


def test_the_domain_imports_only_the_clients_public_face() -> None:
    """robot/ imports names ``rosbridge_mcp_server.client`` exports, no client submodule; the face exports no
    connection (``BridgeSession``, the goal lanes): goals are asked of the client through ``GoalHandle``."""
    from rosbridge_mcp_server import client

    assert CONNECTIONS.isdisjoint(client.__all__)
    assert client_reaches(package_sources(), client.__all__) == []


def test_no_module_outside_the_client_asks_which_bridge_it_is() -> None:
    """Outside client/ (and wire/, sim/) what a bridge does is asked of ``BridgeCapabilities``, never read off
    what detection saw."""
    assert brand_questions(package_sources()) == []


def test_no_module_outside_the_client_reads_its_session() -> None:
    """Outside client/ the current session is asked of the client's face (``session_facts``,
    ``ordering_known(timeout)``, ``calls_share_connection``, ``capabilities()``), never read off
    ``client.session``."""
    assert session_reads(package_sources()) == []


# --- the wire is sans-I/O; one module moves bytes ----------------------------------------------------------

#: What a sans-I/O module never imports: a loop, a socket, a thread.
IO_MODULES = frozenset({"asyncio", "websockets", "socket", "ssl", "selectors", "threading", "trio", "anyio"})
#: The one module of the server that wires in ``websockets`` (the client's transport seam).
WEBSOCKET_MODULE = "client/transport.py"


def io_imports(sources: Iterable[Source]) -> list[str]:
    """Imports of I/O in ``wire/``, and of ``websockets`` in the server outside its transport module."""
    return [
        f"{src.where}:{line} imports {module}"
        for src in sources
        if src.top != SIMULATOR
        for line, module in imports(src)
        if (src.top == "wire" and module.split(".")[0] in IO_MODULES)
        or (module.split(".")[0] == "websockets" and src.where != WEBSOCKET_MODULE)
    ]


def test_the_wire_does_no_io_and_one_module_wires_in_websockets() -> None:
    """wire/ (the conversation included) imports no loop, socket or thread; only ``client/transport.py``
    imports ``websockets``."""
    assert io_imports(package_sources()) == []


# --- settings: one owner ---------------------------------------------------------------------------------

#: The packages that own settings: ``config/`` reads them (flag > environment > file > default), ``cli/``
#: hands it the process's environment.
SETTING_OWNERS = frozenset({"config", "cli"})
#: A variable a lookup by name reads as a setting: ours, and the platform's folders.
_SETTING_VARIABLE = re.compile(
    r"^(ROSBRIDGE_[A-Z0-9_]*|XDG_[A-Z0-9_]+|LOCALAPPDATA|APPDATA|USERPROFILE|HOME)$"
)
_ENVIRONMENT = ("environ", "environb", "getenv", "getenvb")


def _environment_reads(tree: ast.Module) -> Iterator[tuple[int, str]]:
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr in _ENVIRONMENT:
            yield node.lineno, f"os.{node.attr}"
        elif isinstance(node, ast.ImportFrom) and node.module == "os":
            for alias in node.names:
                if alias.name in _ENVIRONMENT:
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
                    yield key.lineno, f"the variable {key.value}"


def environment_reads(sources: Iterable[Source]) -> list[str]:
    """Settings read from the environment outside ``config/`` and ``cli/``."""
    return reads(sources, _environment_reads, outside=SETTING_OWNERS)


def test_no_module_outside_config_and_cli_reads_the_environment() -> None:
    """Configuration has one owner: ``config/`` chooses each setting (the recording folder's default, the
    console's runtime folder included) from the environment ``cli/`` gives it, and passes the value down."""
    assert environment_reads(package_sources()) == []


# --- pictures: Pillow's place -------------------------------------------------------------------------------


def pillow_imports(sources: Iterable[Source]) -> list[str]:
    """Imports of Pillow outside ``pictures/`` and the simulated robot."""
    return [
        f"{src.where}:{line}"
        for src in sources
        if src.top not in {"pictures", SIMULATOR}
        for line, module in imports(src)
        if module == "PIL" or module.startswith("PIL.")
    ]


def test_pillow_is_imported_only_by_the_pictures_and_the_simulated_robot() -> None:
    """``robot/`` reads grids, scans and frames as data; drawing and encoding them is ``pictures/``'s."""
    assert pillow_imports(package_sources()) == []


# --- in a fresh interpreter ---------------------------------------------------------------------------------

#: The picture code a fresh interpreter reports loaded: Pillow's modules and these.
PICTURES = f"{ROOT}.pictures"


def loaded_picture_code(modules: list[str]) -> str:
    """Import *modules* in a fresh interpreter; the picture modules it then holds, as it prints them."""
    program = (
        "import importlib, sys\n"
        f"for name in {modules!r}: importlib.import_module(name)\n"
        f"print(sorted(m for m in sys.modules if m.split('.')[0] == 'PIL' or m.startswith({PICTURES!r})))"
    )
    done = subprocess.run(
        [sys.executable, "-c", program], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def imports_first(module: str, path: Path | None = None) -> subprocess.CompletedProcess[str]:
    """``import module`` as the first thing a fresh interpreter does (with *path* first on ``sys.path``)."""
    program = (
        f"import sys; sys.path.insert(0, {str(path)!r}); import {module}" if path else f"import {module}"
    )
    return subprocess.run(
        [sys.executable, "-c", program], capture_output=True, text=True, timeout=60, check=False
    )


def test_the_domain_loads_neither_pictures_nor_pillow() -> None:
    """Every module of ``robot/`` imported in a fresh interpreter leaves Pillow and ``pictures/`` unloaded."""
    modules = [src.module for src in package_sources() if src.top == "robot"]
    assert len(modules) > 30  # the walk found robot/'s modules, so the empty list below means something
    assert loaded_picture_code(modules) == "[]"


@pytest.mark.parametrize(
    "module",
    [
        "rosbridge_mcp_server.robot.acting",
        "rosbridge_mcp_server.robot.approval",
        "rosbridge_mcp_server.safety",
        "rosbridge_mcp_server.safety.guard",
    ],
)
def test_the_module_imports_first_in_a_fresh_interpreter(module: str) -> None:
    """No import cycle bites whichever of the safety seam, the acting layer and the safety package a program
    imports first."""
    done = imports_first(module)
    assert done.returncode == 0, done.stderr


# --- robot/ names no tool -----------------------------------------------------------------------------------

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


def _texts(tree: ast.Module) -> Iterator[str]:
    """The string constants of *tree* that can reach a reader: not docstrings, not ``__all__``."""
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
            yield node.value


def tool_names(sources: Iterable[Source]) -> dict[str, dict[str, int]]:
    """The MCP tools ``robot/`` and ``errors.py`` name in their texts, by file, and how often each."""
    names = "|".join(sorted(ALL_TOOL_NAMES, key=len, reverse=True))
    tool = re.compile(rf"(?<![\w/])({names})(?![\w/])")
    found: dict[str, dict[str, int]] = {}
    for src in sources:
        if src.top not in {"robot", "errors"} or src.where.startswith(NOT_COUNTED):
            continue
        for text in _texts(src.tree):
            for match in tool.finditer(text):
                counts = found.setdefault(src.where, {})
                counts[match.group(1)] = counts.get(match.group(1), 0) + 1
    return found


def test_the_domain_names_no_mcp_tool_but_the_listed_ones() -> None:
    """robot/ and errors.py say what went wrong; the tools to call next are named at the MCP edge."""
    assert tool_names(package_sources()) == TOOL_NAMES_LEFT


# --- each rule can fail -------------------------------------------------------------------------------------


def test_the_scanner_reads_every_package_of_ours() -> None:
    """The rules above read every layer, the shared modules and the simulated robot: an empty answer of theirs
    is not an empty scan."""
    tops = {src.top for src in package_sources()}
    assert tops >= set().union(*LAYERS) | SHARED | {SIMULATOR}
    assert len(package_sources()) > 150


def test_the_layer_check_catches_an_upward_or_sideways_import() -> None:
    """Up a layer (at run time, under ``TYPE_CHECKING``, in a function, as ``from package import module``),
    sideways between ``safety/`` and ``pictures/``, into the simulated robot from any layer but ``cli/``."""
    robot = source(
        "robot/example.py",
        "from typing import TYPE_CHECKING\n"
        "from rosbridge_mcp_server.client import RosbridgeClient\n"
        "from rosbridge_mcp_server.errors import RosbridgeError\n"
        "from rosbridge_mcp_server import wire, tools\n"
        "if TYPE_CHECKING:\n    from rosbridge_mcp_server.safety import PolicyGuard\n"
        "def later():\n    import rosbridge_mcp_server.server.app\n",
    )
    assert upward_imports([robot]) == [
        "robot/example.py:4 imports rosbridge_mcp_server.tools",
        "robot/example.py:6 imports rosbridge_mcp_server.safety",
        "robot/example.py:8 imports rosbridge_mcp_server.server.app",
    ]
    sideways = source("pictures/example.py", "from rosbridge_mcp_server.safety.guard import PolicyGuard\n")
    assert upward_imports([sideways]) == ["pictures/example.py:1 imports rosbridge_mcp_server.safety.guard"]
    simulated = "from rosbridge_mcp_server.sim import SimulatedRobot\n"
    assert upward_imports([source("cli/example.py", simulated)]) == []
    assert upward_imports([source("tools/example.py", simulated)]) == [
        "tools/example.py:1 imports rosbridge_mcp_server.sim"
    ]


def test_the_table_check_catches_an_unplaced_package_and_a_stale_name() -> None:
    sources = [*package_sources(), source("planner/route.py", "")]
    assert unplaced(sources) == ["not placed: planner"]
    assert unplaced(src for src in package_sources() if src.top != "pictures") == [
        "placed but absent: pictures"
    ]


def test_the_simulator_check_catches_an_import_of_ours() -> None:
    """A relative import within ``sim/`` is its own; the wire's protocol, absolute or relative, is not."""
    sim = source(
        "sim/interfaces/example.py",
        "from .specs import MessageSpec\n"
        "from rosbridge_mcp_server.wire import cbor\n"
        "from ...wire import ids\n",
    )
    assert simulator_imports([sim]) == [
        "sim/interfaces/example.py:2 imports rosbridge_mcp_server.wire",
        "sim/interfaces/example.py:2 imports rosbridge_mcp_server.wire.cbor",
        "sim/interfaces/example.py:3 imports rosbridge_mcp_server.wire",
    ]


def test_the_wire_check_catches_an_import_above_the_client() -> None:
    text = "from rosbridge_mcp_server import wire\nfrom rosbridge_mcp_server.wire.goals import GoalEnded\n"
    assert wire_imports([source("robot/example.py", text), source("client/example.py", text)]) == [
        "robot/example.py:1 imports rosbridge_mcp_server.wire",
        "robot/example.py:2 imports rosbridge_mcp_server.wire.goals",
    ]


def test_the_io_check_catches_a_loop_in_the_wire_and_a_second_websockets_user() -> None:
    wire = source("wire/example.py", "import asyncio\nfrom websockets.asyncio.client import connect\n")
    client = source("client/example.py", "from websockets.exceptions import ConnectionClosed\n")
    transport = source(WEBSOCKET_MODULE, "from websockets.asyncio.client import connect\n")
    assert io_imports([wire, client, transport]) == [
        "wire/example.py:1 imports asyncio",
        "wire/example.py:2 imports websockets.asyncio.client",
        "client/example.py:1 imports websockets.exceptions",
    ]


def test_the_client_face_check_catches_a_submodule_and_an_unexported_name() -> None:
    text = (
        "from rosbridge_mcp_server.client.session import BridgeSession\n"
        "from rosbridge_mcp_server.client import Dialect, GoalLane\n"
        "import rosbridge_mcp_server.client.goals\n"
    )
    found = client_reaches([source("robot/example.py", text), source("tools/example.py", text)], ["Dialect"])
    assert found == [
        "robot/example.py:1 imports rosbridge_mcp_server.client.session",
        "robot/example.py:2 imports rosbridge_mcp_server.client.GoalLane",
        "robot/example.py:3 imports rosbridge_mcp_server.client.goals",
    ]


def test_the_session_check_catches_what_cli_check_read_before_issue_38() -> None:
    """The reads ``cli/check.py`` made of the session; a call of the face and ``robot.session`` pass."""
    text = (
        "session = client.session\n"
        "await asyncio.wait_for(session.ordering_known.wait(), 5.0)\n"
        "lanes = session.lanes_by_default\n"
        "caps = self._client.session.capabilities\n"
        "await client.ordering_known(5.0)\n"
        "gate = robot.session.gate\n"
    )
    assert session_reads([source("cli/example.py", text)]) == [
        "cli/example.py:1 reads client.session",
        "cli/example.py:2 reads session.ordering_known",
        "cli/example.py:3 reads session.lanes_by_default",
        "cli/example.py:4 reads client.session",
    ]
    assert session_reads([source("client/example.py", text)]) == []


def test_the_frame_check_catches_a_frame_read() -> None:
    """The check sees the reads robot/goals/ros2.py (now running.py) did before the typed events."""
    tree = ast.parse(
        'if op == "action_result":\n    x = frame.get("values")\nelif frame["op"] == "status": pass'
    )
    assert [word for _, word in _frame_reads(tree)] == ["action_result", "op"]
    assert frame_reads([Source("robot/example.py", tree)]) == [
        "robot/example.py:1 reads 'action_result'",
        "robot/example.py:3 reads 'op'",
    ]


@pytest.mark.parametrize("text", ["info.status_replies", "session.info.goals_may_block"])
def test_the_brand_check_catches_a_question_about_the_bridge(text: str) -> None:
    """The check sees a question about which bridge it is, outside the client only."""
    assert list(_brand_questions(ast.parse(text)))
    assert brand_questions([source("tools/example.py", text)])
    assert brand_questions([source("client/example.py", text)]) == []


def test_the_pillow_check_catches_an_import_outside_the_pictures() -> None:
    text = "from PIL import Image\nimport PIL.ImageDraw\n"
    assert pillow_imports([source("robot/example.py", text), source("pictures/example.py", text)]) == [
        "robot/example.py:1",
        "robot/example.py:2",
    ]


def test_the_fresh_interpreter_sees_picture_code_loaded() -> None:
    """The probe the domain passes does report the picture code a module loads."""
    assert "rosbridge_mcp_server.pictures" in loaded_picture_code(["rosbridge_mcp_server.pictures"])


def test_the_fresh_interpreter_catches_an_import_cycle(tmp_path: Path) -> None:
    """Two modules importing a name of each other fail in a fresh interpreter whichever comes first."""
    (tmp_path / "cycle_a.py").write_text("from cycle_b import B\nA = 1\n", encoding="utf-8")
    (tmp_path / "cycle_b.py").write_text("from cycle_a import A\nB = 1\n", encoding="utf-8")
    done = imports_first("cycle_a", tmp_path)
    assert done.returncode != 0
    assert "ImportError" in done.stderr, done.stderr


def test_the_tool_check_counts_a_tool_named_in_a_text() -> None:
    """A text a reader sees counts; a docstring, ``__all__`` and robot/goals/ do not."""
    text = (
        '"""Call list_topics to see."""\n'
        '__all__ = ["list_topics"]\n'
        'def f():\n    raise ValueError("no such topic: call list_topics, then stop_robot")\n'
    )
    sources = [source("robot/example.py", text), source("robot/goals/example.py", text)]
    assert tool_names(sources) == {"robot/example.py": {"list_topics": 1, "stop_robot": 1}}


@pytest.mark.parametrize(
    "text",
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
def test_the_environment_check_catches_a_read(text: str) -> None:
    """The check sees each way a module read a setting from the environment itself, outside config/ only."""
    assert list(_environment_reads(ast.parse(text)))
    assert environment_reads([source("robot/example.py", text)])
    assert environment_reads([source("config/example.py", text)]) == []
