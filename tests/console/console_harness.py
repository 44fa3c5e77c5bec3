"""A served console on a simulated robot, an MCP session on the same server, and a headless Chromium.

The browser is Debian's Chromium (``/usr/bin/chromium``, or ``CHROMIUM`` in the environment) driven by
Playwright from PyPI; Playwright's own browser download is never used. Without Chromium the browser tests skip
and say why; ``.ci/run`` installs it.
"""

from __future__ import annotations

import asyncio
import os
import shutil
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from typing import Any

import pytest
from mcp.types import CallToolResult, TextContent

from mcp import Client
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.console import ConsoleHub, ConsoleSettings, RobotView
from rosbridge_mcp_server.console.serve import RunningConsole, open_console
from rosbridge_mcp_server.robot.activity import SessionActivity
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import Audit, Operator, Policy, PolicyGuard
from rosbridge_mcp_server.server import build_server

CONNECT_WAIT = 5.0

CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
]


def chromium_path() -> str | None:
    """Debian's Chromium, or the one ``CHROMIUM`` names; ``None`` when there is none."""
    named = os.environ.get("CHROMIUM")
    if named:
        return named if os.path.exists(named) else None
    return shutil.which("chromium") or shutil.which("chromium-browser")


def need_chromium() -> str:
    path = chromium_path()
    if path is None:
        pytest.skip(
            "Chromium is not installed: `apt-get install -y chromium` (as root; .ci/run does it), or set "
            "CHROMIUM to a Chromium binary, to run the console's browser tests"
        )
    return path


def text_of(result: CallToolResult) -> str:
    return "\n".join(block.text for block in result.content if isinstance(block, TextContent))


@dataclass
class Console:
    """A console being served, the MCP session on the same server, and what both share."""

    running: RunningConsole
    mcp: Client
    operator: Operator
    activity: SessionActivity

    @property
    def url(self) -> str:
        return self.running.url

    async def call(self, name: str, arguments: dict[str, Any]) -> CallToolResult:
        return await self.mcp.call_tool(name, arguments)


@asynccontextmanager
async def served_console(
    url: str, policy: Policy | None = None, elicitation_callback: Any = None
) -> AsyncIterator[Console]:
    """The server as ``serve --console`` wires it (one operator, audit, guard and activity), on port 0; the
    MCP client answers elicitations with ``elicitation_callback`` when given (else it cannot ask)."""
    config = Config(url=url, request_timeout=5.0, connect_timeout=2.0, policy=policy or Policy())
    ros = RosbridgeClient(
        url, connect_timeout=2.0, request_timeout=5.0, reconnect_min=0.05, reconnect_max=0.2
    )
    operator = Operator()
    audit = Audit()
    robot = RobotSession(ros, PolicyGuard(config.policy, audit, operator))
    hub = ConsoleHub([RobotView("robot", robot, audit)], operator)
    ready: asyncio.Future[Client] = asyncio.get_running_loop().create_future()
    stop = asyncio.Event()

    async def host() -> None:
        try:
            server = build_server(robot, config, console_view=hub.snapshot)
            async with Client(server, mode="legacy", elicitation_callback=elicitation_callback) as mcp:
                ready.set_result(mcp)
                await stop.wait()
        except BaseException as exc:
            if not ready.done():
                ready.set_exception(exc)
            raise

    hosting = asyncio.create_task(host())
    try:
        mcp = await ready
        await ros.wait_connected(CONNECT_WAIT)
        async with open_console(ConsoleSettings(port=0), hub) as running:
            yield Console(running, mcp, operator, robot.activity)
    finally:
        stop.set()
        await hosting


@asynccontextmanager
async def browser_page(console: Console) -> AsyncIterator[Any]:
    """A headless Chromium page on the console's one-time URL, once its event stream is live."""
    from playwright.async_api import async_playwright, expect

    executable = need_chromium()
    async with async_playwright() as playwright:
        browser = await playwright.chromium.launch(executable_path=executable, args=CHROMIUM_ARGS)
        try:
            page = await browser.new_page(viewport={"width": 1100, "height": 900})
            await page.goto(console.url)
            await expect(page.locator("#link")).to_have_text("live", timeout=10_000)
            yield page
        finally:
            await browser.close()
