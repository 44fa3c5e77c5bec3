"""The console's pose and map panel in a real headless Chromium, and what listens only while a page is open.

The simulated robot's turtle world publishes a latched ``/map`` (frame ``map``) and ``/tf`` with
``map → world → odom → base_link``; the turtle's pose in ``world`` is the robot's pose in ``map``.
"""

from __future__ import annotations

import asyncio
import math

import pytest
from console_harness import browser_page, need_chromium, served_console

try:
    from playwright.async_api import expect
except ImportError:  # no browser group: need_chromium() skips the browser tests, saying how to install it
    expect = None  # type: ignore[assignment]

from rosbridge_mcp_server.console import ConsoleHub
from rosbridge_mcp_server.console.mapview import pose_of
from rosbridge_mcp_server.robot.transforms import FrameTree
from rosbridge_mcp_server.sim import SimulatedRobot

WAIT_MS = 30_000
CAMERA = "/camera/image_raw"

pytestmark = pytest.mark.usefixtures("chromium")


@pytest.fixture
def chromium() -> str:
    return need_chromium()


def subscribed(sim: SimulatedRobot, topic: str) -> bool:
    return any(topic in conn.subscriptions for conn in sim.bridge.connections.values())


async def hub_until(hub: ConsoleHub, holds: object, timeout: float = 10.0) -> None:
    """Wait (bounded) until ``holds()`` is true, woken by the hub's changes."""
    assert callable(holds)
    async with asyncio.timeout(timeout):
        while not holds():
            await hub.wait_changed(hub.marks(), 1.0)


async def test_the_panel_shows_the_turtles_pose_and_the_map(sim: SimulatedRobot) -> None:
    """The turtle at (3, 7) facing 60°: the panel says so (map → base_link) and draws the map as a PNG."""
    sim.world.turtle.x, sim.world.turtle.y, sim.world.turtle.theta = 3.0, 7.0, math.radians(60)
    async with served_console(sim.url) as console, browser_page(console) as page:
        pose = page.locator("#pose")
        await expect(pose).to_have_attribute("data-frame", "map", timeout=WAIT_MS)
        await expect(pose).to_have_attribute("data-x", "3", timeout=WAIT_MS)
        await expect(pose).to_have_attribute("data-y", "7")
        await expect(pose).to_have_attribute("data-yaw", "60")
        await expect(pose).to_contain_text("base_link in map: x 3.00 m, y 7.00 m, yaw 60.0°")
        image = page.locator("#map")
        await expect(image).to_be_visible(timeout=WAIT_MS)
        await page.wait_for_function("() => document.getElementById('map').naturalWidth > 0", timeout=WAIT_MS)
        source = await image.get_attribute("src")
        assert source is not None
        assert source.startswith("data:image/png;base64,")
        await expect(page.locator("#map-status")).to_contain_text("/map: 242x242 cells")


async def test_the_pose_follows_the_robot(sim_ros2: SimulatedRobot) -> None:
    """When the turtle moves, the shown pose moves with it (pushed, the page does not ask)."""
    async with served_console(sim_ros2.url) as console, browser_page(console) as page:
        pose = page.locator("#pose")
        await expect(pose).to_have_attribute("data-frame", "map", timeout=WAIT_MS)
        sim_ros2.world.turtle.x, sim_ros2.world.turtle.y = 8.5, 2.25
        await expect(pose).to_have_attribute("data-x", "8.5", timeout=WAIT_MS)
        await expect(pose).to_have_attribute("data-y", "2.25", timeout=WAIT_MS)


async def test_without_a_map_topic_the_panel_says_so_and_still_shows_the_pose(
    sim_ros2: SimulatedRobot,
) -> None:
    """A map topic the robot does not have: the panel names it, draws nothing, and keeps the pose."""
    async with served_console(sim_ros2.url) as console, browser_page(console) as page:
        await page.locator("#map-topic").fill("/no_map_here")
        await page.get_by_role("button", name="Use").click()
        await expect(page.locator("#map-status")).to_contain_text(
            "no map: /no_map_here is not in the robot's graph", timeout=WAIT_MS
        )
        await expect(page.locator("#map")).to_be_hidden()
        await expect(page.locator("#pose")).to_have_attribute("data-frame", "map", timeout=WAIT_MS)
        assert console.running.hub.map.topic == "/no_map_here"


