"""A stop stops the robot, whoever's goal it is (issue 35, Why 1).

On the simulated Nav2 world in both dialects, a drive is started by every carrier a model has: the actionlib
goal topic (ROS 1 ``/move_base/goal``), a goal pose for the navigator (``/move_base_simple/goal``,
``/goal_pose``), ``publish_action`` and ``navigate_to``. Then the operator's E-STOP (the console's path) or
``stop_robot`` (through the MCP session) is pressed: a raw rosbridge socket of the test's own sees the cancel
reach the robot, the world's true pose stops moving, and the answer names what was cancelled. A goal another
client sent is cancelled by the E-STOP (it sweeps the known motion servers) and left alone by stop_robot.
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import math
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import pytest
from mcp_harness import Session, text_of
from test_mcp_effects import Watcher, watching

from mcp import Client
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.console import ConsoleHub, RobotView
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import Audit, Operator, PolicyGuard
from rosbridge_mcp_server.server import build_server
from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]

#: Twice a real robot's speed: the drive to FAR takes several seconds, so a stop that does not stop it shows.
SPEED = 2.0
FAR = (1.5, 9.0)
#: How long the robot has to stand still after the stop answered (the stop waits for the bridge to handle it).
STILL_WITHIN = 3.0
#: How long it must then stay where it stopped.
STAYS_FOR = 1.0
#: Where each dialect's navigator takes the goals (ROS 1: move_base; ROS 2: Nav2's bt_navigator).
NAVIGATOR = {"ros1": "/move_base", "ros2": "/navigate_to_pose"}


def stamped_pose(x: float, y: float) -> dict[str, Any]:
    return {
        "header": {"frame_id": "map"},
        "pose": {"position": {"x": x, "y": y, "z": 0.0}, "orientation": {"z": 0.0, "w": 1.0}},
    }


def carrier_call(dialect: str, carrier: str) -> tuple[str, dict[str, Any]]:
    """The MCP tool call that starts a drive to FAR through *carrier*."""
    pose = stamped_pose(*FAR)
    pkg = "geometry_msgs/msg" if dialect == "ros2" else "geometry_msgs"
    if carrier == "goal topic":
        message = {"header": {}, "goal_id": {"id": "g"}, "goal": {"target_pose": pose}}
        return "publish_topic", {
            "topic": "/move_base/goal",
            "message_type": "move_base_msgs/MoveBaseActionGoal",
            "message": message,
        }
    if carrier == "goal pose":
        topic = "/goal_pose" if dialect == "ros2" else "/move_base_simple/goal"
        return "publish_topic", {"topic": topic, "message_type": f"{pkg}/PoseStamped", "message": pose}
    if carrier == "publish_action":
        if dialect == "ros2":
            action, action_type, goal = "/navigate_to_pose", "nav2_msgs/action/NavigateToPose", {"pose": pose}
        else:
            action, action_type, goal = "/move_base", "move_base_msgs/MoveBaseAction", {"target_pose": pose}
        arguments = {"action_name": action, "action_type": action_type, "goal": goal, "timeout": 60}
        return "publish_action", arguments
    return "navigate_to", {"goal": {"x": FAR[0], "y": FAR[1]}, "timeout": 60}


CARRIERS = [
    ("ros1", "goal topic"),
    ("ros1", "goal pose"),
    ("ros2", "goal pose"),
    ("ros1", "publish_action"),
    ("ros2", "publish_action"),
    ("ros1", "navigate_to"),
    ("ros2", "navigate_to"),
]


@contextlib.asynccontextmanager
async def console_stand(robot: SimulatedRobot) -> AsyncIterator[tuple[Session, ConsoleHub, io.StringIO]]:
    """An MCP session on a server with the operator console's hub over the same robot session, as
    ``--console`` serves them; no policy. Entered and left in the test's own task (the SDK's scopes)."""
    config = Config(url=robot.url)
    operator = Operator()
    trail = io.StringIO()
    audit = Audit(trail)
    ros = RosbridgeClient(robot.url, request_timeout=5.0, reconnect_min=0.05, reconnect_max=0.2)
    session = RobotSession(ros, PolicyGuard(config.policy, audit, operator))
    hub = ConsoleHub([RobotView("robot", session, audit)], operator)
    async with Client(build_server(session, config, console_view=hub.snapshot), mode="legacy") as client:
        await ros.wait_connected(30.0)
        yield Session(client, ros), hub, trail


def moving(state: Any) -> bool:
    return abs(state.linear) > 0.05 or abs(state.angular) > 0.05


async def watch_cancels(watcher: Watcher, dialect: str) -> None:
    if dialect == "ros1":
        await watcher.subscribe("/move_base/cancel", "actionlib_msgs/GoalID")
    else:
        await watcher.subscribe("/navigate_to_pose/_action/status", "action_msgs/msg/GoalStatusArray")


async def cancel_reached(watcher: Watcher, dialect: str) -> Any:
    """The cancel as the robot got it: ROS 1 the GoalID on /move_base/cancel; ROS 2 a goal CANCELING or
    CANCELED in the navigator's status list."""
    if dialect == "ros1":
        return await watcher.wait_for("/move_base/cancel", lambda message: True)
    return await watcher.wait_for(
        "/navigate_to_pose/_action/status",
        lambda message: any(entry["status"] in (3, 5) for entry in message["status_list"]),
    )


