"""The safety layer against a real rosbridge (ROS 1 or ROS 2, detected), watched by a raw subscriber.

Skipped unless ``ROSBRIDGE_TEST_URL`` names a bridge (see ``test_mcp_real_bridge.py``); the goal test also
needs ``ROSBRIDGE_TEST_ACTION`` / ``ROSBRIDGE_TEST_ACTION_TYPE`` (and ``ROSBRIDGE_TEST_ACTION_GOAL`` for a
goal that runs a few seconds). Velocity commands go only to ``/mcp_test/cmd_vel``, which nothing reads.

A real 0.11.17 bridge was seen handing a new subscriber messages published just before it subscribed, so each
test recognises its own messages by their values.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
from collections.abc import AsyncIterator
from typing import Any

import pytest
from mcp_harness import open_session, text_of
from websockets.asyncio.client import ClientConnection, connect

from rosbridge_mcp_server.safety import parse_policy

REAL_URL = os.environ.get("ROSBRIDGE_TEST_URL")
ACTION = os.environ.get("ROSBRIDGE_TEST_ACTION")
ACTION_TYPE = os.environ.get("ROSBRIDGE_TEST_ACTION_TYPE")
ACTION_GOAL: dict[str, Any] = json.loads(os.environ.get("ROSBRIDGE_TEST_ACTION_GOAL") or '{"order": 30}')

pytestmark = [
    pytest.mark.real_bridge,
    pytest.mark.skipif(
        REAL_URL is None, reason="set ROSBRIDGE_TEST_URL=ws://host:port to run against a real bridge"
    ),
]

WAIT = 10.0
TOPIC = "/mcp_test/cmd_vel"


class Watcher:
    """A raw rosbridge subscriber on its own socket: what reached the bridge, not what we think we sent."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        self.received: list[dict[str, Any]] = []
        self.changed = asyncio.Event()

    async def read(self) -> None:
        async for raw in self.ws:
            frame = json.loads(raw)
            if frame.get("op") == "publish" and frame.get("topic") == TOPIC:
                self.received.append(frame["msg"])
                self.changed.set()

    async def wait_for(self, count: int) -> None:
        async with asyncio.timeout(WAIT):
            while len(self.received) < count:
                self.changed.clear()
                await self.changed.wait()


async def twist_type() -> str:
    assert REAL_URL is not None
    async with connect(REAL_URL) as ws:
        await ws.send(json.dumps({"op": "call_service", "service": "/rosapi/get_ros_version", "id": "v"}))
        async with asyncio.timeout(WAIT):
            reply = json.loads(await ws.recv())
    # ROS 1 has no /rosapi/get_ros_version: the bridge answers it with result false.
    return "geometry_msgs/msg/Twist" if reply.get("result") else "geometry_msgs/Twist"


@contextlib.asynccontextmanager
async def watching(type_name: str) -> AsyncIterator[Watcher]:
    assert REAL_URL is not None
    async with connect(REAL_URL) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": TOPIC, "type": type_name}))
        watcher = Watcher(ws)
        reader = asyncio.create_task(watcher.read())
        try:
            yield watcher
        finally:
            reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reader


async def test_a_clamped_stream_reaches_the_bridge_capped_and_stop_robot_ends_it_with_a_zero() -> None:
    """Over the real bridge: a 2 m/s stream arrives at 0.5 m/s; stop_robot ends it, the last message zero."""
    assert REAL_URL is not None
    type_name = await twist_type()
    rules = parse_policy({"velocity": {"max_linear": 0.5, "mode": "clamp"}})
    async with (
        watching(type_name) as watcher,
        open_session(REAL_URL, guard=None, policy=rules, request_timeout=WAIT) as session,
    ):
        call = {"topic": TOPIC, "message_type": type_name, "message": {"linear": {"x": 2.0}}}
        streaming = asyncio.create_task(session.call("publish_topic", dict(call, rate_hz=10, duration=30)))
        await watcher.wait_for(3)
        stopped = await session.ok("stop_robot")
        streamed = await asyncio.wait_for(streaming, WAIT)
        count = len(watcher.received)
        # The stream's own closing zero and stop_robot's zero.
        await watcher.wait_for(count + 1 if watcher.received[-1]["linear"]["x"] != 0 else count)
    assert not streamed.is_error, text_of(streamed)
    assert "stop_robot ended the stream" in text_of(streamed)
    assert (stopped.structured_content or {})["zeroed_topics"] == [TOPIC]
    speeds = [message["linear"]["x"] for message in watcher.received]
    assert 2.0 not in speeds
    assert 0.5 in speeds
    assert speeds[-1] == 0.0


async def test_a_twist_over_the_cap_never_reaches_the_bridge() -> None:
    """Refused is refused on a real bridge too: the watcher sees only the command within the cap."""
    assert REAL_URL is not None
    type_name = await twist_type()
    rules = parse_policy({"velocity": {"max_linear": 0.5}})
    async with (
        watching(type_name) as watcher,
        open_session(REAL_URL, guard=None, policy=rules, request_timeout=WAIT) as session,
    ):
        text = await session.error(
            "publish_topic", {"topic": TOPIC, "message_type": type_name, "message": {"linear": {"x": 3.0}}}
        )
        await session.ok(
            "publish_topic", {"topic": TOPIC, "message_type": type_name, "message": {"linear": {"x": 0.25}}}
        )
        async with asyncio.timeout(WAIT):
            while 0.25 not in [message["linear"]["x"] for message in watcher.received]:
                watcher.changed.clear()
                await watcher.changed.wait()
    assert "max_linear 0.5 m/s; you asked 3" in text
    # The refused command was sent before the allowed one, so it would have arrived first.
    assert 3.0 not in [message["linear"]["x"] for message in watcher.received]


async def test_stop_robot_cancels_a_running_goal_on_the_real_action_server() -> None:
    """A goal started by publish_action ends cancelled (canceled / preempted) right after stop_robot."""
    if not ACTION or not ACTION_TYPE:
        pytest.skip("set ROSBRIDGE_TEST_ACTION and ROSBRIDGE_TEST_ACTION_TYPE to run the goal test")
    assert REAL_URL is not None
    async with open_session(REAL_URL, request_timeout=WAIT) as session:
        running = asyncio.Event()

        async def on_progress(progress: float, total: float | None, message: str | None) -> None:
            running.set()

        arguments = {"action_name": ACTION, "action_type": ACTION_TYPE, "goal": ACTION_GOAL, "timeout": 60}
        goal = asyncio.create_task(
            session.mcp.call_tool("publish_action", arguments, progress_callback=on_progress)
        )
        await asyncio.wait_for(running.wait(), WAIT)  # the first feedback: the goal runs
        stopped = await session.ok("stop_robot")
        ended = await asyncio.wait_for(goal, WAIT)
    assert len((stopped.structured_content or {})["goals_cancelled"]) == 1
    assert ended.structured_content is not None
    assert ended.structured_content["canceled_by"] == "stop_robot"
    assert ended.structured_content["status"] in ("canceled", "preempted")
