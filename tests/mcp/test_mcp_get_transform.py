"""get_transform through an MCP session: links heard on /tf and /tf_static, in both dialects."""

from __future__ import annotations

import math
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any

import pytest
from mcp_harness import Session, text_of

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.sim import SimulatedRobot


def link(
    robot: SimulatedRobot, parent: str, child: str, *, x: float, y: float, yaw_deg: float
) -> dict[str, Any]:
    stamp = {"sec": 10, "nanosec": 0} if robot.dialect == "ros2" else {"secs": 10, "nsecs": 0}
    half = math.radians(yaw_deg) / 2
    return {
        "header": {"frame_id": parent, "stamp": stamp},
        "child_frame_id": child,
        "transform": {
            "translation": {"x": x, "y": y, "z": 0.0},
            "rotation": {"x": 0.0, "y": 0.0, "z": math.sin(half), "w": math.cos(half)},
        },
    }


@asynccontextmanager
async def broadcaster(robot: SimulatedRobot) -> AsyncIterator[None]:
    """Another client: dock → cart on /tf_static; cart → arm (turned 90°) → tool on /tf.

    Frames of its own: the simulated robot publishes world, odom and base_link itself, and the newest of two
    publishers of one link would win.
    """
    msg_type = "tf2_msgs/msg/TFMessage" if robot.dialect == "ros2" else "tf2_msgs/TFMessage"
    async with RosbridgeClient(robot.url, connect_timeout=2.0, request_timeout=5.0) as tf:
        await tf.wait_connected(30.0)
        static = {"transforms": [link(robot, "dock", "cart", x=1.0, y=0.0, yaw_deg=0.0)]}
        await tf.publish("/tf_static", msg_type, static, latch=True)
        moving = {
            "transforms": [
                link(robot, "cart", "arm", x=0.0, y=2.0, yaw_deg=90.0),
                link(robot, "arm", "tool", x=0.1, y=0.0, yaw_deg=0.0),
            ]
        }
        # Latched here so a late subscriber hears it without a publishing loop in the test.
        await tf.publish("/tf", msg_type, moving, latch=True)
        yield


async def test_a_transform_over_several_frames(session: Session, sim: SimulatedRobot) -> None:
    """tool in dock: three links composed, 90° of yaw, the chain named."""
    async with broadcaster(sim):
        result = await session.ok("get_transform", {"target_frame": "dock", "source_frame": "tool"})
    data = result.structured_content
    assert data is not None
    assert data["translation"] == pytest.approx({"x": 1.0, "y": 2.1, "z": 0.0})
    assert data["rotation"]["yaw"] == pytest.approx(90.0)
    assert data["chain"] == ["dock", "cart", "arm", "tool"]
    assert data["static"] is False
    assert 0 <= data["age"] < 5
    assert "chain dock → cart → arm → tool" in text_of(result)


async def test_the_reverse_direction_inverts(session: Session, sim: SimulatedRobot) -> None:
    """dock in arm: the inverse, turned -90°."""
    async with broadcaster(sim):
        result = await session.ok("get_transform", {"target_frame": "arm", "source_frame": "dock"})
    data = result.structured_content
    assert data is not None
    assert data["rotation"]["yaw"] == pytest.approx(-90.0)
    assert data["translation"] == pytest.approx({"x": -2.0, "y": 1.0, "z": 0.0})


async def test_an_unknown_frame_lists_the_frames_seen(session: Session) -> None:
    """A misspelt frame is an error after the timeout, listing the frames heard."""
    text = await session.error(
        "get_transform", {"target_frame": "world", "source_frame": "base_lnk", "timeout": 0.5}
    )
    assert "'base_lnk' has not been seen" in text
    assert "Frames seen: base_link, base_scan, camera, map, odom, world." in text


async def test_the_robots_own_frames_give_the_turtles_pose(session: Session, sim: SimulatedRobot) -> None:
    """world ← base_link from the robot's /tf_static and /tf is the turtle's pose in turtlesim coordinates."""
    result = await session.ok("get_transform", {"target_frame": "world", "source_frame": "base_link"})
    data = result.structured_content
    assert data is not None
    turtle = sim.world.turtle
    assert data["translation"]["x"] == pytest.approx(turtle.x, abs=0.05)
    assert data["translation"]["y"] == pytest.approx(turtle.y, abs=0.05)
    assert data["chain"] == ["world", "odom", "base_link"]
    assert data["static"] is False
    assert data["age"] < 1.0


async def test_a_static_only_chain_has_no_age(session: Session) -> None:
    """camera ← base_scan uses /tf_static links only: static, no age."""
    result = await session.ok("get_transform", {"target_frame": "camera", "source_frame": "base_scan"})
    data = result.structured_content
    assert data is not None
    assert data["translation"] == pytest.approx({"x": -0.1, "y": 0.0, "z": -0.1})
    assert (data["static"], data["age"]) == (True, None)
    assert "static links only" in text_of(result)
