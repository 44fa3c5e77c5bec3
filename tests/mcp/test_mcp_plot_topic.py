"""plot_topic through an MCP session: the turtle's pose and odometry over time, in both dialects."""

from __future__ import annotations

import asyncio
import base64
import io
import time
from typing import Any

import pytest
from mcp.types import CallToolResult, ImageContent
from mcp_harness import Session, text_of
from PIL import Image

from rosbridge_mcp_server.pictures.drawing import SERIES_COLOURS
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.world import TURTLE_HOME


def picture_of(result: CallToolResult) -> Image.Image:
    images = [block for block in result.content if isinstance(block, ImageContent)]
    assert len(images) == 1
    return Image.open(io.BytesIO(base64.b64decode(images[0].data))).convert("RGB")


def has_colour(image: Image.Image, colour: tuple[int, int, int]) -> bool:
    """Whether the picture has a pixel of about this colour (the PNG is palette-quantised)."""
    return any(
        all(abs(a - b) <= 16 for a, b in zip(pixel, colour, strict=True))
        for _, pixel in image.getcolors(maxcolors=1 << 16) or []
    )


async def test_a_moving_turtle_shows_in_pose_and_odometry(session: Session, sim: SimulatedRobot) -> None:
    """Driven at 1 m/s for its one-second command: x rises about a metre, odometry's speed goes 1 then 0."""
    turtle = sim.world.turtle
    series = ["/turtle1/pose x", "/odom twist.twist.linear.x"]
    plotting = asyncio.create_task(session.ok("plot_topic", {"series": series, "duration": 1.5}))
    # Driven once the plot listens (a loaded machine may open its subscriptions late): it sees the start.
    await sim.wait_for(lambda _: all(sim.bridge.has_subscribers(t) for t in ("/turtle1/pose", "/odom")), 10)
    turtle.linear, turtle.command_time = 1.0, time.monotonic()
    result = await asyncio.wait_for(plotting, 10)
    data = result.structured_content
    assert data is not None
    pose, odom = data["series"]
    assert (pose["topic"], pose["field"], pose["unit"]) == ("/turtle1/pose", "x", "m")
    assert pose["min"] == pytest.approx(TURTLE_HOME, abs=0.15)
    # It rose; by how much depends on how much of the drive fell in the window (0.47 m at a load of 20).
    assert pose["max"] - pose["min"] > 0.2
    # The observed rates: the simulator publishes pose at 25 Hz and odometry at 20 Hz, or slower on a loaded
    # machine, never faster (a lower bound here failed under load: 17 Hz).
    assert 2 / 1.5 <= pose["rate_hz"] <= 25 * 1.3
    assert (odom["unit"], odom["max"], odom["last"]) == ("m/s", 1.0, 0.0)
    assert 2 / 1.5 <= odom["rate_hz"] <= 20 * 1.3
    image = picture_of(result)
    assert has_colour(image, SERIES_COLOURS[0])
    assert has_colour(image, SERIES_COLOURS[1])
    assert "/odom twist.twist.linear.x (m/s): min 0 max 1" in text_of(result)
    assert session.progress
    assert all(total == 1.5 and 0 < done <= 1.5 for done, total, _ in session.progress)


async def test_several_fields_of_one_topic_come_from_the_same_messages(session: Session) -> None:
    """ "/turtle1/pose x y" is two series with the same sample count."""
    result = await session.ok("plot_topic", {"series": ["/turtle1/pose x y"], "duration": 0.5})
    data = result.structured_content
    assert data is not None
    x, y = data["series"]
    assert (x["field"], y["field"]) == ("x", "y")
    assert x["samples"] == y["samples"] > 3


async def test_a_silent_topic_is_an_error_after_the_duration(session: Session) -> None:
    """Nobody publishes /turtle1/cmd_vel: an error saying nothing arrived."""
    text = await session.error("plot_topic", {"series": ["/turtle1/cmd_vel linear.x"], "duration": 0.3})
    assert "No message arrived on /turtle1/cmd_vel within 0.3 s" in text


@pytest.mark.parametrize(
    ("arguments", "complaint"),
    [
        (
            {"series": ["/odom twist.twist.linear.q"]},
            "there is no 'q' in twist.twist.linear; the fields there",
        ),
        ({"series": ["/odom"]}, "needs a topic and at least one field"),
        (
            {"series": ["/odm pose.pose.position.x"]},
            "Topic /odm is not in the ROS graph. Did you mean /odom?",
        ),
        (
            {"series": ["/turtle1/pose x y theta linear_velocity angular_velocity", "/odom a b c d"]},
            "at most 8",
        ),
        ({"series": []}, "series"),
        ({"series": ["/odom twist.twist.linear.x"], "duration": 0}, "duration"),
    ],
)
async def test_bad_arguments_are_errors_naming_what_is_wrong(
    session: Session, arguments: dict[str, Any], complaint: str
) -> None:
    """A wrong field is caught on the first message; malformed series and limits at once."""
    assert complaint in await session.error("plot_topic", {"duration": 5, **arguments})
