"""The operator console in a real headless Chromium: what the person sees, and what their buttons do.

Each test drives the page as a person would (clicks on Approve, Deny, E-STOP, Release) while an MCP client
calls tools on the same server; what reached the robot is read on the simulated robot's side.
"""

from __future__ import annotations

import asyncio
import re
from typing import Any

import pytest
from console_harness import browser_page, need_chromium, served_console, text_of

try:
    from playwright.async_api import expect
except ImportError:  # no browser group: need_chromium() skips the browser tests, saying how to install it
    expect = None  # type: ignore[assignment]

from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot

CMD_VEL = "/turtle1/cmd_vel"
TWIST = "geometry_msgs/msg/Twist"
#: The issue's bound for an acting call to show on the page (a bounded wait on the DOM, in milliseconds).
SHOWS_WITHIN_MS = 1_000
#: Longer waits: a browser starting, and calls answered, on a busy two-core machine.
WAIT = 30.0
WAIT_MS = int(WAIT * 1000)

pytestmark = pytest.mark.usefixtures("chromium")


@pytest.fixture
def chromium() -> str:
    return need_chromium()


def twist_call(x: float, **extra: Any) -> dict[str, Any]:
    return {"topic": CMD_VEL, "message_type": TWIST, "message": {"linear": {"x": x}}, **extra}


def moving(sim: SimulatedRobot) -> list[float]:
    return [m.msg["linear"]["x"] for m in sim.world.published.get(CMD_VEL, [])]


async def test_an_acting_call_shows_on_the_page_as_it_happens(sim_ros2: SimulatedRobot) -> None:
    """A publish_topic call appears at the top of the acting calls within a second, pushed, not polled."""
    async with served_console(sim_ros2.url) as console, browser_page(console) as page:
        await expect(page.locator("#robots")).to_contain_text("connected", timeout=WAIT_MS)
        await expect(page.locator("#robots")).to_contain_text("ROS 2")
        result = await console.call("publish_topic", twist_call(0.3))
        assert not result.is_error, text_of(result)
        newest = page.locator("#audit li").first
        await expect(newest).to_contain_text(CMD_VEL, timeout=SHOWS_WITHIN_MS)
        await expect(newest).to_contain_text("publish_topic")
        await expect(newest).to_contain_text("allowed")
        # Every time on the page is 24-hour local time (the E-STOP's too), never a 12-hour one beside it.
        await expect(newest.locator(".time")).to_have_text(re.compile(r"^\d\d:\d\d:\d\d$"))


async def test_approve_lets_a_waiting_motion_through(sim_ros2: SimulatedRobot) -> None:
    """confirm = "motion" with a client that cannot ask: the call waits for the console; Approve sends it."""
    policy = parse_policy({"confirm": "motion", "confirm_timeout": 30})
    async with served_console(sim_ros2.url, policy) as console, browser_page(console) as page:
        calling = asyncio.create_task(console.call("publish_topic", twist_call(0.4)))
        waiting = page.locator("#pending li")
        await expect(waiting).to_contain_text(CMD_VEL, timeout=WAIT_MS)
        assert moving(sim_ros2) == []
        await waiting.get_by_role("button", name="Approve").click()
        result = await asyncio.wait_for(calling, WAIT)
        assert not result.is_error, text_of(result)
        await sim_ros2.wait_for(lambda world: moving(sim_ros2) == [0.4], timeout=WAIT)
        await expect(page.locator("#pending li")).to_have_count(0, timeout=WAIT_MS)
        await expect(page.locator("#audit li").first).to_contain_text("confirmed", timeout=WAIT_MS)


async def test_deny_refuses_a_waiting_motion(sim_ros2: SimulatedRobot) -> None:
    """Deny is a no: the model is told the person declined, and nothing reaches the robot."""
    policy = parse_policy({"confirm": "motion", "confirm_timeout": 30})
    async with served_console(sim_ros2.url, policy) as console, browser_page(console) as page:
        calling = asyncio.create_task(console.call("publish_topic", twist_call(0.4)))
        waiting = page.locator("#pending li")
        await expect(waiting).to_contain_text(CMD_VEL, timeout=WAIT_MS)
        await waiting.get_by_role("button", name="Deny").click()
        result = await asyncio.wait_for(calling, WAIT)
        assert result.is_error
        assert "declined" in text_of(result)
        assert moving(sim_ros2) == []
        await expect(page.locator("#audit li").first).to_contain_text("refused", timeout=WAIT_MS)


