"""The console's map panel draws the navigator's plan (its goal at the end) while a goal runs, and drops it
once the goal has ended: on the simulated Nav2 world, whose navigator republishes /plan while it drives."""

from __future__ import annotations

import asyncio
import json
import math
from collections.abc import Awaitable, Callable

import websockets

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.console.mapview import PLAN_KEEP, MapPanel
from rosbridge_mcp_server.robot.graph import RosGraph
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