async def test_an_unknown_base_frame_is_named(sim_ros2: SimulatedRobot) -> None:
    """A base frame /tf does not have: the panel says no pose and lists the frames it saw."""
    async with served_console(sim_ros2.url) as console, browser_page(console) as page:
        await page.locator("#map-base").fill("no_such_base")
        await page.get_by_role("button", name="Use").click()
        pose = page.locator("#pose")
        await expect(pose).to_contain_text("'no_such_base' has not been seen", timeout=WAIT_MS)
        await expect(pose).to_contain_text("base_link")
        assert await pose.get_attribute("data-x") is None


async def test_the_camera_and_the_panel_stop_listening_when_the_last_page_closes(
    sim_ros2: SimulatedRobot,
) -> None:
    """Closing the only page turns the camera off and ends its subscription and the map panel's."""
    async with served_console(sim_ros2.url) as console:
        hub = console.running.hub
        async with browser_page(console) as page:
            await page.locator("#camera-topic").fill(CAMERA)
            await page.get_by_role("button", name="Show").click()
            await expect(page.locator("#camera")).to_be_visible(timeout=WAIT_MS)
            await expect(page.locator("#pose")).to_have_attribute("data-frame", "map", timeout=WAIT_MS)
            assert subscribed(sim_ros2, CAMERA)
            assert subscribed(sim_ros2, "/map")
        await hub_until(hub, lambda: hub.viewers == 0)
        assert hub.camera_topic is None
        assert hub.snapshot()["camera"] == {"topic": None, "status": "off"}
        assert not hub.map.running
        await sim_ros2.wait_for(
            lambda world: not any(subscribed(sim_ros2, topic) for topic in (CAMERA, "/map", "/tf")),
            timeout=10,
        )


def link(parent: str, child: str, x: float, y: float, yaw: float) -> dict[str, object]:
    return {
        "header": {"frame_id": parent},
        "child_frame_id": child,
        "transform": {
            "translation": {"x": x, "y": y, "z": 0.0},
            "rotation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)},
        },
    }


def test_the_pose_is_in_map_when_there_is_one_else_in_odom() -> None:
    """Without a map frame the pose is odom's; once map → odom is heard, it is the map's."""
    tree = FrameTree()
    assert "no transform heard" in str(pose_of(tree, "base_link"))
    tree.add(link("odom", "base_link", 1.0, 2.0, math.radians(90)), static=False, received=1.0)
    found = pose_of(tree, "base_link")
    assert not isinstance(found, str), found
    frame, pose = found
    assert (frame, round(pose.x, 6), round(pose.y, 6), round(math.degrees(pose.yaw), 6)) == ("odom", 1, 2, 90)
    tree.add(link("map", "odom", 10.0, 0.0, 0.0), static=True, received=1.0)
    found = pose_of(tree, "base_link")
    assert not isinstance(found, str), found
    frame, pose = found
    assert (frame, round(pose.x, 6), round(pose.y, 6)) == ("map", 11, 2)
    assert "'nowhere' has not been seen" in str(pose_of(tree, "nowhere"))


def test_the_default_camera_is_the_colour_one() -> None:
    """Depth, infrared and compressed copies come after the colour image; a colour-named topic comes first."""
    from rosbridge_mcp_server.console.hub import default_camera

    simulated = ["/camera/depth/image_raw", "/camera/image_raw", "/camera/image_raw/compressed"]
    assert default_camera(simulated) == "/camera/image_raw"
    realsense = [
        "/camera/aligned_depth_to_color/image_raw",
        "/camera/color/image_raw",
        "/camera/color/image_raw/compressed",
        "/camera/infra1/image_rect_raw",
    ]
    assert default_camera(realsense) == "/camera/color/image_raw"
    assert default_camera(["/camera/depth/image_raw"]) == "/camera/depth/image_raw"
    assert default_camera([]) is None
