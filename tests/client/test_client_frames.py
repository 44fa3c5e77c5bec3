"""Frames off the happy path: fragments reassembled; status, unknown, binary and malformed frames survived."""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import AsyncIterator
from typing import Any

import pytest
from client_harness import MakeClient, MakeSim
from websockets.asyncio.server import ServerConnection, serve

from rosbridge_mcp_server.errors import GoalTimeoutError, RequestTimeoutError, ServiceError
from rosbridge_mcp_server.robot.goals import GoalRegistry, running


async def test_fragmented_replies_and_messages_are_reassembled(
    make_sim: MakeSim, make_client: MakeClient
) -> None:
    """A bridge with a tiny fragment size splits every frame; calls and subscriptions still work."""
    robot = await make_sim(dialect="ros2", max_message_size=64)
    client = await make_client(robot)
    topics = await client.call_service("/rosapi/topics")
    assert "/chatter" in topics["topics"]
    async with client.subscribe("/chatter", "std_msgs/String", max_queue=1) as sub:
        assert (await sub.get(3.0))["data"].startswith("Hello")
    assert client.session is not None
    assembler = client.session.connection.conversation.decoder.assembler
    assert assembler.completed >= 2
    assert assembler.pending == 0


GARBAGE: list[str | bytes] = [
    b"\x00\x01binary",
    "{not json at all",
    "[1, 2, 3]",
    json.dumps({"op": "status", "level": "error", "msg": "a bridge that does send status"}),
    json.dumps({"op": "set_level", "level": "info"}),
    json.dumps({"op": "service_response", "id": "call_service:/nobody:999", "result": True, "values": {}}),
    json.dumps({"op": "publish", "topic": "/nobody_listens", "msg": {"data": 1}}),
    json.dumps({"op": "fragment", "id": "z", "data": "{", "num": 5, "total": 2}),
]


@pytest.fixture
async def noisy_bridge() -> AsyncIterator[str]:
    """A scripted bridge that answers every call_service with garbage first, then the real reply."""

    async def handle(ws: ServerConnection) -> None:
        async for raw in ws:
            request: dict[str, Any] = json.loads(raw)
            if request.get("op") != "call_service":
                continue
            for frame in GARBAGE:
                await ws.send(frame)
            values: dict[str, Any] = {"version": 2, "distro": "jazzy"}
            if request["service"] == "/echo":
                values = {"echo": request.get("args")}
            await ws.send(
                json.dumps(
                    {
                        "op": "service_response",
                        "service": request["service"],
                        "id": request["id"],
                        "result": True,
                        "values": values,
                    }
                )
            )

    async with serve(handle, "127.0.0.1", 0, compression=None) as server:
        port = server.sockets[0].getsockname()[1]
        yield f"ws://127.0.0.1:{port}"


async def test_unknown_status_binary_and_malformed_frames_are_logged_and_survived(
    noisy_bridge: str, make_client: MakeClient, caplog: pytest.LogCaptureFixture
) -> None:
    """Garbage frames never kill the reader: the reply after them still arrives, and they are logged."""
    caplog.set_level(logging.DEBUG, logger="rosbridge_mcp_server.client")
    client = await make_client(noisy_bridge)
    assert (await client.call_service("/echo", {"x": 1}))["echo"] == {"x": 1}
    assert (await client.call_service("/echo", {"x": 2}))["echo"] == {"x": 2}
    assert client.connections_made == 1
    logged = "\n".join(record.getMessage() for record in caplog.records)
    assert "binary frame" in logged
    assert "malformed JSON" in logged
    assert "not a JSON object" in logged
    assert "bridge status (error)" in logged
    assert "unsupported op 'set_level'" in logged
    assert "nobody awaits" in logged


@pytest.fixture
async def stalled_bridge() -> AsyncIterator[str]:
    """A bridge that answers the version query and then never reads another frame."""

    async def handle(ws: ServerConnection) -> None:
        # Other ops may come first (the client's probes on connecting): answer the version query wherever.
        while True:
            request = json.loads(await ws.recv())
            if request.get("service") == "/rosapi/get_ros_version":
                break
        reply = {
            "op": "service_response",
            "id": request["id"],
            "result": True,
            "values": {"version": 2, "distro": "jazzy"},
        }
        await ws.send(json.dumps(reply))
        await ws.wait_closed()

    async with serve(
        handle, "127.0.0.1", 0, compression=None, max_queue=1, max_size=None, close_timeout=0.2
    ) as server:
        port = server.sockets[0].getsockname()[1]
        yield f"ws://127.0.0.1:{port}"


