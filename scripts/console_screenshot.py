"""Take docs/images/console.png: the operator console on the simulated robot, in headless Chromium.

    uv run python scripts/console_screenshot.py [--out docs/images/console.png] [--lost lost.png]

Needs Debian's Chromium (/usr/bin/chromium, or CHROMIUM=...). The scene: confirm = "motion", a chatter
message sent, a velocity command approved, a Fibonacci goal running, another command waiting for Approve,
the camera on (the page's default camera), the pose and the map. ``--lost FILE``: then the robot's bridge
stops, and a second picture shows the page marking the last pose, map and frame stale.
"""

from __future__ import annotations

import argparse
import asyncio
import io
import sys
from pathlib import Path

from PIL import Image
from playwright.async_api import async_playwright, expect

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "console"))

from console_harness import CHROMIUM_ARGS, Console, need_chromium, served_console

from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot

CMD_VEL = "/turtle1/cmd_vel"
TWIST = "geometry_msgs/msg/Twist"


async def approve_next(console: Console) -> None:
    """Approve the next confirmation the operator is asked (waits on the operator's change signal)."""
    operator = console.operator
    changed = asyncio.Event()
    operator.listen(changed.set)
    async with asyncio.timeout(10):
        while not operator.pending:
            await changed.wait()
            changed.clear()
    operator.answer(operator.pending[-1].id, approve=True)


async def main(out: Path, lost: Path | None = None) -> None:
    policy = parse_policy(
        {
            "confirm": "motion",
            "confirm_timeout": 60,
            "velocity": {"max_linear": 0.5, "mode": "clamp"},
            "services": {"deny": ["/reset"]},
        }
    )
    async with SimulatedRobot(port=0, action_step=0.5) as robot, served_console(robot.url, policy) as console:
        await console.call(
            "publish_topic",
            {
                "topic": "/chatter",
                "message_type": "std_msgs/msg/String",
                "message": {"data": "hello from the assistant"},
            },
        )
        moving = asyncio.create_task(
            console.call(
                "publish_topic", {"topic": CMD_VEL, "message_type": TWIST, "message": {"linear": {"x": 0.3}}}
            )
        )
        await approve_next(console)
        await moving
        await console.call(
            "publish_service", {"service": "/reset", "service_type": "std_srvs/srv/Empty", "request": {}}
        )
        goal = asyncio.create_task(
            console.call(
                "publish_action",
                {
                    "action_name": "/fibonacci",
                    "action_type": "example_interfaces/action/Fibonacci",
                    "goal": {"order": 40},
                    "timeout": 60,
                },
            )
        )
        await approve_next(console)
        waiting = asyncio.create_task(
            console.call(
                "publish_topic",
                {
                    "topic": CMD_VEL,
                    "message_type": TWIST,
                    "message": {"linear": {"x": 0.8}, "angular": {"z": 0.4}},
                },
            )
        )
        async with async_playwright() as playwright:
            browser = await playwright.chromium.launch(executable_path=need_chromium(), args=CHROMIUM_ARGS)
            page = await browser.new_page(viewport={"width": 1100, "height": 860})
            await page.goto(console.url)
            await expect(page.locator("#link")).to_have_text("live", timeout=10_000)
            await expect(page.locator("#camera-topic")).not_to_have_value("", timeout=10_000)
            await page.get_by_role("button", name="Show").click()
            await page.wait_for_function("() => document.getElementById('camera').naturalWidth > 0")
            await page.wait_for_function("() => document.getElementById('map').naturalWidth > 0")
            await expect(page.locator("#pose")).to_have_attribute("data-frame", "map", timeout=10_000)
            await expect(page.locator("#pending li")).to_have_count(1, timeout=10_000)
            await expect(page.locator("#running li")).to_have_count(1, timeout=10_000)
            png = await page.screenshot(full_page=True)
            if lost is not None:
                await robot.stop()
                await expect(page.locator("#map-stale")).to_be_visible(timeout=10_000)
                await expect(page.locator("#camera-stale")).to_be_visible(timeout=10_000)
                await page.screenshot(path=str(lost), full_page=True)
                print(f"{lost}: the robot lost")
            await browser.close()
        picture = Image.open(io.BytesIO(png)).convert("RGB").quantize(colors=128)
        out.parent.mkdir(parents=True, exist_ok=True)
        picture.save(out, optimize=True)
        print(f"{out}: {len(png)} bytes before quantizing")
        for task in (waiting, goal):
            task.cancel()
        await asyncio.gather(waiting, goal, return_exceptions=True)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs/images/console.png"))
    parser.add_argument("--lost", type=Path, help="also a picture of the page after the robot is lost")
    arguments = parser.parse_args()
    asyncio.run(main(arguments.out, arguments.lost))
