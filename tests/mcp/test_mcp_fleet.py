"""Several robots from one server: two simulated robots, one of each dialect, behind one MCP session."""

from __future__ import annotations

import asyncio
import json
import socket
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import replace
from pathlib import Path
from typing import Any

import websockets
from mcp.types import CallToolResult, TextContent
from mcp_harness import text_of

from mcp import Client
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.config.fleet import load_fleet
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import Policy, PolicyGuard, parse_policy
from rosbridge_mcp_server.server import Robot, build_fleet_server, build_server
from rosbridge_mcp_server.server.fleet import Fleet
from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 30.0
ROS2_CMD = "/turtle1/cmd_vel"
TWIST = {"linear": {"x": 0.4}, "angular": {"z": 0.0}}


@asynccontextmanager
async def fleet_session(
    robots: dict[str, SimulatedRobot], policies: dict[str, Policy] | None = None
) -> AsyncIterator[Client]:
    """An MCP session on a server driving *robots* (name → simulated robot), each under its policy."""
    base = Config()
    entries = []
    for name, robot in robots.items():
        config = replace(base, url=robot.url, policy=(policies or {}).get(name, Policy()))
        ros = RosbridgeClient(robot.url, request_timeout=5.0)
        entries.append(Robot(name, config, RobotSession(ros, PolicyGuard(config.policy))))
    server = build_fleet_server(entries, base)
    async with Client(server, mode="legacy") as client:
        for entry in entries:
            await entry.session.client.wait_connected(WAIT)
        yield client


def _publish(robot: str, x: float = 0.4, topic: str = ROS2_CMD) -> dict[str, object]:
    return {
        "robot": robot,
        "topic": topic,
        "message_type": "geometry_msgs/Twist",
        "message": {**TWIST, "linear": {"x": x}},
    }


async def test_each_command_lands_on_the_robot_it_names(
    sim_ros2: SimulatedRobot, sim_ros1: SimulatedRobot
) -> None:
    """A publish naming one robot reaches that robot only; each answers its own graph."""
    async with fleet_session({"jazzy": sim_ros2, "noetic": sim_ros1}) as client:
        to_ros2 = await client.call_tool("publish_topic", _publish("jazzy", 0.3))
        to_ros1 = await client.call_tool("publish_topic", _publish("noetic", 0.7))
        topics_ros1 = await client.call_tool("list_topics", {"robot": "noetic"})
    assert not to_ros2.is_error, text_of(to_ros2)
    assert not to_ros1.is_error, text_of(to_ros1)
    await sim_ros2.wait_for(lambda w: ROS2_CMD in w.published, WAIT)
    await sim_ros1.wait_for(lambda w: ROS2_CMD in w.published, WAIT)
    assert [m.msg["linear"]["x"] for m in sim_ros2.world.published[ROS2_CMD]] == [0.3]
    assert [m.msg["linear"]["x"] for m in sim_ros1.world.published[ROS2_CMD]] == [0.7]
    # ROS 1 names its types pkg/Type; the listing comes from that robot.
    assert "geometry_msgs/Twist" in text_of(topics_ros1)
    assert "geometry_msgs/msg/Twist" not in text_of(topics_ros1)


async def test_the_robot_argument_is_required_and_checked(
    sim_ros2: SimulatedRobot, sim_ros1: SimulatedRobot
) -> None:
    """Without robot, or with an unknown one, the call is refused naming the robots, and nothing is sent."""
    async with fleet_session({"jazzy": sim_ros2, "noetic": sim_ros1}) as client:
        missing = await client.call_tool("list_topics", {})
        unknown = await client.call_tool("publish_topic", _publish("mars"))
        listed = await client.list_tools()
    assert missing.is_error
    assert "needs the robot argument" in text_of(missing)
    assert "jazzy, noetic" in text_of(missing)
    assert unknown.is_error
    assert "'mars' is not one of jazzy, noetic" in text_of(unknown)
    assert ROS2_CMD not in sim_ros2.world.published
    assert ROS2_CMD not in sim_ros1.world.published
    schemas = {tool.name: tool.input_schema for tool in listed.tools}
    assert schemas["list_topics"]["properties"]["robot"]["enum"] == ["jazzy", "noetic"]
    assert "robot" in schemas["list_topics"]["required"]
    assert "robot" not in schemas["stop_robot"].get("required", [])
    assert "list_robots" in schemas


