"""The audit says why a cancelled call ended, in words: a stream and a goal cancelled by the MCP client are
recorded as ``cancelled by the client``, never as a Python repr (``CancelledError: Cancelled via cancel scope
7f95… by <Task pending…>``), in both dialects."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any

import pytest
from mcp_harness import open_session, types_for

from rosbridge_mcp_server.robot.approval import Act, AskPerson
from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 30.0


class RecordingGuard:
    """Approves every act and keeps each outcome the seam records."""

    def __init__(self) -> None:
        self.records: list[tuple[str, str]] = []
        self.recorded = asyncio.Event()

    async def approve(self, act: Act, ask: AskPerson) -> Act:
        return act

    def record(self, act: Act, outcome: str) -> None:
        self.records.append((act.tool, outcome))
        self.recorded.set()

    def held(self) -> str | None:
        return None

    def send_interval(self, act: Act) -> float:
        return 0.0


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_a_stream_and_a_goal_cancelled_by_the_client_are_audited_as_such(
    make_sim: Callable[..., Awaitable[SimulatedRobot]], dialect: str
) -> None:
    robot = await make_sim(dialect=dialect, action_step=0.2)
    types = types_for(robot)
    guard = RecordingGuard()
    stream: dict[str, Any] = {
        "topic": "/turtle1/cmd_vel",
        "message_type": types["twist"],
        "message": {"linear": {"x": 0.2}},
        "rate_hz": 20,
        "duration": 30,
    }
    goal = {
        "action_name": "/fibonacci",
        "action_type": types["fibonacci"],
        "goal": {"order": 40},
        "timeout": 60,
    }
    async with open_session(robot.url, guard=guard) as session:
        streaming = asyncio.create_task(session.call("publish_topic", stream))
        await robot.world.wait_for(lambda w: len(w.published.get("/turtle1/cmd_vel", ())) >= 3, WAIT)
        streaming.cancel()
        with pytest.raises(asyncio.CancelledError):
            await streaming
        running = asyncio.create_task(session.call("publish_action", goal))
        await robot.world.wait_for(lambda w: any(g.feedback_count for g in w.goals.values()), WAIT)
        running.cancel()
        with pytest.raises(asyncio.CancelledError):
            await running
        try:
            async with asyncio.timeout(WAIT):
                while len(guard.records) < 2:
                    guard.recorded.clear()
                    await guard.recorded.wait()
        except TimeoutError:
            raise AssertionError(guard.records) from None
    outcomes = dict(guard.records)
    assert outcomes["publish_topic"].startswith("cancelled by the client after "), outcomes
    assert outcomes["publish_action"] == "cancelled by the client", outcomes