async def test_publishing_to_a_bridge_that_stopped_reading_gives_up_at_the_deadline(
    stalled_bridge: str, make_client: MakeClient
) -> None:
    """When the socket is full, a publish waits on flow control only until its deadline."""
    client = await make_client(stalled_bridge, request_timeout=0.3)
    blob = {"data": "x" * 512 * 1024}

    async def flood() -> None:
        async with asyncio.timeout(30.0):
            for _ in range(500):
                await client.publish("/big", "std_msgs/String", blob)

    with pytest.raises(RequestTimeoutError, match="stopped reading"):
        await flood()


class RecordingBridge:
    """A scripted bridge that records every op per connection and answers only what it is told to."""

    def __init__(self, *, ros_version: bool = True) -> None:
        self.ops: list[tuple[int, dict[str, Any]]] = []
        self.ros_version = ros_version
        self.changed = asyncio.Event()
        self._connections = 0

    async def handle(self, ws: ServerConnection) -> None:
        self._connections += 1
        number = self._connections
        async for raw in ws:
            op: dict[str, Any] = json.loads(raw)
            self.ops.append((number, op))
            self.changed.set()
            if op.get("op") != "call_service":
                continue
            if op["service"] == "/rosapi/get_ros_version" and self.ros_version:
                values: Any = {"version": 2, "distro": "jazzy"}
                result = True
            else:
                values, result = f"Service {op['service']} does not exist", False
            reply = {"op": "service_response", "id": op["id"], "result": result, "values": values}
            await ws.send(json.dumps(reply))

    async def wait_for_op(self, name: str) -> tuple[int, dict[str, Any]]:
        """The first recorded op called *name*, waiting for it if need be."""
        async with asyncio.timeout(5.0):
            while True:
                for entry in self.ops:
                    if entry[1].get("op") == name:
                        return entry
                self.changed.clear()
                await self.changed.wait()


@pytest.fixture
async def recording_bridge() -> AsyncIterator[tuple[RecordingBridge, str]]:
    """A RecordingBridge on a loopback port, with its URL."""
    bridge = RecordingBridge()
    async with serve(bridge.handle, "127.0.0.1", 0, compression=None) as server:
        port = server.sockets[0].getsockname()[1]
        yield bridge, f"ws://127.0.0.1:{port}"


async def test_a_silent_goal_is_cancelled_on_the_main_connection_at_its_deadline(
    recording_bridge: tuple[RecordingBridge, str], make_client: MakeClient
) -> None:
    """A bridge that never answers a goal (Humble before 2.0.5): the cancel goes on the main connection and
    on the goal's own (rosbridge-server-rs lets only the connection that started a goal cancel it)."""
    bridge, url = recording_bridge
    client = await make_client(url)
    registry = GoalRegistry(client)
    with pytest.raises(GoalTimeoutError) as caught:
        await running.send_action_goal(
            registry, "/fibonacci", "example_interfaces/Fibonacci", {"order": 3}, timeout=0.2
        )
    assert caught.value.status is None
    goal_connection, goal = await bridge.wait_for_op("send_action_goal")
    cancels = [
        connection
        for connection, op in bridge.ops
        if op.get("op") == "cancel_action_goal" and op.get("id") == goal["id"]
    ]
    assert goal_connection != 1, "the goal runs on a lane of its own"
    assert sorted(cancels) == [1, goal_connection], "one cancel on the main connection, one on the goal's"
    assert goal["action_type"] == "example_interfaces/action/Fibonacci"


async def test_ros2_calls_carry_a_timeout_field_below_the_deadline(
    recording_bridge: tuple[RecordingBridge, str], make_client: MakeClient
) -> None:
    """call_service on ROS 2 sends `timeout`, a little under our deadline so the bridge answers first."""
    bridge, url = recording_bridge
    client = await make_client(url)
    with pytest.raises(ServiceError):
        await client.call_service("/anything", {"x": 1}, timeout=4.0)
    calls = [op for _, op in bridge.ops if op.get("service") == "/anything"]
    assert len(calls) == 1
    assert 3.0 < calls[0]["timeout"] < 4.0
    assert calls[0]["id"].startswith("call_service:/anything:")


async def test_without_rosapi_the_bridge_is_assumed_to_be_ros2_of_unknown_distro(
    make_client: MakeClient,
) -> None:
    """No get_ros_version and no /rosapi/topics: assume ROS 2 with Humble-era caution (in-order)."""
    bridge = RecordingBridge(ros_version=False)
    async with serve(bridge.handle, "127.0.0.1", 0, compression=None) as server:
        client = await make_client(f"ws://127.0.0.1:{server.sockets[0].getsockname()[1]}")
        info = await client.ros_info()
        await client.close()
    assert (info.version, info.distro, info.may_be_in_order) == (2, None, True)
