"""The console with several robots: one person, one E-STOP that stops and latches every robot."""

from __future__ import annotations

import asyncio
from dataclasses import replace
from typing import Any

from console_harness import text_of

from mcp import Client
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.console import ConsoleHub, RobotView
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import Audit, Operator, PolicyGuard
from rosbridge_mcp_server.server import Robot, build_fleet_server
from rosbridge_mcp_server.sim import SimulatedRobot

CMD_VEL = "/turtle1/cmd_vel"


def stream(robot: str, **extra: Any) -> dict[str, Any]:
    return {
        "robot": robot,
        "topic": CMD_VEL,
        "message_type": "geometry_msgs/Twist",
        "message": {"linear": {"x": 0.5}},
        **extra,
    }


def moving(sim: SimulatedRobot) -> list[float]:
    return [m.msg["linear"]["x"] for m in sim.world.published.get(CMD_VEL, [])]


async def test_one_estop_stops_every_robot_and_latches_them_all(
    sim_ros2: SimulatedRobot, sim_ros1: SimulatedRobot
) -> None:
    """Streams on a ROS 2 and a ROS 1 robot both end with a zero; then each robot refuses until Release."""
    sims = {"jazzy": sim_ros2, "noetic": sim_ros1}
    base = Config()
    operator = Operator()
    entries: list[Robot] = []
    views = []
    for name, sim in sims.items():
        config = replace(base, url=sim.url)
        ros = RosbridgeClient(sim.url, request_timeout=5.0, reconnect_min=0.05, reconnect_max=0.2)
        audit = Audit(robot=name)
        robot = RobotSession(ros, PolicyGuard(config.policy, audit, operator))
        entries.append(Robot(name, config, robot))
        views.append(RobotView(name, robot, audit))
    hub = ConsoleHub(views, operator)
    server = build_fleet_server(entries, base, console_view=hub.snapshot)
    async with Client(server, mode="legacy") as client:
        for entry in entries:
            await entry.session.client.wait_connected(30.0)
        streaming = [
            asyncio.create_task(client.call_tool("publish_topic", stream(name, rate_hz=10, duration=30)))
            for name in sims
        ]
        for sim in sims.values():
            await sim.wait_for(lambda world: len(world.published.get(CMD_VEL, [])) >= 3, timeout=10)
        reports = await hub.estop()
        assert [report["robot"] for report in reports] == ["jazzy", "noetic"]
        for result in await asyncio.wait_for(asyncio.gather(*streaming), 10):
            assert not result.is_error, text_of(result)
        for sim in sims.values():
            await sim.wait_for(lambda world, sim=sim: moving(sim)[-1] == 0.0, timeout=5)
        for name in sims:
            refused = await client.call_tool("publish_topic", stream(name))
            assert "E-STOP" in text_of(refused)
        snapshot = hub.snapshot()
        assert [robot["name"] for robot in snapshot["robots"]] == ["jazzy", "noetic"]
        # Each robot's stop is audited as the console's, never as a stop_robot call.
        stops = {(e["robot"], e["tool"]) for e in snapshot["audit"] if e["outcome"] == "e-stop"}
        assert stops == {(name, "console") for name in sims}
        assert hub.release()
        for name in sims:
            assert not (await client.call_tool("publish_topic", stream(name))).is_error


async def test_show_console_is_about_every_robot_and_needs_no_robot_argument(
    sim_ros2: SimulatedRobot, sim_ros1: SimulatedRobot
) -> None:
    """With several robots show_console answers without a robot argument, and still refuses unknown ones."""
    sims = {"jazzy": sim_ros2, "noetic": sim_ros1}
    base = Config()
    operator = Operator()
    entries: list[Robot] = []
    views = []
    for name, sim in sims.items():
        config = replace(base, url=sim.url)
        ros = RosbridgeClient(sim.url, request_timeout=5.0, reconnect_min=0.05, reconnect_max=0.2)
        audit = Audit(robot=name)
        robot = RobotSession(ros, PolicyGuard(config.policy, audit, operator))
        entries.append(Robot(name, config, robot))
        views.append(RobotView(name, robot, audit))
    hub = ConsoleHub(views, operator)
    server = build_fleet_server(entries, base, console_view=hub.snapshot)
    async with Client(server, mode="legacy") as client:
        shown = await client.call_tool("show_console", {})
        assert not shown.is_error, text_of(shown)
        assert "jazzy at" in text_of(shown)
        assert "noetic at" in text_of(shown)
        refused = await client.call_tool("show_console", {"robot": "jazzy"})
        assert refused.is_error
        assert "unknown argument 'robot'" in text_of(refused)
