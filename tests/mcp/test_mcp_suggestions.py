"""Every call an answer suggests is a valid call: the suggestions (``tool {...}``, and ``Call tool``) in the
answers of every diagnose fault, of refusals and of "did you mean"s are collected, checked against the tool's
input schema as listed, and run on the simulated robot, where none may be refused for its arguments.

The driver-error fault's suggestion must also show the failing status, not another driver's OK.
"""

from __future__ import annotations

import asyncio
import json
import re
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from mcp.types import CallToolResult, Tool
from mcp_harness import Session, open_session, text_of
from test_mcp_diagnose import FAULT_SIGNS, broken

from mcp import Client
from rosbridge_mcp_server.catalogue import ALL_TOOL_NAMES
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import PolicyGuard, parse_policy
from rosbridge_mcp_server.server import Robot, build_fleet_server
from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 30.0
#: A suggested call: a tool's name, a space, its arguments as a JSON object.
CALL = re.compile(r"\b([a-z][a-z_]+) (?=\{)")
#: A tool named as the thing to call without arguments: "Call list_services to ...", "list_nodes lists the
#: nodes", "list_topics shows ...", "list_robots describes each", "read_recording without a file ...".
NAMED = re.compile(r"\bCall ([a-z][a-z_]+)\b|\b([a-z][a-z_]+) (?:shows|lists|describes|without a file)\b")
#: Every tool a server may list: the catalogue's, and the edge's own (a fleet's, the console's).
KNOWN_TOOLS = {*ALL_TOOL_NAMES, "list_robots", "show_console"}
TWIST = "geometry_msgs/msg/Twist"
DOUBLE_STOP = re.compile(r"(?<!\.)\.\.(?!\.)")

#: Calls whose answers refuse, correct or point elsewhere, on the turtle world.
TURTLE_MISTAKES: list[tuple[str, dict[str, Any]]] = [
    ("publish_topic", {"topic": "/turtle1/cmd_vell", "message_type": TWIST, "message": {"linear": {"x": 1}}}),
    ("publish_topic", {"topic": "/turtle1/pose", "message_type": TWIST, "message": {}}),
    ("subscribe_topic", {"topic": "/turtle1/pos"}),
    ("get_topic_info", {"topic": "/turtle1/pos"}),
    ("publish_service", {"service": "/add_two_intz", "service_type": "example_interfaces/srv/AddTwoInts"}),
    ("publish_action", {"action_name": "/fibonaci", "action_type": "example_interfaces/action/Fibonacci"}),
    ("cancel_action", {"action_name": "/fibonaci"}),
    ("get_node_info", {"node": "/turtlesm"}),
    ("list_parameters", {"node": "/turtlesm"}),
    ("get_parameter", {"name": "/turtlesim:background_rr"}),
    ("describe_type", {"type_name": "geometry_msgs/msg/Twst"}),
    ("get_transform", {"target_frame": "odm", "source_frame": "base_link", "timeout": 0.5}),
    ("get_image", {"topic": "/turtle1/pose", "timeout": 0.5}),
    ("view_scan", {"topic": "/scann", "timeout": 0.5}),
    ("plot_topic", {"series": ["/turtle1/pose xx"], "duration": 0.5}),
    ("diagnose", {"focus": "wheels"}),
    ("read_logs", {"node": "/turtlesm*"}),
    ("read_recording", {"file": "nothing-here"}),
    ("read_recording", {}),
    ("navigate_to", {"goal": {"x": 1, "y": 2}}),
]
#: A policy refusing in each of its ways on the turtle world.
POLICY = """
[topics]
deny = ["/turtle1/cmd_vel"]
[services]
deny = ["/add_two_ints"]
[velocity]
max_linear = 0.2
mode = "refuse"
"""
POLICY_MISTAKES: list[tuple[str, dict[str, Any]]] = [
    ("publish_topic", {"topic": "/turtle1/cmd_vel", "message_type": TWIST, "message": {"linear": {"x": 1}}}),
    ("publish_topic", {"topic": "/turtle2/cmd_vel", "message_type": TWIST, "message": {"linear": {"x": 1}}}),
    ("publish_service", {"service": "/add_two_ints", "service_type": "example_interfaces/srv/AddTwoInts"}),
]


