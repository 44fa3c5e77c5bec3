"""Our tasks with a tasks client no one here wrote: FastMCP's (``fastmcp-tasks``) over our stdio (on the
simulated Nav2 world in both dialects) and over Streamable HTTP with a bearer token. The client lives in its
own virtual environment (never a dependency of ours): ``ROSBRIDGE_MCP_TASKS_PEER`` names its Python, else
``/work/scratch-tasks/bin/python``; ``.ci/run`` makes one. Without it the test is skipped, saying so."""

from __future__ import annotations

import asyncio
import json
import math
import os
import sys
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import pytest
from e2e_transports import TOKEN, serving

from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]

PEER = Path(os.environ.get("ROSBRIDGE_MCP_TASKS_PEER", "/work/scratch-tasks/bin/python"))
SCRIPT = Path(__file__).with_name("tasks_peer.py")
WAIT = 180.0

pytestmark = pytest.mark.skipif(
    not PEER.exists(),
    reason=f"no Python with fastmcp-tasks at {PEER} (set ROSBRIDGE_MCP_TASKS_PEER; .ci/run makes one)",
)


@pytest.mark.timeout(WAIT + 60)  # the peer's own bound, above the suite's 150 s
@pytest.mark.parametrize(("transport", "dialect"), [("stdio", "ros2"), ("stdio", "ros1"), ("http", "ros2")])
async def test_fastmcp_tasks_client_polls_a_drive_and_cancels_another(
    make_sim: MakeSim, transport: str, dialect: str
) -> None:
    robot = await make_sim(dialect=dialect, world="nav2")
    robot.nav2.navigator.speed = 8.0
    if transport == "stdio":
        seen = await _peer("stdio", sys.executable, robot.url)
    else:
        async with serving("http", "--url", robot.url) as served:
            seen = await _peer("http", served.url, TOKEN)
    assert seen["status"] == "completed"
    assert any("m to go" in message for message in seen["messages"]), seen["messages"]
    assert seen["succeeded"]
    assert seen["kinds"] == ["image", "text"]
    assert seen["transparent"]
    status, message = seen["cancelled"]
    assert status == "cancelled"
    assert "Cancelled by the client (tasks/cancel)" in message
    # The cancel reached the robot: it stopped short of the far goal.
    body = robot.nav2.robots[0]
    await robot.wait_for(lambda world: body.linear == 0.0 and body.angular == 0.0, timeout=10.0)
    assert math.hypot(body.x - 1.5, body.y - 9.0) > 0.5


async def _peer(*arguments: str) -> dict[str, Any]:
    process = await asyncio.create_subprocess_exec(
        str(PEER), str(SCRIPT), *arguments, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE
    )
    out, err = await asyncio.wait_for(process.communicate(), WAIT)
    assert process.returncode == 0, err.decode(errors="replace")[-3000:]
    seen: dict[str, Any] = json.loads(out.decode().strip().splitlines()[-1])
    return seen
