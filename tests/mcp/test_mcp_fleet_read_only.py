"""A read-only robot of a fleet is read-only: its acting tools are refused with a sentence saying so, are not
offered for it, and nothing reaches its bridge — which here is another robot's too (robot ``cam``, read-only,
and robot ``b`` share one simulated bridge, as two fleet entries with one URL do). stop_robot stays allowed.
Both dialects."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import replace
from typing import Any

import pytest
from mcp_harness import text_of, types_for

from mcp import Client
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import Policy, PolicyGuard
from rosbridge_mcp_server.server import Robot, build_fleet_server
from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 30.0
FIB = "/fibonacci"
READ_ONLY = "is not available on cam: that robot is read-only"


@asynccontextmanager
async def fleet(url: str, read_only: tuple[str, ...] = ("cam",)) -> AsyncIterator[Client]:
    """An MCP session on a server driving robots ``b`` and ``cam`` on one bridge, *read_only* read-only."""
    base = Config()
    entries = []
    for name in ("b", "cam"):
        policy = Policy().with_read_only() if name in read_only else Policy()
        config = replace(base, url=url, policy=policy)
        ros = RosbridgeClient(url, request_timeout=5.0)
        entries.append(Robot(name, config, RobotSession(ros, PolicyGuard(policy))))
    async with Client(build_fleet_server(entries, base), mode="legacy") as client:
        for entry in entries:
            await entry.session.client.wait_connected(WAIT)
        yield client


@pytest.fixture(params=["ros2", "ros1"])
async def bridge(request: pytest.FixtureRequest, make_sim: Any) -> SimulatedRobot:
    """One bridge of each dialect whose Fibonacci goals take a while (a step every 0.1 s)."""
    robot: SimulatedRobot = await make_sim(dialect=request.param, action_step=0.1)
    return robot


async def test_a_read_only_robot_cannot_cancel_the_goal_of_a_robot_on_its_bridge(
    bridge: SimulatedRobot,
) -> None:
    """cancel_action on cam is refused; b's goal on the shared bridge succeeds, never asked to cancel."""
    goal = {"action_name": FIB, "action_type": types_for(bridge)["fibonacci"], "goal": {"order": 8}}
    async with fleet(bridge.url) as client:
        running = asyncio.create_task(client.call_tool("publish_action", {"robot": "b", **goal}))
        await bridge.world.wait_for(lambda w: bool(w.goals), WAIT)
        cancel = await client.call_tool("cancel_action", {"robot": "cam", "action_name": FIB})
        result = await asyncio.wait_for(running, WAIT)
    assert cancel.is_error
    assert f"cancel_action {READ_ONLY}" in text_of(cancel)
    assert "It can act on b." in text_of(cancel)
    assert not result.is_error, text_of(result)
    assert (result.structured_content or {})["succeeded"] is True
    (record,) = bridge.world.goals.values()
    assert not record.cancel_requested


async def test_every_acting_tool_on_a_read_only_robot_is_refused_and_nothing_is_sent(
    bridge: SimulatedRobot,
) -> None:
    """publish_topic, publish_service, publish_action, cancel_action and set_parameter on cam: each refused
    naming the robot; the bridge sees no message, call, goal or parameter change."""
    types = types_for(bridge)
    parameter = "/turtlesim:background_r" if bridge.dialect == "ros2" else "/turtlesim/background_r"
    calls: dict[str, dict[str, Any]] = {
        "publish_topic": {"topic": "/chatter", "message_type": types["string"], "message": {"data": "x"}},
        "publish_service": {"service": "/add_two_ints", "service_type": types["add_two_ints"]},
        "publish_action": {"action_name": FIB, "action_type": types["fibonacci"], "goal": {"order": 2}},
        "cancel_action": {"action_name": FIB},
        "set_parameter": {"name": parameter, "value": 200},
    }
    async with fleet(bridge.url) as client:
        answers = {
            name: await client.call_tool(name, {"robot": "cam", **args}) for name, args in calls.items()
        }
        value = await client.call_tool("get_parameter", {"robot": "cam", "name": parameter})
    for name, answer in answers.items():
        assert answer.is_error, name
        assert f"{name} {READ_ONLY}" in text_of(answer)
    assert "/chatter" not in bridge.world.published
    assert "/add_two_ints" not in bridge.world.service_calls
    assert not bridge.world.goals
    assert (value.structured_content or {})["value"] == 69


async def test_acting_tools_offer_only_the_robots_that_may_act_and_stop_robot_works_everywhere(
    bridge: SimulatedRobot,
) -> None:
    """The acting tools' robot enum leaves cam out and says it is read-only; reading tools and stop_robot
    offer both; stop_robot on cam, and without a robot, answers without an error."""
    async with fleet(bridge.url) as client:
        listed = {tool.name: tool.input_schema for tool in (await client.list_tools()).tools}
        stop_cam = await client.call_tool("stop_robot", {"robot": "cam"})
        stop_all = await client.call_tool("stop_robot", {})
        read = await client.call_tool("list_topics", {"robot": "cam"})
    for name in ("publish_topic", "publish_service", "publish_action", "cancel_action", "set_parameter"):
        robot = listed[name]["properties"]["robot"]
        assert robot["enum"] == ["b"], name
        assert "cam: read-only" in robot["description"]
    assert listed["list_topics"]["properties"]["robot"]["enum"] == ["b", "cam"]
    assert listed["stop_robot"]["properties"]["robot"]["enum"] == ["b", "cam"]
    assert not stop_cam.is_error, text_of(stop_cam)
    assert not stop_all.is_error, text_of(stop_all)
    assert not read.is_error, text_of(read)


async def test_a_fleet_of_read_only_robots_lists_no_acting_tool(bridge: SimulatedRobot) -> None:
    """With every robot read-only the server is read-only: acting tools (stop_robot too) are not listed, and
    one called by name is refused as on a read-only server."""
    async with fleet(bridge.url, read_only=("b", "cam")) as client:
        names = {tool.name for tool in (await client.list_tools()).tools}
        refused = await client.call_tool("cancel_action", {"robot": "b", "action_name": FIB})
    assert not names & {
        "publish_topic",
        "publish_service",
        "publish_action",
        "cancel_action",
        "set_parameter",
    }
    assert "stop_robot" not in names
    assert {"list_topics", "get_image", "list_robots"} <= names
    assert refused.is_error
    assert "this server is read-only" in text_of(refused)


async def test_the_fleet_is_told_what_the_stop_does_and_record_stays_off_a_read_only_robot(
    bridge: SimulatedRobot,
) -> None:
    """The instructions say stop_robot without a robot stops every robot and works on cam (from its spec);
    record, which sends nothing to a robot but writes the host's disk, is refused on cam as acting tools
    are."""
    async with fleet(bridge.url) as client:
        instructions = client.instructions or ""
        recorded = await client.call_tool("record", {"robot": "cam", "topics": ["/chatter"], "duration": 1})
    assert "(stop_robot without it stops every robot)" in instructions
    assert "Read-only robots (cam): only reading tools and stop_robot work on them" in instructions
    assert recorded.is_error
    assert f"record {READ_ONLY}" in text_of(recorded)
