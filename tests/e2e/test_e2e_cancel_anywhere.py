"""Cancel anywhere, on every transport: every tool the server lists is called and cancelled at a random
moment (the SDK client's ``notifications/cancelled``, sent when the task awaiting ``call_tool`` is cancelled)
on the simulated Nav2 robot, over stdio and over Streamable HTTP (in memory: ``tests/mcp``).

After each cancel the same session answers the next call, and each tool kept its promise on the robot: a
velocity stream's last command is all zeros, a navigation goal is cancelled (the robot stands short of the
goal), a recording is a finished, readable file. The moments come from a seeded random generator (the same
ones every run), a different one for each transport.
"""

from __future__ import annotations

import asyncio
import contextlib
import random
from collections.abc import AsyncIterator, Awaitable, Callable
from pathlib import Path
from typing import Any

import pytest
from e2e_transports import serving
from mcap.reader import make_reader
from mcp.types import CallToolResult, TextContent

from mcp import Client
from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]
WAIT = 15.0
#: Cancels land between 0 and this many seconds after the call is sent.
LATEST_CANCEL = 1.5
CMD_VEL = "/cmd_vel"
STILL = {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
GOAL = {"x": 1.5, "y": 2.0}

#: A call of each tool that runs for a while on the simulated Nav2 robot (ROS 2), so that a cancel finds it
#: at work; a tool not named here is called without arguments.
CALLS: dict[str, dict[str, Any]] = {
    "get_topic_info": {"topic": "/scan"},
    "publish_topic": {
        "topic": CMD_VEL,
        "message_type": "geometry_msgs/msg/TwistStamped",
        "message": {"header": {"frame_id": "base_link"}, "twist": {"linear": {"x": 0.3}}},
        "rate_hz": 10,
        "duration": 30,
    },
    "publish_service": {"service": "/map_server/map", "service_type": "nav_msgs/srv/GetMap"},
    "publish_action": {
        "action_name": "/navigate_to_pose",
        "action_type": "nav2_msgs/action/NavigateToPose",
        "goal": {"pose": {"header": {"frame_id": "map"}, "pose": {"position": GOAL}}},
        "timeout": 60,
    },
    "cancel_action": {"action_name": "/navigate_to_pose"},
    "subscribe_topic": {"topic": "/odom", "count": 100, "duration": 10},
    "get_image": {"topic": "/camera/camera/color/image_raw", "timeout": 5},
    "describe_type": {"type_name": "nav2_msgs/action/NavigateToPose"},
    "get_node_info": {"node": "/amcl"},
    "get_parameter": {"name": "/amcl:max_particles"},
    "set_parameter": {"name": "/amcl:max_particles", "value": 2000},
    "get_transform": {"target_frame": "map", "source_frame": "base_link"},
    "view_map": {"scan_topic": "/scan"},
    "plot_topic": {"series": ["/odom twist.twist.linear.x"], "duration": 10},
    "navigate_to": {"goal": GOAL, "timeout": 60},
    "record": {"topics": ["/odom", "/scan"], "duration": 30, "name": "cancelled"},
    "read_recording": {"file": "cancelled.mcap"},
}


async def wait_finished(path: Path) -> None:
    """Until the recording's summary is written (polled: a file gives no event)."""
    async with asyncio.timeout(WAIT):
        while True:
            with contextlib.suppress(Exception), path.open("rb") as handle:
                summary = make_reader(handle).get_summary()
                if summary is not None and summary.statistics is not None:
                    return
            await asyncio.sleep(0.05)


def _text(result: CallToolResult) -> str:
    return "\n".join(block.text for block in result.content if isinstance(block, TextContent))


async def _cancelled_at(client: Client, name: str, delay: float) -> None:
    """Call *name* and cancel it *delay* seconds later (it may have answered by then)."""
    call = asyncio.create_task(client.call_tool(name, CALLS.get(name, {})))
    # The attack's timing, not a synchronisation: the cancel lands wherever the call is by then.
    await asyncio.wait({call}, timeout=delay)
    call.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await call


async def _promise_kept(name: str, robot: SimulatedRobot, directory: Path) -> None:
    """What *name* promises on a cancel, as the robot (and the disk) saw it."""
    driven = robot.nav2.robots[0]
    if name == "publish_topic":
        await robot.world.wait_for(
            lambda w: not w.published.get(CMD_VEL) or w.published[CMD_VEL][-1].msg["twist"] == STILL, WAIT
        )
    if name in ("publish_action", "navigate_to"):
        await robot.wait_for(lambda _w: driven.linear == 0.0 and driven.angular == 0.0, WAIT)
        assert abs(driven.x - GOAL["x"]) + abs(driven.y - GOAL["y"]) > 0.5, "the goal was not cancelled"
    if name == "record" and (directory / "cancelled.mcap").exists():
        await wait_finished(directory / "cancelled.mcap")


async def sweep(client: Client, robot: SimulatedRobot, directory: Path, seed: int) -> list[str]:
    """Every listed tool called and cancelled at a random moment; the tools swept."""
    chooser = random.Random(seed)
    tools = [tool.name for tool in (await client.list_tools()).tools]
    for name in tools:
        await _cancelled_at(client, name, chooser.uniform(0.0, LATEST_CANCEL))
        answer = await asyncio.wait_for(client.call_tool("list_topics", {}), WAIT)
        assert not answer.is_error, f"after cancelling {name}: {_text(answer)[:200]}"
        await _promise_kept(name, robot, directory)
    return tools


@contextlib.asynccontextmanager
async def connected(transport: str, robot: SimulatedRobot, directory: Path) -> AsyncIterator[Client]:
    env = {"ROSBRIDGE_MCP_RECORD_DIR": str(directory)}
    async with serving(transport, "--url", robot.url, env=env) as served, served.connect() as client:
        yield client


@pytest.mark.slow
@pytest.mark.parametrize(("transport", "seed"), [("stdio", 2), ("http", 3)])
async def test_every_tool_cancelled_at_a_random_moment_keeps_the_session_and_its_promise(
    make_sim: MakeSim, tmp_path: Path, transport: str, seed: int
) -> None:
    robot = await make_sim(dialect="ros2", world="nav2")
    directory = tmp_path / "recordings"
    async with connected(transport, robot, directory) as client:
        tools = await sweep(client, robot, directory, seed)
        assert {"record", "navigate_to", "publish_topic", "publish_action"} <= set(tools)
    driven = robot.nav2.robots[0]
    await robot.wait_for(lambda _w: driven.linear == 0.0 and driven.angular == 0.0, WAIT)