async def test_a_policy_on_one_robot_does_not_touch_the_other(
    sim_ros2: SimulatedRobot, sim_ros1: SimulatedRobot
) -> None:
    """A velocity cap on one robot refuses there; the same command goes through on the other."""
    careful = parse_policy({"velocity": {"max_linear": 0.2, "mode": "refuse"}})
    async with fleet_session({"jazzy": sim_ros2, "noetic": sim_ros1}, {"jazzy": careful}) as client:
        refused = await client.call_tool("publish_topic", _publish("jazzy", 1.0))
        allowed = await client.call_tool("publish_topic", _publish("noetic", 1.0))
        robots = await client.call_tool("list_robots", {})
    assert refused.is_error
    assert "max_linear" in text_of(refused)
    assert not allowed.is_error, text_of(allowed)
    await sim_ros1.wait_for(lambda w: ROS2_CMD in w.published, WAIT)
    assert ROS2_CMD not in sim_ros2.world.published
    rows = {row["name"]: row for row in robots.structured_content["robots"]}  # type: ignore[index]
    assert "linear ≤ 0.2 m/s" in rows["jazzy"]["policy"]
    assert rows["noetic"]["policy"].startswith("no restrictions")
    assert rows["jazzy"]["ros"].startswith("ROS 2")
    assert rows["noetic"]["ros"] == "ROS 1"
    assert rows["jazzy"]["connected"]
    assert rows["noetic"]["connected"]


async def test_one_robots_outage_leaves_the_other_answering(
    sim_ros2: SimulatedRobot, sim_ros1: SimulatedRobot
) -> None:
    """With one robot's bridge stopped, its calls fail with its URL and the other robot still answers."""
    async with fleet_session({"jazzy": sim_ros2, "noetic": sim_ros1}) as client:
        await sim_ros1.stop()
        down = await client.call_tool("list_topics", {"robot": "noetic"})
        up = await client.call_tool("list_topics", {"robot": "jazzy"})
        robots = await client.call_tool("list_robots", {})
    assert down.is_error
    assert sim_ros1.url in text_of(down)
    assert not up.is_error, text_of(up)
    assert "noetic: not connected" in text_of(robots)
    assert "jazzy: connected" in text_of(robots)


async def test_stop_robot_without_a_robot_stops_every_robot(
    sim_ros2: SimulatedRobot, sim_ros1: SimulatedRobot
) -> None:
    """stop_robot with robot stops that one; without, each robot gets its zero velocity."""
    async with fleet_session({"jazzy": sim_ros2, "noetic": sim_ros1}) as client:
        for name in ("jazzy", "noetic"):
            assert not (await client.call_tool("publish_topic", _publish(name, 0.5))).is_error
        one = await client.call_tool("stop_robot", {"robot": "noetic"})
        every = await client.call_tool("stop_robot", {})
    assert not one.is_error, text_of(one)
    assert not every.is_error, text_of(every)
    assert text_of(every).startswith("jazzy: ")
    assert "\nnoetic: " in text_of(every)
    assert every.structured_content is not None
    assert f"jazzy: {ROS2_CMD}" in every.structured_content["zeroed_topics"]
    await sim_ros2.wait_for(lambda w: w.published[ROS2_CMD][-1].msg["linear"]["x"] == 0.0, WAIT)
    await sim_ros1.wait_for(lambda w: w.published[ROS2_CMD][-1].msg["linear"]["x"] == 0.0, WAIT)


async def test_one_robot_lists_no_robot_argument_and_no_list_robots(
    sim_ros2: SimulatedRobot, sim_ros1: SimulatedRobot
) -> None:
    """A server of one robot lists what a fleet lists minus the robot argument and list_robots."""
    base = replace(Config(), url=sim_ros2.url)
    single = build_server(RobotSession(RosbridgeClient(sim_ros2.url), PolicyGuard(base.policy)), base)
    two = build_fleet_server(
        [
            Robot("a", base, RobotSession(RosbridgeClient(sim_ros2.url), PolicyGuard(base.policy))),
            Robot(
                "b",
                replace(base, url=sim_ros1.url),
                RobotSession(RosbridgeClient(sim_ros1.url), PolicyGuard(base.policy)),
            ),
        ],
        base,
    )
    async with Client(single, mode="legacy") as one_client, Client(two, mode="legacy") as two_client:
        listed_one = [tool.model_dump() for tool in (await one_client.list_tools()).tools]
        listed_two = [tool.model_dump() for tool in (await two_client.list_tools()).tools]
    assert all("robot" not in tool["input_schema"]["properties"] for tool in listed_one)
    assert "list_robots" not in {tool["name"] for tool in listed_one}
    assert [_without_robot(tool) for tool in listed_two if tool["name"] != "list_robots"] == [
        _without_robot(tool) for tool in listed_one
    ]


