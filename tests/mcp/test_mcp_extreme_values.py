"""Every value the schema allows is bounded work: extreme numbers and strings through every parameter.

For every tool the session lists, every parameter whose schema says it is a number, an integer or a string
(and the number and string fields of an object parameter that names them, such as navigate_to's goal, and the
items of a list of strings) gets the extremes a client can send as JSON: ±1e308, ±1e-300, 0, -1, 10^30, 2^63,
the empty string, 100,000 characters, NUL, a path out of the directory. The other arguments are a plausible
call on the simulated Nav2 robot. Each answer must come within :data:`DEADLINE` and be a normal answer or an
``isError`` answer in our words (no "Error executing tool", no pydantic dump, no traceback); the session
answers afterwards.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator, Iterator
from pathlib import Path
from typing import Any

import pytest
from mcp_harness import Session, open_session, text_of

from rosbridge_mcp_server.sim import SimulatedRobot

#: Longest an answer may take: the longest wait a plausible call asks for, plus room for a loaded machine.
DEADLINE = 20.0

NUMBERS: tuple[float | int, ...] = (1e308, -1e308, 1e-300, -1e-300, 0, -1, 10**30, 2**63)
STRINGS = ("", "x" * 100_000, "\0", "../../../../etc/passwd", "/a/" + "b" * 5000)

#: A plausible call of each tool on the simulated Nav2 robot (what a parameter under test does not replace).
#: Waits are kept short so that the extremes, not the waits, decide how long a call takes.
BASE: dict[str, dict[str, Any]] = {
    "get_topic_info": {"topic": "/scan"},
    "publish_topic": {"topic": "/extreme", "message_type": "std_msgs/msg/String", "message": {"data": "x"}},
    "publish_service": {"service": "/map_server/map", "service_type": "nav_msgs/srv/GetMap", "timeout": 2},
    "publish_action": {
        "action_name": "/navigate_to_pose",
        "action_type": "nav2_msgs/action/NavigateToPose",
        "goal": {"pose": {"header": {"frame_id": "map"}, "pose": {"position": {"x": 1.5, "y": 2.0}}}},
        "timeout": 0.5,
    },
    "cancel_action": {"action_name": "/navigate_to_pose"},
    "subscribe_topic": {"topic": "/odom", "timeout": 2},
    "get_image": {"topic": "/camera/image_raw", "timeout": 1},
    "describe_type": {"type_name": "sensor_msgs/msg/LaserScan"},
    "get_node_info": {"node": "/amcl"},
    "get_parameter": {"name": "/amcl:use_sim_time"},
    "set_parameter": {"name": "/amcl:max_particles", "value": 2000},
    "get_transform": {"target_frame": "map", "source_frame": "base_link", "timeout": 2},
    "view_map": {"timeout": 2},
    "view_scan": {"timeout": 2},
    "plot_topic": {"series": ["/odom twist.twist.linear.x"], "duration": 0.5},
    "navigate_to": {"goal": {"x": 1.5, "y": 2.0}, "timeout": 0.5},
    "record": {"topics": ["/odom"], "duration": 0.3},
    "read_recording": {"file": "base.mcap", "mode": "messages"},
}
#: Varying a relative move (forward, left, turn) leaves the base call's goal out: the two exclude each other.
WITHOUT = {
    ("navigate_to", "forward"): "goal",
    ("navigate_to", "left"): "goal",
    ("navigate_to", "turn"): "goal",
}


def _kinds(schema: dict[str, Any]) -> set[str]:
    kinds = schema.get("type")
    found = set(kinds) if isinstance(kinds, list) else {kinds} if kinds else set()
    for option in schema.get("anyOf", []):
        found |= _kinds(option)
    return found


def _values(schema: dict[str, Any]) -> Iterator[Any]:
    kinds = _kinds(schema)
    if "enum" in schema:
        return
    if kinds & {"number", "integer"}:
        yield from NUMBERS
    if "string" in kinds:
        yield from STRINGS
    if "array" in kinds and _kinds(schema.get("items", {})) == {"string"}:
        yield from ([value] for value in STRINGS)


def extreme_calls(name: str, schema: dict[str, Any]) -> Iterator[tuple[str, dict[str, Any]]]:
    """(what is varied, arguments) for every extreme value of every parameter of tool *name*."""
    base = BASE.get(name, {})
    for key, prop in schema.get("properties", {}).items():
        for value in _values(prop):
            arguments = {k: v for k, v in base.items() if k != WITHOUT.get((name, key))}
            yield key, {**arguments, key: value}
        # An object parameter's own fields: navigate_to's goal {"x", "y", "yaw"}.
        if key == "goal" and name == "navigate_to":
            for field in ("x", "y", "yaw"):
                for value in NUMBERS:
                    yield f"goal.{field}", {**base, "goal": {"x": 1.5, "y": 2.0, field: value}}


@pytest.fixture
async def nav2_session(make_sim: Any, tmp_path: Path) -> AsyncIterator[tuple[Session, SimulatedRobot]]:
    robot: SimulatedRobot = await make_sim(dialect="ros2", world="nav2")
    robot.nav2.navigator.speed = 8.0
    async with open_session(robot.url, record_dir=str(tmp_path / "recordings")) as session:
        await session.ok("record", {"topics": ["/odom"], "duration": 0.3, "name": "base"})
        yield session, robot


def _in_our_words(text: str) -> str | None:
    """What is wrong with an error's text, or None. The edge's answer for an exception no tool answered is in
    our words, but it is a bug's: the values must be refused, or handled, before that."""
    markers = (
        "Error executing tool",
        "unexpected error in this server",
        "validation error",
        "Traceback",
        "input_value=",
        "pydantic",
    )
    for marker in markers:
        if marker in text:
            return f"says {marker!r}"
    return None if text.strip() else "is empty"


@pytest.mark.slow
async def test_every_extreme_value_of_every_parameter_is_answered_in_time_and_in_our_words(
    nav2_session: tuple[Session, SimulatedRobot],
) -> None:
    session, _robot = nav2_session
    listed = await session.mcp.list_tools()
    problems: list[str] = []
    tried = 0
    for tool in listed.tools:
        for varied, arguments in extreme_calls(tool.name, tool.input_schema):
            tried += 1
            shown = f"{tool.name}.{varied}={str(arguments.get(varied.split('.')[0]))[:40]}"
            started = time.monotonic()
            try:
                result = await asyncio.wait_for(session.call(tool.name, arguments), DEADLINE)
            except TimeoutError:
                problems.append(f"{shown}: no answer within {DEADLINE:g} s")
                continue
            took = time.monotonic() - started
            if result.is_error and (wrong := _in_our_words(text_of(result))):
                problems.append(f"{shown}: the error {wrong}: {text_of(result)[:200]}")
            elif took > DEADLINE / 2:
                problems.append(f"{shown}: took {took:.1f} s")
    assert tried > 300
    assert not problems, "\n".join(problems)
    await session.ok("list_topics")
