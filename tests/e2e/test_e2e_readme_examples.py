"""Every example of the README's tools table (English and Japanese), run on ``--demo`` as a reader would.

The table is read from README.md and README_ja.md: each `{...}` in a row's examples is one call of that row's
tool; a fragment such as `"rate_hz": 10, "duration": 3` ("add ... to keep it moving") is added to the example
before it. An example both tables show runs once. The calls go to the real command,
``python -m rosbridge_mcp_server --demo --console 0``, over stdio with the SDK's client. A goal id written as
a placeholder (``"…"``) is filled with the id of a goal started first. ``record``'s example records for
30 s, so it and ``read_recording``'s run on a ``--demo`` server of their own. ``list_robots`` is listed only
with several robots, so its examples run on a two-robot server over the same simulated robot;
``navigate_to`` needs a robot with Nav2 and a map, so its examples run on the simulated Nav2 world (the one
``--demo --demo-world nav2`` starts, driven faster than the demo's real speed) with the sample policy's
place (``dock``, examples/robot-policy.toml) in a policy; the arm's tools run on ``--demo --demo-world arm``.
The five servers run at once.
"""

from __future__ import annotations

import asyncio
import json
import os
import re
import sys
import tomllib
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import pytest
from mcp.client.stdio import StdioServerParameters
from mcp.types import CallToolResult, TextContent

from mcp import Client
from rosbridge_mcp_server.sim import SimulatedRobot

ROOT = Path(__file__).resolve().parents[2]
WAIT = 60.0
PLACEHOLDER = "…"
#: Tools that are listed only when the server drives several robots.
FLEET_ONLY = {"list_robots"}
NAV2_ONLY = {"navigate_to"}
#: The arm's tools run on the demo's arm world (``--demo --demo-world arm``).
ARM_ONLY = {"view_arm", "move_arm", "move_gripper"}
#: record's example waits out its 30 s: it and read_recording's (which read its file) run on a demo server of
#: their own, beside the others.
RECORDING = {"record", "read_recording"}
#: The Nav2 world's speeds scaled up (the demo drives at a real robot's 0.4 m/s).
NAV2_SPEED = 8.0
READMES = ("README.md", "README_ja.md")
#: The places of the sample policy the README shows (its ``dock`` is free space on the Nav2 demo's map); the
#: rest of it has a person confirm every motion, and this client has no person.
SAMPLE_PLACES = tomllib.loads((ROOT / "examples" / "robot-policy.toml").read_text("utf-8"))["places"]
NAV2_POLICY = "[places]\n" + "".join(f"{name} = {json.dumps(at)}\n" for name, at in SAMPLE_PLACES.items())


def tools_table(readme: Path) -> dict[str, list[dict[str, Any]]]:
    """The tools table's examples: tool name → the argument objects its row shows."""
    examples: dict[str, list[dict[str, Any]]] = {}
    for line in readme.read_text(encoding="utf-8").splitlines():
        row = re.match(r"^\| `([a-z_]+)` \|(.*)\|(.*)\|\s*$", line)
        if row is None:
            continue
        name, _, shown = row.groups()
        calls: list[dict[str, Any]] = []
        for fragment in re.findall(r"`([^`]+)`", shown):
            if fragment.startswith("{"):
                calls.append(json.loads(fragment))
            elif ":" in fragment and calls:
                calls[-1] = {**calls[-1], **json.loads("{" + fragment + "}")}
        examples[name] = calls
    return examples


def text_of(result: CallToolResult) -> str:
    return "\n".join(block.text for block in result.content if isinstance(block, TextContent))


def _env() -> dict[str, str]:
    return {
        k: v
        for k, v in os.environ.items()
        if not k.startswith("ROSBRIDGE_") or k in ("ROSBRIDGE_MCP_RUNTIME_DIR", "ROSBRIDGE_MCP_RECORD_DIR")
    }


