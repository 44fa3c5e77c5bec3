"""Effects and canonical names against a real rosbridge (ROS 1 or ROS 2, detected), watched from a raw socket.

Skipped unless ``ROSBRIDGE_TEST_URL`` names a bridge (see ``test_mcp_real_bridge.py``). Needs the lab's
``/fibonacci`` action server and ``/turtlesim`` (its ``background_r`` parameter). Every act here is refused,
so nothing of the lab changes; the parameter's value is read back from the robot to prove it.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import json
import os
from collections.abc import AsyncIterator
from typing import Any

import pytest
from mcp_harness import Session, open_session
from websockets.asyncio.client import ClientConnection, connect

from rosbridge_mcp_server.safety import parse_policy

REAL_URL = os.environ.get("ROSBRIDGE_TEST_URL")

pytestmark = [
    pytest.mark.real_bridge,
    pytest.mark.skipif(
        REAL_URL is None, reason="set ROSBRIDGE_TEST_URL=ws://host:port to run against a real bridge"
    ),
]

WAIT = 10.0
MARKER_TOPIC = "/mcp_test/effects_marker"
_ids = itertools.count(1)


class Watcher:
    """A raw rosbridge socket: what reached the bridge on the topics it subscribed to, and service calls."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        self.seen: dict[str, list[Any]] = {}
        self.changed = asyncio.Event()
        self.replies: dict[str, asyncio.Future[dict[str, Any]]] = {}

    async def read(self) -> None:
        async for raw in self.ws:
            frame = json.loads(raw)
            if frame.get("op") == "publish":
                self.seen.setdefault(frame["topic"], []).append(frame["msg"])
                self.changed.set()
            elif frame.get("op") == "service_response" and frame.get("id") in self.replies:
                self.replies.pop(frame["id"]).set_result(frame)

    async def call(self, service: str, args: dict[str, Any] | None = None) -> dict[str, Any]:
        request_id = f"effects:{next(_ids)}"
        reply: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self.replies[request_id] = reply
        message = {"op": "call_service", "id": request_id, "service": service, "args": args or {}}
        await self.ws.send(json.dumps(message))
        return await asyncio.wait_for(reply, WAIT)

    async def subscribe(self, topic: str, type_name: str) -> None:
        await self.ws.send(json.dumps({"op": "subscribe", "topic": topic, "type": type_name}))

    async def wait_for(self, topic: str, data: str) -> None:
        async with asyncio.timeout(WAIT):
            while not any(m.get("data") == data for m in self.seen.get(topic, [])):
                self.changed.clear()
                await self.changed.wait()


@contextlib.asynccontextmanager
async def watching() -> AsyncIterator[Watcher]:
    assert REAL_URL is not None
    async with connect(REAL_URL) as ws:
        watcher = Watcher(ws)
        reader = asyncio.create_task(watcher.read())
        try:
            yield watcher
        finally:
            reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reader


async def ros_version(watcher: Watcher) -> int:
    # ROS 1 has no /rosapi/get_ros_version: the bridge answers it with result false.
    reply = await watcher.call("/rosapi/get_ros_version")
    return 2 if reply.get("result") else 1


async def background_r(watcher: Watcher, version: int) -> Any:
    """/turtlesim's background_r as the robot holds it."""
    if version == 2:
        reply = await watcher.call("/turtlesim/get_parameters", {"names": ["background_r"]})
        return reply["values"]["values"][0]["integer_value"]
    reply = await watcher.call("/rosapi/get_param", {"name": "/turtlesim/background_r"})
    return json.loads(reply["values"]["value"])


async def barrier(session: Session, watcher: Watcher, version: int) -> None:
    """What the server sent before now has reached the watcher (one connection's frames arrive in order)."""
    marker = f"marker {next(_ids)}"
    kind = "std_msgs/msg/String" if version == 2 else "std_msgs/String"
    await session.ok(
        "publish_topic", {"topic": MARKER_TOPIC, "message_type": kind, "message": {"data": marker}}
    )
    await watcher.wait_for(MARKER_TOPIC, marker)


async def test_a_goal_sent_by_another_tool_meets_the_actions_deny_on_a_real_bridge() -> None:
    """ROS 1: publish_topic /fibonacci/goal; ROS 2: publish_service /fibonacci/_action/send_goal; refused by
    [actions] deny, and (ROS 1) nothing arrives on the goal topic."""
    assert REAL_URL is not None
    rules = parse_policy({"actions": {"deny": ["/fibonacci"]}, "confirm": "motion"})
    async with watching() as watcher:
        version = await ros_version(watcher)
        string = "std_msgs/msg/String" if version == 2 else "std_msgs/String"
        await watcher.subscribe(MARKER_TOPIC, string)
        if version == 1:
            await watcher.subscribe("/fibonacci/goal", "actionlib_tutorials/FibonacciActionGoal")
            tool = "publish_topic"
            call: dict[str, Any] = {
                "topic": "/fibonacci/goal",
                "message_type": "actionlib_tutorials/FibonacciActionGoal",
                "message": {"goal_id": {"id": "mcp-effects-attack"}, "goal": {"order": 3}},
            }
        else:
            tool = "publish_service"
            call = {
                "service": "/fibonacci/_action/send_goal",
                "service_type": "example_interfaces/action/Fibonacci_SendGoal",
                "request": {"goal_id": {"uuid": list(range(16))}, "goal": {"order": 3}},
            }
        async with open_session(REAL_URL, guard=None, policy=rules, request_timeout=WAIT) as session:
            text = await session.error(tool, call)
            await barrier(session, watcher, version)
    assert "[actions] deny '/fibonacci' matches /fibonacci" in text
    assert "a goal of action /fibonacci" in text
    assert "/fibonacci/goal" not in watcher.seen


async def test_odd_parameter_spellings_and_parameter_services_meet_the_parameters_deny_on_a_real_bridge() -> (
    None
):
    """The findings' spellings through set_parameter, and the parameter services through publish_service, are
    refused by one deny rule; /turtlesim's background_r keeps its value on the robot."""
    assert REAL_URL is not None
    async with watching() as watcher:
        version = await ros_version(watcher)
        before = await background_r(watcher, version)
        if version == 2:
            deny = "/turtlesim:*"
            names = ["/turtlesim/:background_r", "/turtlesim//:background_r"]
            service_call: dict[str, Any] = {
                "service": "/turtlesim/set_parameters",
                "service_type": "rcl_interfaces/srv/SetParameters",
                "request": {
                    "parameters": [
                        {"name": "background_r", "value": {"type": 2, "integer_value": before ^ 1}}
                    ]
                },
            }
        else:
            deny = "/turtlesim/background_r"
            names = ["/turtlesim/background_r/", "//turtlesim/background_r", "/turtlesim//background_r"]
            service_call = {
                "service": "/rosapi/set_param",
                "service_type": "rosapi/SetParam",
                "request": {"name": "/turtlesim//background_r", "value": json.dumps(before ^ 1)},
            }
        rules = parse_policy({"parameters": {"deny": [deny]}})
        async with open_session(REAL_URL, guard=None, policy=rules, request_timeout=WAIT) as session:
            texts = [
                await session.error("set_parameter", {"name": name, "value": before ^ 1}) for name in names
            ]
            texts.append(await session.error("publish_service", service_call))
        after = await background_r(watcher, version)
    assert after == before
    assert all(f"[parameters] deny {deny!r}" in text for text in texts), texts