def suggested_calls(text: str, bare: dict[str, Any] | None = None) -> list[tuple[str, dict[str, Any] | str]]:
    """Every ``tool {...}`` in *text*: the tool and its arguments (the text after it when not JSON)."""
    found: list[tuple[str, dict[str, Any] | str]] = []
    decoder = json.JSONDecoder()
    for match in CALL.finditer(text):
        name = match.group(1)
        if name not in KNOWN_TOOLS:
            continue
        try:
            arguments, _ = decoder.raw_decode(text, match.end())
        except json.JSONDecodeError:
            arguments = text[match.end() : match.end() + 80]
        found.append((name, arguments))
    named = [call or name for call, name in NAMED.findall(text) if call or name in KNOWN_TOOLS]
    # A tool named bare takes no argument; on a fleet, its robot (list_robots takes none).
    found += [(name, dict(bare or {}) if name != "list_robots" else {}) for name in named]
    return found


def schema_problems(tool: Tool, arguments: dict[str, Any]) -> list[str]:
    """What in *arguments* the listed input schema does not take: missing required keys, unknown keys, a value
    outside an enum or a numeric bound, a value of the wrong JSON type."""
    schema = tool.input_schema
    properties: dict[str, Any] = schema.get("properties", {})
    problems = [f"{key}: required but missing" for key in schema.get("required", []) if key not in arguments]
    for key, value in arguments.items():
        if key not in properties:
            problems.append(f"{key}: not a parameter")
            continue
        problems += [f"{key}: {p}" for p in _value_problems(properties[key], value)]
    return problems


def _value_problems(prop: dict[str, Any], value: Any) -> list[str]:
    options = prop.get("anyOf") or prop.get("oneOf")
    if options:
        return [] if any(not _value_problems(o, value) for o in options) else [f"{value!r} fits no option"]
    kinds = prop.get("type")
    if kinds is not None:
        kinds = kinds if isinstance(kinds, list) else [kinds]
        if not any(_is(kind, value) for kind in kinds):
            return [f"{value!r} is not {' or '.join(kinds)}"]
    if "enum" in prop and value not in prop["enum"]:
        return [f"{value!r} not one of {prop['enum']}"]
    if isinstance(value, int | float) and not isinstance(value, bool):
        low, high = prop.get("minimum", prop.get("exclusiveMinimum")), prop.get("maximum")
        if (low is not None and value < low) or (high is not None and value > high):
            return [f"{value!r} out of bounds"]
    return []


def _is(kind: str, value: Any) -> bool:
    checks: dict[str, Any] = {
        "object": lambda v: isinstance(v, dict),
        "array": lambda v: isinstance(v, list),
        "string": lambda v: isinstance(v, str),
        "integer": lambda v: isinstance(v, int) and not isinstance(v, bool),
        "number": lambda v: isinstance(v, int | float) and not isinstance(v, bool),
        "boolean": lambda v: isinstance(v, bool),
        "null": lambda v: v is None,
    }
    return bool(checks[kind](value))


async def answers_of(session: Session, calls: list[tuple[str, dict[str, Any]]]) -> list[str]:
    """The text of each call's answer, error or not."""
    return [text_of(await asyncio.wait_for(session.call(name, args), WAIT)) for name, args in calls]