async def stands_still(robot: SimulatedRobot, state: Any) -> None:
    """The robot stops within STILL_WITHIN and stays where it stopped for STAYS_FOR."""
    await robot.wait_for(lambda world: not moving(state), timeout=STILL_WITHIN)
    here = (state.x, state.y)
    with pytest.raises(TimeoutError):
        await robot.wait_for(
            lambda world: moving(state) or math.dist((state.x, state.y), here) > 0.02, timeout=STAYS_FOR
        )


async def press(stop: str, session: Session, hub: ConsoleHub) -> str:
    """Press the stop; its answer as text (the console's: the robot's report)."""
    if stop == "stop_robot":
        return text_of(await session.ok("stop_robot"))
    [report] = await hub.estop()
    return "\n".join([*report["cancels"], *report["failures"]])


@pytest.mark.parametrize("stop", ["estop", "stop_robot"])
@pytest.mark.parametrize(("dialect", "carrier"), CARRIERS)
async def test_a_stop_stops_a_drive_whatever_carried_its_goal(
    make_sim: MakeSim, dialect: str, carrier: str, stop: str
) -> None:
    robot = await make_sim(dialect=dialect, world="nav2")
    robot.nav2.navigator.speed = SPEED
    state = robot.nav2.robots[0]
    tool, arguments = carrier_call(dialect, carrier)
    async with console_stand(robot) as (session, hub, _), watching(robot) as watcher:
        await watch_cancels(watcher, dialect)
        call = asyncio.create_task(session.call(tool, arguments))
        await robot.wait_for(lambda world: moving(state), timeout=15.0)
        answer = await press(stop, session, hub)
        await cancel_reached(watcher, dialect)
        await stands_still(robot, state)
        result = await asyncio.wait_for(call, 10.0)
        hub.release()
        # What a stop cancelled is done with: the next stop_robot has nothing left of it.
        again = text_of(await session.ok("stop_robot"))
    assert not result.is_error, text_of(result)
    assert math.dist((state.x, state.y), FAR) > 1.0  # it never got there
    assert "Nothing to stop" not in answer
    assert "Nothing to stop" in again, again
    assert NAVIGATOR[dialect] in answer, answer
    if carrier == "goal topic":
        assert "goal g on /move_base (sent on /move_base/goal by this server)" in answer
    if carrier == "goal pose":
        topic = "/goal_pose" if dialect == "ros2" else "/move_base_simple/goal"
        assert f"every goal on {NAVIGATOR[dialect]} (sent on {topic} by this server)" in answer
