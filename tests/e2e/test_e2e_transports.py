"""The same MCP sessions over stdio and over Streamable HTTP: every check runs the same on both."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from e2e_transports import serving
from mcp.client.context import ClientRequestContext
from mcp.types import ElicitRequestParams, ElicitResult, TextContent

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.tools import TOOL_MODULES

pytestmark = pytest.mark.parametrize("transport", ["stdio", "http"])

CMD_VEL = "/turtle1/cmd_vel"
TWIST = {"linear": {"x": 0.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.25}}


def _text(result: object) -> str:
    return "\n".join(block.text for block in result.content if isinstance(block, TextContent))  # type: ignore[attr-defined]


async def test_every_tool_is_listed_and_a_reading_tool_answers(
    transport: str, sim_ros2: SimulatedRobot
) -> None:
    """tools/list holds every tool module; list_topics answers with the robot's topics."""
    async with serving(transport, "--url", sim_ros2.url) as served, served.connect() as client:
        listed = await client.list_tools()
        topics = await client.call_tool("list_topics", {})
    assert sorted(tool.name for tool in listed.tools) == sorted(m.SPEC.name for m in TOOL_MODULES)
    assert not topics.is_error, _text(topics)
    assert CMD_VEL in _text(topics)


async def test_a_published_twist_lands_on_the_robot(transport: str, sim_ros2: SimulatedRobot) -> None:
    """publish_topic over either transport reaches the simulated robot with the message sent."""
    async with serving(transport, "--url", sim_ros2.url) as served, served.connect() as client:
        result = await client.call_tool(
            "publish_topic",
            {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "message": TWIST},
        )
    assert not result.is_error, _text(result)
    await sim_ros2.wait_for(lambda world: CMD_VEL in world.published, 10)
    assert sim_ros2.world.published[CMD_VEL][-1].msg["linear"]["x"] == 0.5


async def test_an_unknown_argument_is_refused_by_name_and_nothing_is_sent(
    transport: str, sim_ros2: SimulatedRobot
) -> None:
    """The argument check runs before the SDK's conversion on both transports."""
    async with serving(transport, "--url", sim_ros2.url) as served, served.connect() as client:
        result = await client.call_tool(
            "publish_topic",
            {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "mesage": TWIST},
        )
        wrong_type = await client.call_tool("subscribe_topic", {"topic": "/chatter", "count": "many"})
    assert result.is_error
    assert "mesage" in _text(result)
    assert "message" in _text(result)
    assert wrong_type.is_error
    assert "count" in _text(wrong_type)
    assert CMD_VEL not in sim_ros2.world.published


async def test_a_read_only_server_refuses_an_acting_tool_called_by_name(
    transport: str, sim_ros2: SimulatedRobot
) -> None:
    """--read-only lists no acting tool, and calling one anyway is refused with the reason."""
    async with (
        serving(transport, "--url", sim_ros2.url, "--read-only") as served,
        served.connect() as client,
    ):
        listed = await client.list_tools()
        result = await client.call_tool(
            "publish_topic",
            {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "message": TWIST},
        )
    assert "publish_topic" not in {tool.name for tool in listed.tools}
    assert result.is_error
    assert "read-only" in _text(result)
    assert CMD_VEL not in sim_ros2.world.published


async def test_every_acting_call_is_audited_with_its_caller_over_http(
    transport: str, sim_ros2: SimulatedRobot, tmp_path: Path
) -> None:
    """The audit line names the token's name over HTTP; stdio has no caller to name."""
    audit = tmp_path / "audit.jsonl"
    flags = ("--url", sim_ros2.url, "--audit-log", str(audit), "--policy", str(_policy(tmp_path)))
    async with serving(transport, *flags) as served, served.connect() as client:
        allowed = await client.call_tool(
            "publish_topic",
            {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "message": TWIST},
        )
        refused = await client.call_tool(
            "publish_topic", {"topic": "/forbidden", "message_type": "std_msgs/msg/String", "message": {}}
        )
    assert not allowed.is_error, _text(allowed)
    assert refused.is_error
    lines = [json.loads(line) for line in audit.read_text().splitlines()]
    assert [line["outcome"] for line in lines] == ["allowed", "refused"]
    expected = "operator" if transport == "http" else None
    assert [line.get("caller") for line in lines] == [expected, expected]


def _policy(tmp_path: Path) -> Path:
    path = tmp_path / "policy.toml"
    path.write_text('[topics]\ndeny = ["/forbidden"]\n')
    return path


async def test_a_fleet_file_drives_two_robots_each_under_its_policy(
    transport: str, make_sim: Any, tmp_path: Path
) -> None:
    """--robots FILE: a ROS 1 and a ROS 2 robot; a policy on one refuses there only; the audit names both."""
    ros2 = await make_sim(dialect="ros2")
    ros1 = await make_sim(dialect="ros1")
    (tmp_path / "careful.toml").write_text('[velocity]\nmax_linear = 0.2\nmode = "refuse"\n')
    fleet = tmp_path / "fleet.toml"
    fleet.write_text(
        f'[robots.jazzy]\nurl = "{ros2.url}"\npolicy = "careful.toml"\n\n'
        f'[robots.noetic]\nurl = "{ros1.url}"\n'
    )
    audit = tmp_path / "audit.jsonl"
    fast = {"topic": CMD_VEL, "message_type": "geometry_msgs/Twist", "message": TWIST}
    async with (
        serving(transport, "--robots", str(fleet), "--audit-log", str(audit)) as served,
        served.connect() as client,
    ):
        refused = await client.call_tool("publish_topic", {**fast, "robot": "jazzy"})
        allowed = await client.call_tool("publish_topic", {**fast, "robot": "noetic"})
        robots = await client.call_tool("list_robots", {})
    assert refused.is_error
    assert "max_linear" in _text(refused)
    assert not allowed.is_error, _text(allowed)
    await ros1.wait_for(lambda world: CMD_VEL in world.published, 10)
    assert CMD_VEL not in ros2.world.published
    assert "jazzy: connected, ROS 2" in _text(robots)
    assert "noetic: connected, ROS 1" in _text(robots)
    lines = [json.loads(line) for line in audit.read_text().splitlines()]
    assert [(line["robot"], line["outcome"]) for line in lines] == [
        ("jazzy", "refused"),
        ("noetic", "allowed"),
    ]


async def test_the_person_is_asked_over_either_transport(
    transport: str, sim_ros2: SimulatedRobot, tmp_path: Path
) -> None:
    """confirm = "motion": the question reaches the client mid-call (over HTTP on the call's event stream)."""
    asked: list[str] = []
    answers = iter([True, False])

    async def person(context: ClientRequestContext, params: ElicitRequestParams) -> ElicitResult:
        asked.append(params.message)
        return ElicitResult(action="accept", content={"approve": next(answers)})

    policy = tmp_path / "confirm.toml"
    policy.write_text('confirm = "motion"\n')
    publish = {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "message": TWIST}
    async with (
        serving(transport, "--url", sim_ros2.url, "--policy", str(policy)) as served,
        served.connect(elicitation_callback=person) as client,
    ):
        approved = await client.call_tool("publish_topic", publish)
        declined = await client.call_tool("publish_topic", publish)
    assert len(asked) == 2
    assert CMD_VEL in asked[0]
    assert not approved.is_error, _text(approved)
    assert declined.is_error
    await sim_ros2.wait_for(lambda world: CMD_VEL in world.published, 10)
    assert len(sim_ros2.world.published[CMD_VEL]) == 1