async def test_estop_stops_a_running_stream_and_refuses_acting_calls_until_release(
    sim_ros2: SimulatedRobot,
) -> None:
    """E-STOP ends a 10 Hz stream with a zero (at most two more commands once pressed), then latches."""
    async with served_console(sim_ros2.url) as console, browser_page(console) as page:
        streaming = asyncio.create_task(
            console.call("publish_topic", twist_call(0.5, rate_hz=10, duration=30))
        )
        await sim_ros2.wait_for(lambda world: len(world.published.get(CMD_VEL, [])) >= 3, timeout=WAIT)
        await expect(page.locator("#running li")).to_contain_text(CMD_VEL, timeout=WAIT_MS)
        # Counted from the moment the server latched (its first step), not from the click: a loaded
        # machine's browser may take a while to send the request, which is not the stop's doing.
        at_latch: list[int] = []
        console.operator.listen(
            lambda: (
                at_latch.append(len(moving(sim_ros2))) if console.operator.latched and not at_latch else None
            )
        )
        await page.get_by_role("button", name="E-STOP").click()
        result = await asyncio.wait_for(streaming, WAIT)
        assert not result.is_error, text_of(result)
        assert text_of(result).startswith("E-STOP on the operator console ended the stream")
        # The stream's closing zero and the e-stop's own zero reach the robot last.
        await sim_ros2.wait_for(lambda world: moving(sim_ros2)[-2:] == [0.0, 0.0], timeout=WAIT)
        after = moving(sim_ros2)[at_latch[0] :]
        # 200 ms at 10 Hz is two commands: the stream must end within that.
        assert len([x for x in after if x != 0.0]) <= 2
        await expect(page.locator("#latched")).to_be_visible(timeout=WAIT_MS)
        await expect(page.locator("#running li")).to_have_count(0, timeout=WAIT_MS)

        sent = len(moving(sim_ros2))
        refused = await console.call("publish_topic", twist_call(0.2))
        assert refused.is_error
        assert "E-STOP" in text_of(refused)
        refused_service = await console.call(
            "publish_service", {"service": "/reset", "service_type": "std_srvs/srv/Empty", "request": {}}
        )
        assert refused_service.is_error
        assert len(moving(sim_ros2)) == sent

        await page.get_by_role("button", name="Release").click()
        await expect(page.locator("#latched")).to_be_hidden(timeout=WAIT_MS)
        # Release is good news: not in the red of refusals and of the e-stop.
        released = page.locator("#audit li").first.locator(".outcome")
        await expect(released).to_have_text("e-stop released", timeout=WAIT_MS)
        # Asked until it holds: the page redraws the audit list as events arrive, and a style read from a node
        # that was just replaced is empty.
        await expect(released).to_have_css("color", "rgb(45, 122, 45)", timeout=WAIT_MS)
        allowed = await console.call("publish_topic", twist_call(0.2))
        assert not allowed.is_error, text_of(allowed)
        await sim_ros2.wait_for(lambda world: moving(sim_ros2)[-1] == 0.2, timeout=WAIT)


async def test_the_camera_frame_appears(sim_ros2: SimulatedRobot) -> None:
    """The operator picks a camera topic, and a JPEG frame of the robot's camera shows."""
    async with served_console(sim_ros2.url) as console, browser_page(console) as page:
        await page.locator("#camera-topic").fill("/camera/image_raw")
        await page.get_by_role("button", name="Show").click()
        image = page.locator("#camera")
        await expect(image).to_be_visible(timeout=WAIT_MS)
        await expect(image).to_have_attribute("data-topic", "/camera/image_raw")
        await page.wait_for_function(
            "() => document.getElementById('camera').naturalWidth > 0", timeout=WAIT_MS
        )
        source = await image.get_attribute("src")
        assert source is not None
        assert source.startswith("data:image/jpeg;base64,")


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_the_page_without_the_secret_says_so_and_its_estop_stops_the_robot(
    make_sim: Any, dialect: str
) -> None:
    """Opened without the URL's secret (a bookmark, a second tab), the page says it can only stop, shows no
    robot data, Approve or Release; its E-STOP ends a 10 Hz stream and says what it stopped."""
    from console_harness import CHROMIUM_ARGS
    from playwright.async_api import async_playwright

    sim = await make_sim(dialect=dialect)
    twist = TWIST if dialect == "ros2" else "geometry_msgs/Twist"
    call = {"topic": CMD_VEL, "message_type": twist, "message": {"linear": {"x": 0.5}}}
    async with served_console(sim.url) as console, async_playwright() as playwright:
        browser = await playwright.chromium.launch(executable_path=need_chromium(), args=CHROMIUM_ARGS)
        try:
            page = await browser.new_page()
            await page.goto(console.running.base_url)
            await expect(page.locator("#no-secret")).to_be_visible(timeout=WAIT_MS)
            await expect(page.locator("#no-secret")).to_contain_text("E-STOP works")
            await expect(page.locator("#audit-section")).to_be_hidden()
            await expect(page.locator("#pending-section")).to_be_hidden()
            await expect(page.get_by_role("button", name="Release")).to_be_hidden()
            streaming = asyncio.create_task(
                console.call("publish_topic", {**call, "rate_hz": 10, "duration": 30})
            )
            await sim.world.wait_for(lambda world: len(world.published.get(CMD_VEL, [])) >= 3, timeout=WAIT)
            await page.get_by_role("button", name="E-STOP").click()
            result = await asyncio.wait_for(streaming, WAIT)
            assert text_of(result).startswith("E-STOP on the operator console ended the stream"), text_of(
                result
            )
            shown = page.locator("#stopped")
            await expect(shown).to_contain_text("E-STOP latched", timeout=WAIT_MS)
            await expect(shown).to_contain_text(f"ended streams on {CMD_VEL}")
            assert console.operator.latched == "console"
            await expect(page.get_by_role("button", name="Release")).to_be_hidden()
            refused = await console.call("publish_topic", call)
            assert refused.is_error
            assert "E-STOP" in text_of(refused)
        finally:
            await browser.close()


