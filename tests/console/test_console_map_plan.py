"""The console and navigation on the simulated Nav2 world: the map panel draws the navigator's plan (its goal
at the end) while a goal runs and drops it once the goal has ended; the operator's E-STOP stops a navigating
robot."""

from __future__ import annotations

import asyncio
import json
import math
from collections.abc import Awaitable, Callable

import websockets
from console_harness import text_of

from mcp import Client
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.console import ConsoleHub, RobotView
from rosbridge_mcp_server.console.mapview import PLAN_KEEP, MapPanel
from rosbridge_mcp_server.robot.graph import RosGraph
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import Audit, Operator, PolicyGuard
from rosbridge_mcp_server.server import build_server
from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]


async def test_the_panel_draws_the_plan_to_the_goal_while_the_robot_drives(make_sim: MakeSim) -> None:
    robot = await make_sim(dialect="ros2", world="nav2")
    robot.nav2.navigator.speed = 8.0
    pushed = asyncio.Event()
    async with RosbridgeClient(robot.url, connect_timeout=2.0, request_timeout=5.0) as ros:
        panel = MapPanel(ros, RosGraph(ros), lambda: None, pushed.set)

        async def until(holds: Callable[[], bool], timeout: float) -> None:
            async with asyncio.timeout(timeout):
                while not holds():
                    pushed.clear()
                    # Woken by the panel's pushes; bounded by the timeout around it.
                    await pushed.wait()

        panel.start()
        try:
            await until(lambda: panel.image is not None, 10.0)
            drawn = panel.images
            goal = {
                "pose": {"header": {"frame_id": "map"}, "pose": {"position": {"x": 2.0, "y": 8.5}}},
            }
            async with websockets.connect(robot.url) as raw:
                frame = {
                    "op": "send_action_goal",
                    "id": "nav",
                    "action": "/navigate_to_pose",
                    "action_type": "nav2_msgs/action/NavigateToPose",
                    "args": goal,
                }
                await raw.send(json.dumps(frame))
                await until(lambda: bool(panel.plan), 10.0)
                end = panel.plan[-1]
                assert math.dist(end, (2.0, 8.5)) < 0.01
                await until(lambda: panel.images > drawn, 5.0)
                async with asyncio.timeout(20.0):
                    while json.loads(await raw.recv()).get("op") != "action_result":
                        pass
            await until(lambda: not panel.plan, PLAN_KEEP + 5.0)
        finally:
            panel.stop()


async def test_the_console_estop_stops_a_navigating_robot_and_refuses_the_next_goal(
    make_sim: MakeSim,
) -> None:
    """The operator's E-STOP cancels navigate_to's goal: the robot stands within 0.5 s, the call says so, and
    the latch refuses the next goal until Release."""
    robot = await make_sim(dialect="ros1", world="nav2")
    robot.nav2.navigator.speed = 8.0
    state = robot.nav2.robots[0]
    config = Config(url=robot.url)
    operator = Operator()
    audit = Audit()
    ros = RosbridgeClient(robot.url, request_timeout=5.0, reconnect_min=0.05, reconnect_max=0.2)
    session = RobotSession(ros, PolicyGuard(config.policy, audit, operator))
    hub = ConsoleHub([RobotView("robot", session, audit)], operator)
    async with Client(build_server(session, config, console_view=hub.snapshot), mode="legacy") as client:
        await ros.wait_connected(30.0)
        driving = asyncio.create_task(client.call_tool("navigate_to", {"goal": {"x": 1.5, "y": 2.0}}))
        await robot.wait_for(lambda world: state.linear > 0.1, timeout=15)
        await hub.estop()
        await robot.wait_for(lambda world: state.linear == 0.0 and state.angular == 0.0, timeout=0.5)
        result = await asyncio.wait_for(driving, 10)
        assert not result.is_error, text_of(result)
        assert (result.structured_content or {})["canceled_by"] == "estop"
        assert "(cancelled by E-STOP on the operator console)" in text_of(result)
        refused = await client.call_tool("navigate_to", {"goal": {"x": 4.0, "y": 4.0}})
        assert refused.is_error
        assert "E-STOP" in text_of(refused)
        assert hub.release()