async def check_suggestions(
    session: Session, texts: list[str], robot: str | None = None
) -> dict[tuple[str, str], CallToolResult]:
    """Every suggestion in *texts* checked against its tool's schema and run; the results, by call.

    A suggestion may fail on the robot as the thing it looks at would (a topic that stays silent times out),
    but never for its arguments or its tool. On a fleet a tool named bare ("Call list_topics") is called on
    *robot*, the robot the answer came from; a call written out must name it itself."""
    tools = {tool.name: tool for tool in (await session.mcp.list_tools()).tools}
    calls: dict[tuple[str, str], dict[str, Any]] = {}
    # Sentences joined without a doubled stop ("transforms.. Nothing was sent."); "..." is an ellipsis.
    problems = [f"a doubled stop in {text!r}" for text in texts if DOUBLE_STOP.search(text)]
    for text in texts:
        for name, arguments in suggested_calls(text, bare={"robot": robot} if robot else {}):
            if name not in tools:
                problems.append(f"{name}: not a listed tool, in {text!r}")
            elif not isinstance(arguments, dict):
                problems.append(f"{name} {arguments}: arguments are no JSON object, in {text!r}")
            elif wrong := schema_problems(tools[name], arguments):
                problems.append(f"{name} {json.dumps(arguments)}: {'; '.join(wrong)}, in {text!r}")
            else:
                calls[(name, json.dumps(arguments, sort_keys=True))] = arguments
    assert problems == [], "\n".join(problems)
    keys = list(calls)
    results = await asyncio.gather(*(asyncio.wait_for(session.call(n, calls[(n, a)]), WAIT) for n, a in keys))
    for (name, arguments), result in zip(keys, results, strict=True):
        text = text_of(result)
        refused = text.startswith(("Invalid arguments", "Unknown tool"))
        assert not (result.is_error and refused), f"{name} {arguments}: {text}"
    return dict(zip(keys, results, strict=True))


@pytest.mark.timeout(120)
@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_every_call_diagnose_suggests_for_every_fault_is_valid_and_runs(dialect: str) -> None:
    """All faults at once: each finding's next calls fit their tools' schemas and run on the robot."""
    faults = tuple(f for f in FAULT_SIGNS if not (dialect == "ros1" and f == "controller-inactive"))
    async with broken(dialect, faults, tools=None) as (_robot, session):
        result = await session.ok("diagnose")
        data = result.structured_content
        assert data is not None
        texts = [text_of(result), *(finding["next"] for finding in data["findings"])]
        ran = await check_suggestions(session, texts)
    assert len(ran) >= len(faults), ran.keys()
    # An inactive lifecycle node's finding names activating it in words: an acting call is never suggested.
    assert not any(name.startswith("publish_") or name == "set_parameter" for name, _ in ran), ran.keys()


@pytest.mark.timeout(60)
@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_the_driver_error_next_call_returns_the_failing_status(dialect: str) -> None:
    """The lidar driver's ERROR is one of four drivers' statuses on /diagnostics: the call diagnose suggests
    for it shows that ERROR, not another driver's OK."""
    async with broken(dialect, ("driver-error",), tools=None) as (_robot, session):
        finding = (await session.ok("diagnose")).structured_content["findings"][0]  # type: ignore[index]
        assert finding["area"] == "diagnostics", finding
        [(name, arguments)] = [c for c in suggested_calls(finding["next"]) if isinstance(c[1], dict)]
        shown = text_of(await session.ok(name, arguments))
    assert "Motor stalled" in shown, shown


@pytest.mark.timeout(90)
async def test_every_call_a_refusal_or_did_you_mean_suggests_is_valid_and_runs(
    sim_ros2: SimulatedRobot, tmp_path: Path
) -> None:
    """Wrong names, wrong types, unknown frames, a missing map or Nav2 and the policy's refusals: each
    suggestion their answers carry is a call that fits and runs."""
    async with open_session(sim_ros2.url, record_dir=str(tmp_path)) as session:
        texts = await answers_of(session, TURTLE_MISTAKES)
        ran = await check_suggestions(session, texts)
    async with open_session(sim_ros2.url, guard=None, policy=parse_policy(tomllib.loads(POLICY))) as refusing:
        refusals = await answers_of(refusing, POLICY_MISTAKES)
        ran |= await check_suggestions(refusing, refusals)
    assert {"list_topics", "list_services", "list_actions", "list_nodes", "record", "read_recording"} <= {
        name for name, _ in ran
    }, sorted(ran)


