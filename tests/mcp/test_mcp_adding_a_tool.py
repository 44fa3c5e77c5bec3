"""Adding a tool (docs/architecture.md, "Adding a tool"): what an acting tool must say is asked where it is
written, and nothing falls into a silent default."""

from __future__ import annotations

import ast
import io
import json
from pathlib import Path
from types import ModuleType

import pytest
from mcp_harness import guarded, open_session
from pydantic import BaseModel

import rosbridge_mcp_server.server
from rosbridge_mcp_server.catalogue import ALL_TOOL_NAMES, Entry
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import load_config
from rosbridge_mcp_server.safety import Audit, Policy, PolicyGuard
from rosbridge_mcp_server.server import build_server
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.tools import TOOL_MODULES, check_module
from rosbridge_mcp_server.tools.base import ACTS_ON_ROBOT, READS_ROBOT, LongWork, ToolSpec


class _Answer(BaseModel):
    done: bool


def test_an_acting_tool_that_does_not_say_what_it_acts_on_fails_where_its_spec_is_written() -> None:
    """A forgotten ``acts_on`` is a TypeError naming the tool when the module is imported, and a reading tool
    cannot claim one."""
    with pytest.raises(TypeError, match=r"new_tool: an acting tool's ToolSpec must say acts_on="):
        ToolSpec(name="new_tool", title="New", description="d", hints=ACTS_ON_ROBOT, output=_Answer)
    with pytest.raises(TypeError, match=r"new_reader: a reading tool acts on nothing"):
        ToolSpec(
            name="new_reader",
            title="New",
            description="d",
            hints=READS_ROBOT,
            output=_Answer,
            acts_on="topic",
        )


def test_every_acting_tool_says_what_it_acts_on() -> None:
    """Every tool that is not read-only says what it acts on the robot through, or (record, which subscribes
    and writes a file) what it changes instead."""
    acting = {
        m.SPEC.name: m.SPEC.acts_on or m.SPEC.changes for m in TOOL_MODULES if not m.SPEC.hints.read_only
    }
    assert acting == {
        "publish_topic": "topic",
        "publish_service": "service",
        "publish_action": "action",
        "cancel_action": "action",
        "set_parameter": "parameter",
        "stop_robot": "topic",
        "navigate_to": "action",
        "record": "files on the server's host",
        "move_arm": "action",
        "move_gripper": "action",
    }


async def test_a_withheld_tool_is_audited_with_what_it_acts_on(sim_ros2: SimulatedRobot) -> None:
    """A read-only server refusing navigate_to and set_parameter audits each as what it acts on (an action,
    a parameter), not as a topic by default; record, refused too, sends nothing to the robot: no act to
    audit."""
    stream = io.StringIO()
    guard = PolicyGuard(Policy(read_only=True), Audit(stream))
    async with open_session(sim_ros2.url, guard=guard, policy=Policy(read_only=True)) as session:
        await session.error("navigate_to", {"forward": 1.0})
        await session.error("set_parameter", {"name": "/turtlesim:background_r", "value": 1})
        recorded = await session.error("record", {"topics": ["/chatter"], "duration": 1})
    assert "record is not available: this server is read-only" in recorded
    audited = [json.loads(line) for line in stream.getvalue().splitlines()]
    assert [(e["tool"], e["kind"], e["outcome"]) for e in audited] == [
        ("navigate_to", "action", "withheld: read-only"),
        ("set_parameter", "parameter", "withheld: read-only"),
    ]
    assert sim_ros2.world.goals == {}


def test_a_spec_says_what_it_changes_once_and_only_an_acting_tool_stops() -> None:
    """A tool that is not read-only says acts_on or changes, never both; a stop acts on the robot."""
    with pytest.raises(TypeError, match=r"new_tool: an acting tool's ToolSpec must say acts_on=.*not both"):
        ToolSpec(
            name="new_tool",
            title="New",
            description="d",
            hints=ACTS_ON_ROBOT,
            output=_Answer,
            acts_on="topic",
            changes="a file",
        )
    with pytest.raises(TypeError, match=r"new_stop: a tool that stops the robot acts on it"):
        ToolSpec(
            name="new_stop",
            title="New",
            description="d",
            hints=ACTS_ON_ROBOT,
            output=_Answer,
            changes="a file",
            stops=True,
        )


