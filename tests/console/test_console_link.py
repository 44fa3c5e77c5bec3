"""Confirmations by link: a client that supports URL-mode elicitation sends the person to the console's
approval for that one call; the link carries a token for that call, never the console's secret."""

from __future__ import annotations

import asyncio
import re
from typing import Any
from urllib.parse import urlsplit

import httpx2
import pytest
from console_harness import CHROMIUM_ARGS, need_chromium, served_console, text_of
from mcp.types import ElicitRequestURLParams, ElicitResult

try:
    from playwright.async_api import async_playwright, expect
except ImportError:  # no browser group: need_chromium() skips the browser tests, saying how to install it
    async_playwright = expect = None  # type: ignore[assignment]

from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot

CMD_VEL = "/turtle1/cmd_vel"
TWIST = "geometry_msgs/msg/Twist"
WAIT_MS = 30_000
CALL = {"topic": CMD_VEL, "message_type": TWIST, "message": {"linear": {"x": 0.4}}}
POLICY = {"confirm": "motion", "confirm_timeout": 30}


def moving(sim: SimulatedRobot) -> list[float]:
    return [m.msg["linear"]["x"] for m in sim.world.published.get(CMD_VEL, [])]


def parts(url: str) -> tuple[str, str, str]:
    """The console's base URL, the confirmation's id and its token, from a link."""
    found = re.fullmatch(r"(http://127\.0\.0\.1:\d+/)#confirm=(c\d+)&token=([A-Za-z0-9_-]+)", url)
    assert found, url
    return found.group(1), found.group(2), found.group(3)


async def test_a_url_elicitation_sends_the_person_to_the_consoles_approval(sim_ros2: SimulatedRobot) -> None:
    """The client opens the link in Chromium; the page shows that call's question; Approve lets it through."""
    need_chromium()
    links: list[str] = []
    console_secret: list[str] = []

    async def open_link(context: Any, params: Any) -> ElicitResult:
        assert isinstance(params, ElicitRequestURLParams), params
        links.append(params.url)
        assert console_secret[0] not in params.url
        assert "secret" not in params.url
        async with async_playwright() as playwright:
            browser = await playwright.chromium.launch(executable_path=need_chromium(), args=CHROMIUM_ARGS)
            try:
                page = await browser.new_page()
                await page.goto(params.url)
                await expect(page.locator("#link-question")).to_contain_text(CMD_VEL, timeout=WAIT_MS)
                await expect(page.locator("#link-question")).to_contain_text("linear.x: 0.4")
                # The link is not the console: the robot's panels stay hidden without the secret.
                await expect(page.locator("#main")).to_be_hidden()
                assert moving(sim_ros2) == []
                await page.locator("#link-approve").click()
                await expect(page.locator("#link-status")).to_contain_text("Approved", timeout=WAIT_MS)
                # The token left the address bar with the fragment.
                assert "token" not in page.url
            finally:
                await browser.close()
        return ElicitResult(action="accept")

    async with served_console(sim_ros2.url, parse_policy(POLICY), open_link) as console:
        console_secret.append(console.running.secret)
        result = await asyncio.wait_for(console.call("publish_topic", CALL), 30)
        assert not result.is_error, text_of(result)
        await sim_ros2.wait_for(lambda world: moving(sim_ros2) == [0.4], timeout=5)
        assert len(links) == 1
        assert urlsplit(links[0]).netloc == urlsplit(console.running.base_url).netloc