async def test_every_call_a_fleet_refusal_suggests_is_valid_and_runs(
    sim_ros2: SimulatedRobot, sim_ros1: SimulatedRobot, tmp_path: Path
) -> None:
    """Two robots: a call without robot, with an unknown one, a wrong name on one, an empty recording folder:
    each suggestion names the robot the answer came from, and runs."""
    base = replace(Config(), record_dir=tmp_path)
    entries = [
        Robot(name, replace(base, url=url), RobotSession(RosbridgeClient(url), PolicyGuard(base.policy)))
        for name, url in (("jazzy", sim_ros2.url), ("noetic", sim_ros1.url))
    ]
    async with Client(build_fleet_server(entries, base), mode="legacy") as client:
        for entry in entries:
            await entry.session.client.wait_connected(WAIT)
        session = Session(client, entries[0].session.client)
        texts = await answers_of(
            session,
            [
                ("list_topics", {}),
                ("get_node_info", {"robot": "mars", "node": "/turtlesim"}),
                ("subscribe_topic", {"robot": "noetic", "topic": "/turtle1/pos"}),
                ("read_recording", {"robot": "noetic"}),
            ],
        )
        ran = await check_suggestions(session, texts, robot="noetic")
    assert ("list_robots", "{}") in ran, sorted(ran)
    assert ("list_topics", '{"robot": "noetic"}') in ran, sorted(ran)
    assert ("record", '{"duration": 10, "robot": "noetic", "topics": ["/rosout"]}') in ran, sorted(ran)


README_TEXTS = {
    name: (Path(__file__).resolve().parents[2] / name).read_text(encoding="utf-8")
    for name in ("README.md", "README_ja.md")
}


@pytest.mark.parametrize("readme", list(README_TEXTS))
async def test_every_call_the_readme_shows_fits_its_tool(readme: str) -> None:
    """The README's answers (diagnose's next calls, ...) and comments show calls a model would copy: each one
    names a listed tool and fits its schema."""
    async with open_session("ws://127.0.0.1:9", wait=False) as session:
        tools = {tool.name: tool for tool in (await session.mcp.list_tools()).tools}
    shown = [(name, args) for name, args in suggested_calls(README_TEXTS[readme]) if args != {}]
    problems = [
        f"{name} {args}: {schema_problems(tools[name], args) if isinstance(args, dict) else 'no JSON'}"
        for name, args in shown
        if not isinstance(args, dict) or schema_problems(tools[name], args)
    ]
    assert problems == [], "\n".join(problems)
    assert any(name == "read_logs" for name, _ in shown), shown


@pytest.mark.timeout(120)
@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_every_call_offered_for_robots_under_namespaces_is_valid_and_runs(
    make_sim: Any, dialect: str
) -> None:
    """Two robots on one bridge (/robot1, /robot2): the tools that need one robot's names answer each robot's
    call, and diagnose's next call for robot2's broken tf names its namespace; each fits and runs."""
    fleet = await make_sim(dialect=dialect, world="nav2", robots=2)
    fleet.nav2.navigator.speed = 8.0
    async with open_session(fleet.url) as session:
        texts = await answers_of(
            session,
            [
                ("navigate_to", {"forward": 0.3}),
                ("get_transform", {"target_frame": "map", "source_frame": "base_link"}),
                ("view_map", {"around_robot": 3}),
                ("view_scan", {}),
            ],
        )
        fleet.nav2.robots[1].quiet.add("odom->base_footprint")
        texts.append(text_of(await session.ok("diagnose", {"focus": "tf"})))
        ran = await check_suggestions(session, texts)
    assert {name for name, _ in ran} == {"navigate_to", "get_transform", "view_map", "view_scan"}, sorted(ran)
    assert ("navigate_to", '{"forward": 0.3, "namespace": "/robot2"}') in ran, sorted(ran)