async def run_examples(
    flags: list[str], examples: dict[str, list[dict[str, Any]]]
) -> tuple[list[str], set[str]]:
    """Call every example on the server the flags start; returns what failed (one line each) and the tools
    the server listed."""
    failures: list[str] = []
    parameters = StdioServerParameters(
        command=sys.executable, args=["-m", "rosbridge_mcp_server", *flags], env=_env()
    )
    async with Client(parameters, mode="legacy") as mcp:
        listed = {tool.name for tool in (await mcp.list_tools()).tools}
        for name, calls in examples.items():
            if name not in listed:
                failures.append(f"{name}: not listed by the server")
                continue
            for example in calls:
                arguments = example
                if PLACEHOLDER in json.dumps(example, ensure_ascii=False):
                    arguments = await _filled(mcp, example)
                result = await asyncio.wait_for(mcp.call_tool(name, arguments), WAIT)
                if result.is_error:
                    failures.append(f"{name} {json.dumps(arguments)}: {text_of(result)[:300]}")
    return failures, listed


async def _filled(mcp: Client, arguments: dict[str, Any]) -> dict[str, Any]:
    """A placeholder goal id replaced by the id of a goal of the example's action that is running now (read
    from the goal's first feedback, which publish_action reports as progress)."""
    goal_id: asyncio.Future[str] = asyncio.get_running_loop().create_future()

    async def on_progress(progress: float, total: float | None, message: str | None) -> None:
        found = re.match(r"goal (\S+) feedback", message or "")
        if found and not goal_id.done():
            goal_id.set_result(found.group(1))

    goal = {"order": 40}
    started = asyncio.create_task(
        mcp.call_tool(
            "publish_action",
            {
                "action_name": arguments["action_name"],
                "action_type": "example_interfaces/action/Fibonacci",
                "goal": goal,
                "timeout": 30,
            },
            progress_callback=on_progress,
        )
    )
    running = await asyncio.wait_for(goal_id, WAIT)
    # The goal ends by the example's cancel; its own call's answer is not what this test looks at.
    started.add_done_callback(lambda task: task.cancelled() or task.exception())
    return {key: (running if value == PLACEHOLDER else value) for key, value in arguments.items()}


def distinct_examples(tables: list[dict[str, list[dict[str, Any]]]]) -> dict[str, list[dict[str, Any]]]:
    """The examples of several tables, each call once, in the order of the first table that shows it."""
    merged: dict[str, list[dict[str, Any]]] = {}
    for table in tables:
        for name, calls in table.items():
            seen = merged.setdefault(name, [])
            seen += [call for call in calls if call not in seen]
    return merged


@pytest.mark.timeout(120)  # record's example records for 30 s
async def test_every_tools_table_example_runs_on_the_demo_robot(
    sim_ros2: SimulatedRobot, make_sim: Callable[..., Awaitable[SimulatedRobot]], tmp_path: Path
) -> None:
    """Each example of either table is a call that succeeds on `--demo`; every tool the server lists is in
    both."""
    tables = {readme: tools_table(ROOT / readme) for readme in READMES}
    for readme, table in tables.items():
        assert len(table) >= 21, (readme, sorted(table))
    examples = distinct_examples(list(tables.values()))
    single = {
        name: calls
        for name, calls in examples.items()
        if name not in FLEET_ONLY | NAV2_ONLY | RECORDING | ARM_ONLY
    }
    recording = {name: calls for name, calls in examples.items() if name in RECORDING}
    fleet = {name: calls for name, calls in examples.items() if name in FLEET_ONLY}
    nav2 = {name: calls for name, calls in examples.items() if name in NAV2_ONLY}
    arm = {name: calls for name, calls in examples.items() if name in ARM_ONLY}
    for readme, table in tables.items():
        assert all(table.values()), (readme, [name for name, calls in table.items() if not calls])
    nav2_robot = await make_sim(dialect="ros2", world="nav2")
    nav2_robot.nav2.navigator.speed = NAV2_SPEED
    policy = tmp_path / "policy.toml"
    policy.write_text(NAV2_POLICY, encoding="utf-8")
    robots = ["--robot", f"a={sim_ros2.url}", "--robot", f"b={sim_ros2.url}"]
    runs = await asyncio.gather(
        run_examples(["--demo", "--console", "0"], single),
        run_examples(["--demo"], recording),
        run_examples(robots, fleet),
        run_examples(["--url", nav2_robot.url, "--policy", str(policy)], nav2),
        run_examples(["--demo", "--demo-world", "arm"], arm),
    )
    problems = [failure for failures, _ in runs for failure in failures]
    assert problems == [], "\n".join(problems)
    listed = set().union(*(tools for _, tools in runs))
    for readme, table in tables.items():
        assert listed - set(table) == set(), f"tools missing from {readme}'s table"