def _tool_names_in(path: Path) -> list[str]:
    """The catalogue's tool names *path* uses as values: string constants (not docstrings or text) and tool
    modules imported by name."""
    tree = ast.parse(path.read_text())
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef)
        and node.body
        and isinstance(node.body[0], ast.Expr)
    }
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and node.value in ALL_TOOL_NAMES and id(node) not in docstrings:
            found.append(f"{path.name}:{node.lineno}: {node.value!r}")
        elif isinstance(node, ast.ImportFrom) and node.module == "rosbridge_mcp_server.tools":
            found += [
                f"{path.name}:{node.lineno}: import {a.name}" for a in node.names if a.name in ALL_TOOL_NAMES
            ]
    return found


def test_the_server_decides_by_what_a_spec_declares_never_by_a_tool_name(tmp_path: Path) -> None:
    """No module of server/ holds a tool's name as a value to compare, look up or import: the stop, the
    fleet's fan-out, what a session keeps in the background, what acts and which calls run as tasks are read
    from the tool's spec."""
    server = Path(rosbridge_mcp_server.server.__file__).parent
    named = [hit for path in sorted(server.glob("*.py")) for hit in _tool_names_in(path)]
    assert named == []
    # The check sees a name where one is used (it caught app.py's, fleet.py's, tasks.py's), and not in text.
    by_name = tmp_path / "tasks.py"
    by_name.write_text(
        '"""Long work is record."""\n'
        "from rosbridge_mcp_server.tools import stop_robot\n"
        '_LONG = ("navigate_to", "a navigate_to call")\n'
    )
    assert _tool_names_in(by_name) == ["tasks.py:2: import stop_robot", "tasks.py:3: 'navigate_to'"]


def test_which_calls_may_run_as_tasks_is_on_the_spec() -> None:
    """Long work (run as an MCP task) is declared on the spec: when it is, and what cancelling it ends."""
    long = {m.SPEC.name: m.SPEC.long_work for m in TOOL_MODULES if m.SPEC.long_work is not None}
    assert {name: (w.given, w.unless) for name, w in long.items()} == {
        "publish_topic": ("duration", None),
        "publish_action": (None, None),
        "subscribe_topic": ("duration", None),
        "navigate_to": (None, None),
        "record": (None, "stop"),
        "plot_topic": (None, None),
    }
    assert long["publish_topic"].applies({"duration": 2})
    assert not long["publish_topic"].applies({})
    assert not long["publish_topic"].applies({"duration": None})
    assert long["record"].applies({"topics": ["/chatter"]})
    assert not long["record"].applies({"stop": True})
    assert long["plot_topic"].cancelled == "its reading ended"


def test_long_work_that_names_an_argument_the_tool_does_not_take_fails_at_import() -> None:
    """A ``given``/``unless`` misspelt would make every call a plain one (or every call a task), silently:
    the catalogue's check names it instead."""

    async def run(ctx: object, topic: str, duration: float | None = None) -> None: ...

    module = ModuleType("count_nodes")
    module.run = run  # type: ignore[attr-defined]
    module.SPEC = ToolSpec(  # type: ignore[attr-defined]
        name="count_nodes",
        title="Count",
        description="d",
        hints=READS_ROBOT,
        output=_Answer,
        long_work=LongWork(given="duration"),
    )
    check_module(Entry("count_nodes", "graph", acts=False), module)
    module.SPEC = ToolSpec(  # type: ignore[attr-defined]
        name="count_nodes",
        title="Count",
        description="d",
        hints=READS_ROBOT,
        output=_Answer,
        long_work=LongWork(given="seconds"),
    )
    with pytest.raises(ImportError, match=r"count_nodes's long_work names 'seconds', which its run does not"):
        check_module(Entry("count_nodes", "graph", acts=False), module)


@pytest.mark.parametrize(
    ("tools", "learns_types", "keeps_log"),
    [
        ("list_topics", False, False),
        ("list_services", True, False),
        ("diagnose", False, True),
        ("all", True, True),
    ],
)
def test_what_a_session_keeps_in_the_background_is_what_the_served_specs_need(
    tools: str, learns_types: bool, keeps_log: bool
) -> None:
    """The service-type warm-up and the log keeper start exactly when a served tool's spec needs them."""
    config = load_config({}, url="ws://127.0.0.1:9", tools=tools)
    robot = guarded(RosbridgeClient(config.url), config)
    build_server(robot, config)
    assert (robot.warm_up is not None, robot.logs is not None) == (learns_types, keeps_log)
