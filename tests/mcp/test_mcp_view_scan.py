"""view_scan through an MCP session: the simulated laser from above, and a point cloud, in both dialects."""

from __future__ import annotations

import base64
import io
import math
import struct
from typing import Any

import pytest
from mcp.types import CallToolResult, ImageContent
from mcp_harness import Session, open_session, text_of
from PIL import Image

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.pictures.drawing import OBSTACLE_COLOUR
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.nodes.room import PILLAR
from rosbridge_mcp_server.sim.world import TURTLE_ARENA, TURTLE_HOME


def picture_of(result: CallToolResult) -> Image.Image:
    images = [block for block in result.content if isinstance(block, ImageContent)]
    assert len(images) == 1
    return Image.open(io.BytesIO(base64.b64decode(images[0].data))).convert("RGB")


def red_near(image: Image.Image, at: tuple[float, float], reach: int = 2) -> bool:
    x0, y0 = round(at[0]), round(at[1])
    return any(
        all(abs(a - b) <= 16 for a, b in zip(image.getpixel((x, y)), OBSTACLE_COLOUR, strict=True))  # type: ignore[arg-type]
        for x in range(x0 - reach, x0 + reach + 1)
        for y in range(y0 - reach, y0 + reach + 1)
    )


def top_view_pixel(data: dict[str, Any], size: int, forward: float, left: float) -> tuple[float, float]:
    """Where a point (forward, left) of the sensor is drawn: forward up, left to the left."""
    scale = (size / 2 - 8) / data["radius"]
    return (size / 2 - left * scale, size / 2 - forward * scale)


async def test_the_wall_ahead_is_drawn_where_the_laser_hits_it(session: Session) -> None:
    """From the start the turtle faces the wall 5.54 m ahead: a red hit up the middle, the pillar nearest."""
    result = await session.ok("view_scan", {"radius": 8, "max_size": 500})
    data = result.structured_content
    assert data is not None
    image = picture_of(result)
    ahead = TURTLE_ARENA - TURTLE_HOME
    assert red_near(image, top_view_pixel(data, 500, ahead, 0.0))
    assert not red_near(image, top_view_pixel(data, 500, ahead / 2, 0.0), reach=4)
    cx, cy, radius = PILLAR
    to_pillar = math.hypot(cx - TURTLE_HOME, cy - TURTLE_HOME) - radius
    assert data["nearest"] == pytest.approx([to_pillar, 45.0], abs=0.02)
    assert data["frame_id"] == "base_scan"
    assert f"nearest obstacle {data['nearest'][0]:g} m at bearing 45°" in text_of(result)


async def test_free_sectors_leave_out_the_blocked_directions(session: Session, sim: SimulatedRobot) -> None:
    """Close to the right-hand wall (0.5 m), facing +x: the right is blocked for 1 m, ahead is free."""
    sim.world.turtle.y = 0.5
    result = await session.ok("view_scan", {"clearance": 1.0})
    data = result.structured_content
    assert data is not None
    sectors = data["free_sectors"]
    assert any(start <= 0 <= end for start, end in sectors)
    assert not any(start <= -90 <= end for start, end in sectors)


async def test_a_point_cloud_is_drawn_from_above(sim: SimulatedRobot) -> None:
    """A PointCloud2 of three points: the one 2 m ahead is drawn up the middle and is the nearest."""
    points = [(2.0, 0.0, 0.3), (3.0, 3.0, 0.0), (-4.0, 1.0, 1.0)]
    data = b"".join(struct.pack("<fff", *p) for p in points)
    cloud_type = "sensor_msgs/msg/PointCloud2" if sim.dialect == "ros2" else "sensor_msgs/PointCloud2"
    cloud = {
        "header": {"frame_id": "lidar3d"},
        "height": 1,
        "width": 3,
        "fields": [{"name": n, "offset": 4 * i, "datatype": 7, "count": 1} for i, n in enumerate("xyz")],
        "is_bigendian": False,
        "point_step": 12,
        "row_step": 36,
        "data": base64.b64encode(data).decode(),
        "is_dense": True,
    }
    async with RosbridgeClient(sim.url, connect_timeout=2.0, request_timeout=5.0) as publisher:
        await publisher.wait_connected(30.0)
        await publisher.publish("/test/points", cloud_type, cloud, latch=True)
        async with open_session(sim.url) as session:
            result = await session.ok("view_scan", {"topic": "/test/points", "max_size": 400})
    answer = result.structured_content
    assert answer is not None
    assert answer["points"] == 3
    assert answer["nearest"] == [2.0, 0.0]
    assert red_near(picture_of(result), top_view_pixel(answer, 400, 2.0, 0.0))


@pytest.mark.parametrize(
    ("arguments", "complaint"),
    [
        ({"topic": "/map"}, "topic: /map carries nav_msgs"),
        ({"topic": "/scann"}, "Topic /scann is not in the ROS graph. Did you mean /scan?"),
        ({"clearance": 0}, "clearance"),
    ],
)
async def test_bad_arguments_are_errors_naming_what_is_wrong(
    session: Session, arguments: dict[str, Any], complaint: str
) -> None:
    """A map topic, a misspelt topic or a zero clearance are isError answers."""
    assert complaint in await session.error("view_scan", arguments)
