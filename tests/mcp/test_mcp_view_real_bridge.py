"""The picture tools through a real MCP session against a real rosbridge (ROS 1 or ROS 2, detected).

Skipped unless ``ROSBRIDGE_TEST_URL`` names a bridge (see ``test_mcp_real_bridge.py``). Test maps and values
go on topics under ``/mcp_test/`` of this run's own; the robot's own ``/map`` and ``/scan`` are read when it
has them (the ROS 2 lab built with tf2_msgs does).
"""

from __future__ import annotations

import asyncio
import base64
import io
import math
import os
from collections.abc import AsyncIterator
from typing import Any

import pytest
from mcp.types import CallToolResult, ImageContent
from mcp_harness import Session, open_session
from PIL import Image

from rosbridge_mcp_server.pictures.drawing import ROBOT_COLOUR
from rosbridge_mcp_server.pictures.maps import MARGIN_BOTTOM, MARGIN_LEFT

REAL_URL = os.environ.get("ROSBRIDGE_TEST_URL")

pytestmark = [
    pytest.mark.real_bridge,
    pytest.mark.skipif(
        REAL_URL is None, reason="set ROSBRIDGE_TEST_URL=ws://host:port to run against a real bridge"
    ),
]

WAIT = 10.0


@pytest.fixture
async def real() -> AsyncIterator[Session]:
    """An MCP session on the real bridge."""
    assert REAL_URL is not None
    async with open_session(REAL_URL, request_timeout=WAIT) as opened:
        yield opened


async def _type(real: Session, short_type: str) -> str:
    """The type in the bridge's spelling; skips the test when the robot does not have it."""
    package, name = short_type.split("/")
    msg_type = short_type if (await real.ros.ros_info()).version == 1 else f"{package}/msg/{name}"
    if (await real.call("describe_type", {"type_name": msg_type})).is_error:
        pytest.skip(f"{short_type} is not installed on this robot")
    return msg_type


async def _listed(real: Session, topic: str) -> None:
    """Until the bridge has registered the topic with the graph (ROS 1 master, ROS 2 discovery)."""

    async def listed() -> None:
        while not (await real.ros.call_service("/rosapi/topic_type", {"topic": topic})).get("type"):
            continue

    await asyncio.wait_for(listed(), WAIT)


def _picture(result: CallToolResult) -> Image.Image:
    (image,) = [block for block in result.content if isinstance(block, ImageContent)]
    return Image.open(io.BytesIO(base64.b64decode(image.data))).convert("RGB")


def _pixel(data: dict[str, Any], image: Image.Image, x: float, y: float) -> tuple[int, int]:
    ppm = data["pixels_per_metre"]
    return (
        round(MARGIN_LEFT + (x - data["window"][0]) * ppm),
        round(image.height - MARGIN_BOTTOM - (y - data["window"][1]) * ppm),
    )


async def test_a_test_map_is_drawn_cell_for_cell(real: Session) -> None:
    """A latched 40×30 test grid with a wall at x 2.0-2.1 m: the wall black, the rest white, 5% occupied."""
    msg_type = await _type(real, "nav_msgs/OccupancyGrid")
    cells = [100 if col == 20 else 0 for row in range(30) for col in range(40)]
    grid = {
        "header": {"frame_id": "mcp_test_map"},
        "info": {
            "resolution": 0.1,
            "width": 40,
            "height": 30,
            "origin": {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": {"w": 1.0}},
        },
        "data": cells,
    }
    topic = f"/mcp_test/map_{os.getpid()}"
    await real.ros.publish(topic, msg_type, grid, latch=True)
    await _listed(real, topic)
    result = await real.ok("view_map", {"topic": topic, "base_frame": "", "timeout": WAIT})
    data = result.structured_content
    assert data is not None
    assert (data["cells"], data["frame_id"], data["notes"]) == ([40, 30], "mcp_test_map", [])
    assert data["shares"]["occupied"] == pytest.approx(1 / 40)
    image = _picture(result)
    assert image.getpixel(_pixel(data, image, 2.05, 1.5)) == (0, 0, 0)
    assert image.getpixel(_pixel(data, image, 1.0, 1.5)) == (254, 254, 254)


async def test_the_robots_map_shows_it_where_tf_says_with_its_scan(real: Session) -> None:
    """The robot's own /map with /scan: the robot placed through /tf (a blue arrow there), hits drawn."""
    topics = {row["name"]: row["type"] for row in (await real.ok("list_topics")).structured_content["topics"]}
    if not topics.get("/map", "").endswith("OccupancyGrid") or "/scan" not in topics:
        pytest.skip("the robot has no /map and /scan")
    result = await real.ok("view_map", {"scan_topic": "/scan", "timeout": WAIT})
    data = result.structured_content
    assert data is not None
    assert data["notes"] == []
    assert data["scan_hits"] > 0
    x, y, _ = data["robot"]
    image = _picture(result)
    red, green, blue = image.getpixel(_pixel(data, image, x, y))  # type: ignore[misc]
    assert (red, green, blue) == pytest.approx(ROBOT_COLOUR, abs=16)


async def test_view_scan_finds_the_nearest_reading(real: Session) -> None:
    """view_scan's nearest obstacle is the smallest valid range of the robot's /scan (at rest)."""
    topics = {row["name"]: row["type"] for row in (await real.ok("list_topics")).structured_content["topics"]}
    if not topics.get("/scan", "").endswith("LaserScan"):
        pytest.skip("the robot has no /scan")
    read = await real.ok("subscribe_topic", {"topic": "/scan", "timeout": WAIT})
    ranges = read.structured_content["messages"][0]["message"]["ranges"]
    result = await real.ok("view_scan", {"topic": "/scan", "timeout": WAIT})
    data = result.structured_content
    assert data is not None
    assert data["nearest"][0] == pytest.approx(ranges["min"], abs=0.05)


async def test_plot_topic_charts_a_test_stream(real: Session) -> None:
    """A 10 Hz Float64 stream on a test topic: about 10 Hz, every sample 0.25."""
    msg_type = await _type(real, "std_msgs/Float64")
    topic = f"/mcp_test/value_{os.getpid()}"
    await real.ros.advertise(topic, msg_type)
    await _listed(real, topic)
    stream = {
        "topic": topic,
        "message_type": msg_type,
        "message": {"data": 0.25},
        "rate_hz": 10,
        "duration": 3,
    }
    streamed, plotted = await asyncio.gather(
        real.ok("publish_topic", stream),
        real.ok("plot_topic", {"series": [f"{topic} data"], "duration": 2}),
    )
    (series,) = plotted.structured_content["series"]
    assert series["samples"] >= 10
    assert (series["min"], series["max"], series["last"]) == (0.25, 0.25, 0.25)
    assert math.isclose(series["rate_hz"], 10, rel_tol=0.3)
    assert streamed.structured_content is not None