async def test_a_links_token_answers_its_one_confirmation_and_nothing_else(sim_ros2: SimulatedRobot) -> None:
    """A wrong token reads and answers nothing; the right one cannot open the event stream or pick a camera;
    once used it is spent."""
    opened: asyncio.Future[str] = asyncio.get_running_loop().create_future()

    async def went_there(context: Any, params: Any) -> ElicitResult:
        # The person agreed to open the link; the answer itself is given on the console.
        opened.set_result(params.url)
        return ElicitResult(action="accept")

    checked: dict[str, int] = {}
    async with served_console(sim_ros2.url, parse_policy(POLICY), went_there) as console:
        calling = asyncio.create_task(console.call("publish_topic", CALL))
        base, pending_id, token = parts(await asyncio.wait_for(opened, 10))
        async with httpx2.AsyncClient(base_url=base, timeout=10) as http:
            wrong = {"X-Confirmation-Token": token[:-2] + ("BB" if token.endswith("AA") else "AA")}
            right = {"X-Confirmation-Token": token}
            checked["wrong read"] = (
                await http.get(f"/api/confirmations/{pending_id}", headers=wrong)
            ).status_code
            checked["wrong approve"] = (
                await http.post(f"/api/confirmations/{pending_id}/approve", headers=wrong)
            ).status_code
            checked["other id"] = (
                await http.post("/api/confirmations/c999/approve", headers=right)
            ).status_code
            checked["events"] = (await http.get("/api/events", headers=right)).status_code
            checked["camera"] = (
                await http.post("/api/camera", headers=right, json={"topic": ""})
            ).status_code
            checked["nothing sent yet"] = len(moving(sim_ros2))
            read = await http.get(f"/api/confirmations/{pending_id}", headers=right)
            checked["read"] = read.status_code
            checked["question names the topic"] = int(CMD_VEL in read.json().get("question", ""))
            checked["approve"] = (
                await http.post(f"/api/confirmations/{pending_id}/approve", headers=right)
            ).status_code
            result = await asyncio.wait_for(calling, 10)
            checked["again"] = (
                await http.post(f"/api/confirmations/{pending_id}/deny", headers=right)
            ).status_code
        assert not result.is_error, text_of(result)
    assert checked == {
        "wrong read": 403,
        "wrong approve": 403,
        "other id": 403,
        "events": 403,
        "camera": 403,
        "nothing sent yet": 0,
        "read": 200,
        "question names the topic": 1,
        "approve": 200,
        "again": 403,
    }
    assert moving(sim_ros2) == [0.4]


@pytest.mark.parametrize("action", ["decline", "cancel"])
async def test_declining_the_link_is_a_no(sim_ros2: SimulatedRobot, action: str) -> None:
    """The person declines to open the console: the call is refused at once and nothing reaches the robot."""

    async def refuse(context: Any, params: Any) -> ElicitResult:
        assert isinstance(params, ElicitRequestURLParams)
        return ElicitResult(action=action)  # type: ignore[arg-type]

    async with served_console(sim_ros2.url, parse_policy(POLICY), refuse) as console:
        result = await asyncio.wait_for(console.call("publish_topic", CALL), 10)
        assert result.is_error
        assert console.operator.pending == []
    assert moving(sim_ros2) == []


async def test_with_approvals_by_the_console_a_link_is_never_sent_to_the_requesters_client(
    sim_ros2: SimulatedRobot,
) -> None:
    """approvals = "console": a client that can open links gets none (its token would let the requester
    approve itself); the call waits for the console's person, and only their Approve lets it through."""
    links: list[str] = []

    async def open_link(context: Any, params: Any) -> ElicitResult:
        links.append(getattr(params, "url", repr(params)))
        return ElicitResult(action="accept")

    policy = parse_policy({**POLICY, "approvals": "console"})
    async with served_console(sim_ros2.url, policy, open_link) as console:
        waiting = asyncio.Event()
        console.operator.listen(lambda: waiting.set() if console.operator.pending else None)
        call = asyncio.create_task(console.call("publish_topic", CALL))
        await asyncio.wait_for(waiting.wait(), 10)
        (pending,) = console.operator.pending
        assert not pending.by_link
        assert links == []
        assert moving(sim_ros2) == []
        assert console.operator.answer(pending.id, approve=True)
        result = await asyncio.wait_for(call, 30)
        assert not result.is_error, text_of(result)
        await sim_ros2.wait_for(lambda world: moving(sim_ros2) == [0.4], timeout=5)
        assert links == []
