"""Pictures within a budget: someone on the robot's graph publishes a frame, map or scan that declares far
more than it holds (a raw socket on the bridge, as any ROS node could); the reading tools refuse it from its
declared size, naming the size and the limit, and the session goes on. Both dialects."""

from __future__ import annotations

import asyncio
import base64
import json
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any

from mcp_harness import Session
from websockets.asyncio.client import connect

from rosbridge_mcp_server.robot.budget import DECODE_BUDGET, byte_size
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.png import png_bomb

LIMIT = f"budget of {byte_size(DECODE_BUDGET)}"


def _type(sim: SimulatedRobot, package: str, name: str) -> str:
    return f"{package}/msg/{name}" if sim.dialect == "ros2" else f"{package}/{name}"


@asynccontextmanager
async def published(
    sim: SimulatedRobot, topic: str, msg_type: str, msg: dict[str, Any]
) -> AsyncIterator[None]:
    """A raw rosbridge client advertises *topic* latched and publishes *msg* once, then stays connected."""
    async with connect(sim.url, max_size=None) as attacker:
        await attacker.send(json.dumps({"op": "advertise", "topic": topic, "type": msg_type, "latch": True}))
        await attacker.send(json.dumps({"op": "publish", "topic": topic, "msg": msg}))
        # The bridge handles a connection's ops in order: once this call is answered, the frame is latched.
        barrier = {"op": "call_service", "id": "barrier", "service": "/rosapi/get_time"}
        await attacker.send(json.dumps(barrier))
        async with asyncio.timeout(60):  # a bound, not a pause: a million-beam frame on a busy machine
            while json.loads(await attacker.recv()).get("id") != "barrier":
                pass
        yield


async def test_a_png_bomb_on_the_graph_is_refused_naming_its_size_and_the_limit(
    session: Session, sim: SimulatedRobot
) -> None:
    """A ~330 kB CompressedImage declaring 13000² at 16 bits: get_image refuses it from its header."""
    bomb = {"format": "png", "data": base64.b64encode(png_bomb()).decode()}
    async with published(sim, "/attack/compressed", _type(sim, "sensor_msgs", "CompressedImage"), bomb):
        text = await session.error("get_image", {"topic": "/attack/compressed", "timeout": 10})
        # The session and its one connection go on, and a real frame still comes.
        await session.ok("get_image", {"topic": "/camera/image_raw/compressed"})
    assert "declares 13000x13000 pixels (16-bit grey PNG)" in text
    assert LIMIT in text
    assert "it was not decoded" in text
    assert "(topic /attack/compressed)" in text
    assert session.ros.connections_made == 1


async def test_a_raw_frame_declaring_a_huge_size_is_refused_before_its_data_is_read(
    session: Session, sim: SimulatedRobot
) -> None:
    """A sensor_msgs/Image of 30000 × 30000 rgb8 with four bytes of data: refused by the budget."""
    frame = {"width": 30000, "height": 30000, "encoding": "rgb8", "step": 90000, "data": "AAAA"}
    async with published(sim, "/attack/image", _type(sim, "sensor_msgs", "Image"), frame):
        text = await session.error("get_image", {"topic": "/attack/image", "timeout": 10})
    assert "The image declares 30000x30000 pixels of rgb8" in text
    assert LIMIT in text


async def test_a_map_declaring_a_huge_grid_is_refused(session: Session, sim: SimulatedRobot) -> None:
    """An OccupancyGrid of 200000 × 200000 cells with three cells of data: view_map refuses it by its size."""
    grid = {
        "header": {"frame_id": "map"},
        "info": {"width": 200000, "height": 200000, "resolution": 0.05},
        "data": [0, 0, 0],
    }
    async with published(sim, "/attack/map", _type(sim, "nav_msgs", "OccupancyGrid"), grid):
        text = await session.error("view_map", {"topic": "/attack/map", "base_frame": "", "timeout": 10})
    assert "The map declares 200000x200000 cells" in text
    assert LIMIT in text


async def test_a_scan_of_over_a_million_beams_is_refused(session: Session, sim: SimulatedRobot) -> None:
    """A LaserScan with 1,200,000 ranges (~275 MB once decoded): view_scan refuses it, naming the beams."""
    scan = {
        "header": {"frame_id": "laser"},
        "angle_min": -3.14,
        "angle_max": 3.14,
        "angle_increment": 0.000003,
        "range_min": 0.1,
        "range_max": 10.0,
        "ranges": [1.0] * 1_200_000,
    }
    async with published(sim, "/attack/scan", _type(sim, "sensor_msgs", "LaserScan"), scan):
        text = await session.error("view_scan", {"topic": "/attack/scan", "timeout": 20})
    assert "The scan declares 1,200,000 beams" in text
    assert LIMIT in text