def _without_robot(tool: dict[str, Any]) -> dict[str, Any]:
    schema = dict(tool["input_schema"])
    schema["properties"] = {k: v for k, v in schema["properties"].items() if k != "robot"}
    schema["required"] = [name for name in schema.get("required", []) if name != "robot"]
    return {**tool, "input_schema": schema}


async def test_each_robots_service_listing_is_its_own_and_follows_its_changes(
    sim_ros2: SimulatedRobot, sim_ros1: SimulatedRobot
) -> None:
    """list_services on two robots in turn answers each robot's own listing every time, and a service offered
    on one shows in its next listing while the other's stays as it was."""
    async with fleet_session({"jazzy": sim_ros2, "noetic": sim_ros1}) as client:
        rounds = []
        for _ in range(3):
            rounds.append(
                {
                    name: await client.call_tool("list_services", {"robot": name})
                    for name in ("jazzy", "noetic")
                }
            )
        first = {name: text_of(result) for name, result in rounds[0].items()}
        assert first["jazzy"] != first["noetic"]
        assert "std_srvs/srv/Empty" in first["jazzy"]
        assert "std_srvs/Empty" in first["noetic"]
        assert "std_srvs/srv/" not in first["noetic"]
        for later in rounds[1:]:
            assert {name: text_of(result) for name, result in later.items()} == first
        async with websockets.connect(sim_ros2.url) as provider:
            await provider.send(
                json.dumps({"op": "advertise_service", "service": "/dyn", "type": "std_srvs/srv/Trigger"})
            )
            # No acknowledgement exists in rosbridge: wait until rosapi lists it (a look-up is the barrier).
            async with RosbridgeClient(sim_ros2.url) as probe:
                await probe.wait_connected(WAIT)
                for _ in range(100):
                    if "/dyn" in (await probe.call_service("/rosapi/services", {}))["services"]:
                        break
                    await asyncio.sleep(0)
                else:
                    raise AssertionError("rosapi never listed /dyn")
            changed = text_of(await client.call_tool("list_services", {"robot": "jazzy"}))
            again = text_of(await client.call_tool("list_services", {"robot": "noetic"}))
    assert "/dyn (std_srvs/srv/Trigger)" in changed
    assert "/dyn" not in first["jazzy"]
    assert again == first["noetic"]


async def test_a_robot_that_is_down_is_named_by_its_fleet_entry_and_every_line_by_its_robot(
    sim_ros2: SimulatedRobot, tmp_path: Path
) -> None:
    """A fleet file's robot that is down: its errors point at its entry in the fleet file, not at
    ROSBRIDGE_HOST/PORT; stop_robot's answer labels every line with its robot; list_robots says the policy
    once ("policy: from ...", not "policy: policy")."""
    (tmp_path / "slow.toml").write_text("[velocity]\nmax_linear = 0.3\n", encoding="utf-8")
    fleet_file = tmp_path / "fleet.toml"
    down_entry = f'[robots.down]\nurl = "{_closed_url()}"\npolicy = "slow.toml"\n'
    fleet_file.write_text(f'[robots.up]\nurl = "{sim_ros2.url}"\n{down_entry}', encoding="utf-8")
    base = Config()
    entries = [
        Robot(name, config, RobotSession(RosbridgeClient(config.url), PolicyGuard(config.policy)))
        for name, config in load_fleet(base, robots_file=str(fleet_file))
    ]
    async with Client(build_fleet_server(entries, base), mode="legacy") as client:
        await entries[0].session.client.wait_connected(WAIT)
        down = await client.call_tool("list_topics", {"robot": "down"})
        stopped = await client.call_tool("stop_robot", {})
        robots = await client.call_tool("list_robots", {})
    assert down.is_error
    assert f"[robots.down] in --robots {fleet_file}" in text_of(down), text_of(down)
    assert "ROSBRIDGE_HOST" not in text_of(down)
    lines = text_of(stopped).splitlines()
    assert len(lines) >= 3, lines
    assert all(line.startswith(("up: ", "down: ")) for line in lines), lines
    assert "ROSBRIDGE_HOST" not in text_of(stopped)
    assert "policy: policy" not in text_of(robots), text_of(robots)
    assert f"policy: from {tmp_path / 'slow.toml'}; confirm = never" in text_of(robots), text_of(robots)