async def test_the_colour_camera_is_the_default_and_the_map_keeps_its_aspect(
    sim_ros2: SimulatedRobot,
) -> None:
    """The picker offers the colour camera (not the depth image that sorts first), and a map shrunk to a
    narrow column keeps its width-to-height ratio (round obstacles stay round)."""
    async with served_console(sim_ros2.url) as console, browser_page(console) as page:
        await page.set_viewport_size({"width": 420, "height": 900})
        await expect(page.locator("#camera-topic")).to_have_value("/camera/image_raw", timeout=WAIT_MS)
        picture = page.locator("#map")
        await expect(picture).to_be_visible(timeout=WAIT_MS)
        shown = await picture.evaluate(
            "img => [img.clientWidth, img.clientHeight, img.naturalWidth, img.naturalHeight]"
        )
        width, height, natural_width, natural_height = shown
        assert width < natural_width, f"the map was not shrunk: {shown}"
        assert width / height == pytest.approx(natural_width / natural_height, rel=0.01), shown
        # The pose wraps between its parts only: every number with its unit stays on one line.
        await expect(page.locator("#pose span").first).to_be_visible(timeout=WAIT_MS)
        for part in await page.locator("#pose span").all():
            await expect(part).to_have_css("white-space", "nowrap", timeout=WAIT_MS)


async def test_a_lost_robot_marks_the_last_pose_map_and_frame_stale(sim_ros2: SimulatedRobot) -> None:
    """The robot's bridge stops: the last map, frame and pose stay, each marked "stale since HH:MM:SS", the
    robot is "not connected since", and the model's long error text is shown nowhere (not twice)."""
    sim = sim_ros2
    async with served_console(sim.url) as console, browser_page(console) as page:
        await page.get_by_role("button", name="Show").click()
        await expect(page.locator("#camera")).to_be_visible(timeout=WAIT_MS)
        await expect(page.locator("#map")).to_be_visible(timeout=WAIT_MS)
        await expect(page.locator("#pose")).to_contain_text("yaw", timeout=WAIT_MS)
        await expect(page.locator("#map-stale")).to_be_hidden()

        await sim.stop()
        await expect(page.locator("#robots")).to_contain_text("not connected since", timeout=WAIT_MS)
        for mark in ("#map-stale", "#camera-stale"):
            await expect(page.locator(mark)).to_be_visible(timeout=WAIT_MS)
            await expect(page.locator(mark)).to_contain_text(re.compile(r"stale since \d\d:\d\d:\d\d"))
        # The last pictures stay under the mark; the pose keeps its numbers, marked too.
        await expect(page.locator("#map")).to_be_visible()
        await expect(page.locator("#camera")).to_be_visible()
        await expect(page.locator("#pose")).to_contain_text("stale since")
        await expect(page.locator("#map-status")).to_be_hidden()
        body = await page.locator("body").inner_text()
        assert "Not connected to rosbridge" not in body, body

        await sim.start()
        await expect(page.locator("#map-stale")).to_be_hidden(timeout=WAIT_MS)
        await expect(page.locator("#pose")).not_to_contain_text("stale", timeout=WAIT_MS)


async def test_a_failed_estop_says_so_on_the_page(sim_ros2: SimulatedRobot) -> None:
    """When the console cannot be reached, the press says E-STOP FAILED rather than nothing."""
    async with served_console(sim_ros2.url) as console, browser_page(console) as page:
        # The console's own server goes away under the open page (as when the MCP server was stopped).
        await page.route("**/api/estop", lambda route: route.abort())
        await page.get_by_role("button", name="E-STOP").click()
        await expect(page.locator("#stopped")).to_contain_text("E-STOP FAILED", timeout=WAIT_MS)
        assert console.operator.latched is None
