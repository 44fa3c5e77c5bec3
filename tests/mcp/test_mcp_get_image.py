"""get_image through an MCP session: camera frames as MCP images, in both dialects."""

from __future__ import annotations

import array
import base64
import io
import sys
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import asynccontextmanager
from typing import Any

import pytest
from mcp.types import ImageContent
from mcp_harness import Session, open_session, text_of
from PIL import Image

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.sim import SimulatedRobot


def picture_of(result: Any) -> Image.Image:
    images = [block for block in result.content if isinstance(block, ImageContent)]
    assert len(images) == 1
    return Image.open(io.BytesIO(base64.b64decode(images[0].data)))


@asynccontextmanager
async def camera(robot: SimulatedRobot, topic: str, kind: str, msg: dict[str, Any]) -> AsyncIterator[None]:
    """Another client of the bridge that publishes one latched frame on ``topic``."""
    msg_type = f"sensor_msgs/msg/{kind}" if robot.dialect == "ros2" else f"sensor_msgs/{kind}"
    # 30 s: an 8 MB frame's publish (and the ping after it) on a busy machine.
    async with RosbridgeClient(robot.url, connect_timeout=10.0, request_timeout=30.0) as publisher:
        await publisher.wait_connected(30.0)
        await publisher.publish(topic, msg_type, msg, latch=True)
        yield


def frame(width: int, height: int, encoding: str, data: bytes, *, step: int) -> dict[str, Any]:
    return {
        "header": {"frame_id": "test_cam"},
        "height": height,
        "width": width,
        "encoding": encoding,
        "is_bigendian": 0,
        "step": step,
        "data": base64.b64encode(data).decode(),
    }


async def test_a_camera_frame_comes_back_as_an_image(session: Session) -> None:
    """The simulated camera's 160×120 rgb8 frame arrives as a JPEG with a line of metadata."""
    result = await session.ok("get_image", {"topic": "/camera/image_raw"})
    assert picture_of(result).format == "JPEG"
    assert picture_of(result).size == (160, 120)
    data = result.structured_content
    assert data is not None
    assert (data["encoding"], data["width"], data["height"], data["frame_id"]) == ("rgb8", 160, 120, "camera")
    assert text_of(result).startswith("/camera/image_raw: 160x120 rgb8 as jpeg, frame camera")


async def test_a_compressed_frame_is_resized_and_sent_as_png(session: Session) -> None:
    """The PNG CompressedImage comes back as PNG no larger than max_size."""
    result = await session.ok(
        "get_image", {"topic": "/camera/image_raw/compressed", "max_size": 80, "format": "png"}
    )
    picture = picture_of(result)
    assert (picture.format, picture.size) == ("PNG", (80, 60))
    assert "(sent 80x60)" in text_of(result)


async def test_a_full_hd_frame_passes_through(session: Session, sim: SimulatedRobot) -> None:
    """A 1920×1080 rgb8 frame (8 MB of base64) arrives and is sent 800 pixels wide."""
    width, height = 1920, 1080
    pixels = bytes([30, 60, 90]) * (width * height)
    async with camera(sim, "/test/full_hd", "Image", frame(width, height, "rgb8", pixels, step=width * 3)):
        result = await session.ok("get_image", {"topic": "/test/full_hd", "timeout": 10})
    assert picture_of(result).size == (800, 450)
    assert picture_of(result).getpixel((400, 200)) == pytest.approx((30, 60, 90), abs=3)


async def test_a_depth_frame_is_grey_with_its_range(session: Session, sim: SimulatedRobot) -> None:
    """A 32FC1 depth frame becomes grey, and the text gives the depth range in metres."""
    values = array.array("f", [0.5, 1.0, 2.0, float("nan")] * 4)
    if sys.byteorder == "big":
        values.byteswap()
    msg = frame(4, 4, "32FC1", values.tobytes(), step=16)
    async with camera(sim, "/test/depth", "Image", msg):
        result = await session.ok("get_image", {"topic": "/test/depth", "format": "png"})
    picture = picture_of(result)
    assert picture.mode == "L"
    assert [picture.getpixel((x, 0)) for x in range(4)] == [1, 85, 255, 0]
    assert "depth 0.5-2 m" in text_of(result)
    assert (result.structured_content or {})["depth_range"] == [0.5, 2.0]


async def test_an_unsupported_encoding_is_an_error_naming_it(session: Session, sim: SimulatedRobot) -> None:
    """A yuv422 frame is an error that names the encoding and the supported ones."""
    async with camera(sim, "/test/yuv", "Image", frame(2, 2, "yuv422", bytes(8), step=4)):
        text = await session.error("get_image", {"topic": "/test/yuv"})
    assert "'yuv422' is not supported" in text
    assert "rgb8" in text


async def test_a_topic_that_is_no_image_is_an_error(session: Session) -> None:
    """/chatter is refused as not an image, naming its type."""
    text = await session.error("get_image", {"topic": "/chatter"})
    assert "carries std_msgs" in text
    assert "not a sensor_msgs Image" in text


async def test_an_unknown_topic_lists_the_image_topics(session: Session) -> None:
    """A misspelt camera topic suggests the real one and lists the image topics."""
    text = await session.error("get_image", {"topic": "/camera/image_rw"})
    assert "Did you mean /camera/image_raw" in text
    assert "/camera/image_raw/compressed" in text


async def test_a_bad_format_is_an_argument_error(session: Session) -> None:
    """format gif is refused by the argument check."""
    text = await session.error("get_image", {"topic": "/camera/image_raw", "format": "gif"})
    assert "format" in text


async def test_the_simulated_depth_camera_is_grey_with_its_range_in_millimetres(session: Session) -> None:
    """The 16UC1 depth frame comes back grey with its nearest and farthest depth in mm."""
    result = await session.ok("get_image", {"topic": "/camera/depth/image_raw", "format": "png"})
    data = result.structured_content
    assert data is not None
    assert (data["encoding"], data["depth_unit"]) == ("16UC1", "mm")
    near, far = data["depth_range"]
    assert 0 < near < far
    assert picture_of(result).mode == "L"
    assert f"depth {near:g}-{far:g} mm" in text_of(result)


async def test_a_full_hd_frame_in_fragments_passes_through(
    make_sim: Callable[..., Awaitable[SimulatedRobot]],
) -> None:
    """A bridge run with `ros2 run` fragments above 1 MB: an 8 MB frame arrives in 9 pieces and works."""
    robot = await make_sim(dialect="ros2", max_message_size=1_000_000)
    width, height = 1920, 1080
    pixels = bytes([90, 60, 30]) * (width * height)
    async with (
        open_session(robot.url) as session,
        camera(robot, "/test/full_hd", "Image", frame(width, height, "rgb8", pixels, step=width * 3)),
    ):
        result = await session.ok("get_image", {"topic": "/test/full_hd", "timeout": 10})
    assert picture_of(result).size == (800, 450)