async def test_list_robots_on_one_robot_says_it_needs_a_fleet_and_how(sim_ros2: SimulatedRobot) -> None:
    """list_robots is listed only with several robots; called on one, the answer says so and how to run
    several, not a bare "Unknown tool"."""
    base = replace(Config(), url=sim_ros2.url)
    single = build_server(RobotSession(RosbridgeClient(sim_ros2.url), PolicyGuard(base.policy)), base)
    async with Client(single, mode="legacy") as client:
        result = await client.call_tool("list_robots", {})
        other = await client.call_tool("list_robot", {})
    assert result.is_error
    text = text_of(result)
    assert "list_robots" in text
    assert "one robot" in text
    assert "--robot NAME=URL" in text
    assert "--robots" in text
    assert text_of(other).startswith("Unknown tool: list_robot")


def _closed_url() -> str:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return f"ws://127.0.0.1:{probe.getsockname()[1]}"


def test_the_calls_an_answer_suggests_name_the_robot_in_its_text_and_structured_content() -> None:
    """diagnose's next calls on robot b of a fleet: each `tool {...}` gets "robot": "b" first, in the text and
    in the structured content; a call already naming a robot, a tool that is none and plain text stay."""
    fleet = Fleet(
        [
            Robot(name, Config(), RobotSession(RosbridgeClient("ws://127.0.0.1:9"), PolicyGuard(Policy())))
            for name in ("a", "b")
        ]
    )
    next_call = 'read_logs {"node": "/amcl", "level": "info"} for its last words; list_nodes'
    result = CallToolResult(
        content=[TextContent(type="text", text=f"PROBLEM gone\n  → {next_call}; manage_nodes {{}}")],
        structured_content={"findings": [{"next": next_call, "nodes": ["/amcl"]}], "count": 1},
    )
    named = fleet.calls_on(result, "b", {"read_logs", "list_nodes"})
    expected = 'read_logs {"robot": "b", "node": "/amcl", "level": "info"} for its last words; list_nodes'
    assert text_of(named) == f"PROBLEM gone\n  → {expected}; manage_nodes {{}}"
    assert named.structured_content == {"findings": [{"next": expected, "nodes": ["/amcl"]}], "count": 1}
    again = fleet.calls_on(named, "b", {"read_logs"})
    assert text_of(again) == text_of(named)


async def test_robots_of_the_fleet_on_one_bridge_carry_their_namespaces(make_sim: Any) -> None:
    """Two fleet entries on one bridge, namespace /robot1 and /robot2 (as the fleet file sets them): the
    transform tool reads each robot's own tf without a namespace argument; a third entry on that bridge
    without a namespace is answered each robot's call, naming the entry."""
    shared = await make_sim(dialect="ros2", world="nav2", robots=2)
    shared.nav2.robots[1].x += 1.0
    base = Config()
    entries = []
    for name, namespace in (("one", "/robot1"), ("two", "/robot2"), ("any", None)):
        config = replace(base, url=shared.url, namespace=namespace)
        ros = RosbridgeClient(shared.url, request_timeout=5.0)
        entries.append(Robot(name, config, RobotSession(ros, PolicyGuard(config.policy))))
    server = build_fleet_server(entries, base)
    async with Client(server, mode="legacy") as client:
        for entry in entries:
            await entry.session.client.wait_connected(WAIT)
        found = {}
        for name in ("one", "two"):
            arguments = {"robot": name, "target_frame": "map", "source_frame": "base_link", "timeout": 5}
            result = await client.call_tool("get_transform", arguments)
            assert not result.is_error, text_of(result)
            found[name] = result.structured_content or {}
        arguments = {"robot": "any", "target_frame": "map", "source_frame": "base_link"}
        several = await client.call_tool("get_transform", arguments)
    assert several.is_error
    calls = [line for line in text_of(several).splitlines() if line.startswith("→ ")]
    assert [json.loads(line.split(" ", 2)[2]) for line in calls] == [
        {**arguments, "namespace": namespace} for namespace in ("/robot1", "/robot2")
    ], text_of(several)
    assert found["one"]["namespace"] == "/robot1"
    assert found["two"]["namespace"] == "/robot2"
    assert abs(found["two"]["translation"]["x"] - found["one"]["translation"]["x"] - 1.0) < 0.05
