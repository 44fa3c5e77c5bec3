"""A served console on a simulated robot, an MCP session on the same server, and a headless Chromium.

The browser is Debian's Chromium (``/usr/bin/chromium``, or ``CHROMIUM`` in the environment) driven by
Playwright from PyPI; Playwright's own browser download is never used. Without Chromium the browser tests skip
and say why; ``.ci/run`` installs it.

``race_harness.py`` builds its E-STOP races on :func:`served_console` (through a slow link, with longer
timeouts) and keeps only what is theirs: the delaying proxy, the raw watcher socket, the race itself.
"""

from __future__ import annotations

import asyncio
import importlib.util
import json
import os
import shutil
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from typing import Any
from urllib.parse import urlsplit

import pytest
from mcp.types import CallToolResult, TextContent

from mcp import Client
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.console import ConsoleHub, ConsoleSettings, RobotView
from rosbridge_mcp_server.console.serve import RunningConsole, open_console
from rosbridge_mcp_server.console.web import SECRET_HEADER
from rosbridge_mcp_server.robot.activity import SessionActivity
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import Audit, Operator, Policy, PolicyGuard
from rosbridge_mcp_server.server import build_server

CONNECT_WAIT = 30.0
#: How long a console request may take to answer.
HTTP_WAIT = 15.0

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
    """Chromium's path, or a skip saying what is missing: Playwright (the ``browser`` group) or Chromium."""
    if importlib.util.find_spec("playwright") is None:
        pytest.skip(
            "Playwright is not installed: `uv sync --group browser` (.ci/run does it), to run the console's "
            "browser tests"
        )
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
    robot: RobotSession
    audit: Audit

    @property
    def url(self) -> str:
        return self.running.url

    @property
    def activity(self) -> SessionActivity:
        return self.robot.activity

    async def call(self, name: str, arguments: dict[str, Any]) -> CallToolResult:
        return await self.mcp.call_tool(name, arguments)

    async def post(self, path: str) -> tuple[int, Any]:
        """POST *path* to the console with its secret, as the page does; (status, JSON answer)."""
        parts = urlsplit(self.running.base_url)
        assert parts.hostname is not None
        assert parts.port is not None
        reader, writer = await asyncio.open_connection(parts.hostname, parts.port)
        try:
            head = (
                f"POST {path} HTTP/1.1\r\nHost: {parts.hostname}:{parts.port}\r\nConnection: close\r\n"
                f"{SECRET_HEADER}: {self.running.secret}\r\nContent-Type: application/json\r\n"
                "Content-Length: 2\r\n\r\n{}"
            )
            writer.write(head.encode())
            await writer.drain()
            async with asyncio.timeout(HTTP_WAIT):
                raw = await reader.read()
        finally:
            writer.close()
        header, _, body = raw.partition(b"\r\n\r\n")
        return int(header.split()[1]), json.loads(body or b"null")


@asynccontextmanager
async def served_console(
    url: str,
    policy: Policy | None = None,
    elicitation_callback: Any = None,
    *,
    request_timeout: float = 5.0,
    connect_timeout: float = 2.0,
    connect_wait: float = CONNECT_WAIT,
) -> AsyncIterator[Console]:
    """The server as ``serve --console`` wires it (one operator, audit, guard and activity), on port 0; the
    MCP client answers elicitations with ``elicitation_callback`` when given (else it cannot ask).

    The rosbridge client has *request_timeout* and *connect_timeout*; the console opens once it has connected,
    within *connect_wait* seconds (a slow link wants more of all three)."""
    config = Config(
        url=url, request_timeout=request_timeout, connect_timeout=connect_timeout, policy=policy or Policy()
    )
    ros = RosbridgeClient(
        url,
        connect_timeout=connect_timeout,
        request_timeout=request_timeout,
        reconnect_min=0.05,
        reconnect_max=0.2,
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
        await ros.wait_connected(connect_wait)
        async with open_console(ConsoleSettings(port=0), hub) as running:
            yield Console(running, mcp, operator, robot, audit)
    finally:
        stop.set()
        await hosting


@asynccontextmanager
async def browser_page(console: Console) -> AsyncIterator[Any]:
    """A headless Chromium page on the console's one-time URL, once its event stream is live."""
    from playwright.async_api import async_playwright, expect

    executable = need_chromium()
    # An assertion's default wait (5 s) is not enough for a page on a busy two-core machine; a test that
    # means a bound (an audit line within a second) gives its own.
    expect.set_options(timeout=15_000)
    async with async_playwright() as playwright:
        browser = await playwright.chromium.launch(executable_path=executable, args=CHROMIUM_ARGS)
        try:
            page = await browser.new_page(viewport={"width": 1100, "height": 900})
            await page.goto(console.url)
            await expect(page.locator("#link")).to_have_text("live", timeout=30_000)
            yield page
        finally:
            await browser.close()
