"""A bridge that sends garbage: one log line per bad frame, no traceback, and the connection keeps working."""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import AsyncIterator

import pytest
from websockets.asyncio.server import ServerConnection, serve

from rosbridge_mcp_server.client import RosbridgeClient

DEEP = "[" * 100_000 + "]" * 100_000

#: Frames a hostile or broken bridge might send; each must cost one log line and nothing else.
GARBAGE: list[str | bytes] = [
    "not json at all",
    "[1, 2, 3]",
    "42",
    "null",
    '"a string"',
    "{}",
    '{"op": 5}',
    '{"op": null, "id": "x"}',
    '{"op": ["publish"]}',
    '{"op": "publish", "topic": 5, "msg": "x"}',
    '{"op": "publish", "topic": "/chatter", "msg": [1, 2]}',
    '{"op": "publish", "topic": null}',
    '{"op": "service_response"}',
    '{"op": "action_result", "id": null, "values": 5}',
    '{"op": "fragment", "id": "f1", "data": 5, "num": "0", "total": null}',
    '{"op": "fragment", "id": {"a": 1}, "data": "x", "num": 0, "total": 2}',
    '{"op": "fragment", "id": "f2", "data": "x", "num": 7, "total": 2}',
    '{"op": "fragment", "id": "f4", "data": "not json", "num": 0, "total": 1}',
    '{"op": "fragment", "id": "f5", "data": "{\\"op\\": \\"fragment\\"}", "num": 0, "total": 1}',
    '{"op": "unknown_op", "id": "x"}',
    '{"op": "png", "data": "AAAA"}',
    '{"op": "set_level", "level": "debug"}',
    b"\x00\x01\x02 binary garbage",
    DEEP,
    '{"op": "publish", "topic": "/chatter", "msg": {"data": ' + DEEP + "}}",
    '{"op": "service_response", "id": 1' + "0" * 5000 + ', "result": true}',
    '{"op": "' + "x" * 100_000 + '"}',
]

#: Frames not wrong enough to log: fragments starting a (bounded) buffer, a publish nobody listens to.
QUIET: list[str | bytes] = [
    '{"op": "fragment", "id": "f3", "data": "x", "num": 0, "total": 1.0e308}',
    '{"op": "fragment", "id": "big", "data": "' + "x" * 2_000_000 + '", "num": 0, "total": 1000}',
    '{"op": "publish", "topic": "/chatter", "msg": {"data": "\\ud800"}}',
]


class HostileBridge:
    """A raw websockets server that answers version detection, then sends GARBAGE when asked."""

    def __init__(self) -> None:
        self.url = ""

    async def handler(self, ws: ServerConnection) -> None:
        async for raw in ws:
            request = json.loads(raw)
            if request.get("op") != "call_service":
                continue
            service = request["service"]
            if service == "/hostile/garbage":
                for frame in GARBAGE + QUIET:
                    await ws.send(frame)
            if service == "/hostile/fragments":
                chunk = "x" * 1_000_000
                for n in range(100):
                    await ws.send(
                        json.dumps({"op": "fragment", "id": f"f{n}", "data": chunk, "num": 0, "total": 9})
                    )
            values: dict[str, object] = {}
            if service == "/rosapi/get_ros_version":
                values = {"version": 2, "distro": "jazzy"}
            elif service == "/rosbridge_websocket/get_parameters":
                # It threads its calls, so the client keeps them on the one connection under test.
                values = {"values": [{"type": 1, "bool_value": True}] * 2}
            await ws.send(
                json.dumps(
                    {
                        "op": "service_response",
                        "id": request["id"],
                        "service": service,
                        "result": True,
                        "values": values,
                    }
                )
            )


@pytest.fixture
async def hostile() -> AsyncIterator[HostileBridge]:
    bridge = HostileBridge()
    async with serve(bridge.handler, "127.0.0.1", 0, max_size=None) as server:
        port = server.sockets[0].getsockname()[1]
        bridge.url = f"ws://127.0.0.1:{port}"
        yield bridge


async def test_garbage_frames_cost_one_log_line_each_and_nothing_else(
    hostile: HostileBridge, caplog: pytest.LogCaptureFixture
) -> None:
    """Every bad frame is logged once without a traceback; the connection answers the next call."""
    async with RosbridgeClient(hostile.url, reconnect_min=0.05, reconnect_max=0.2) as client:
        await client.wait_connected(30.0)
        caplog.clear()
        with caplog.at_level(logging.DEBUG, logger="rosbridge_mcp_server.client"):
            await client.call_service("/hostile/garbage", timeout=10.0)
            await asyncio.wait_for(client.call_service("/hostile/after", timeout=5.0), 15.0)
        records = [r for r in caplog.records if r.name == "rosbridge_mcp_server.client"]
        assert all(r.exc_info is None for r in records), [r.getMessage()[:200] for r in records if r.exc_info]
        bad = [r for r in records if r.levelno >= logging.INFO]
        assert len(bad) == len(GARBAGE), [r.getMessage()[:120] for r in bad]
        assert all(len(r.getMessage()) < 1000 for r in records)
        assert client.connected
        assert client.connections_made == 1


async def test_partial_fragments_from_a_bridge_leave_the_connection_answering(hostile: HostileBridge) -> None:
    """100 MB of fragments that never complete: the connection still answers (what the decoder holds of them
    is bounded: tests/protocol/test_protocol_inbound.py)."""
    async with RosbridgeClient(hostile.url, reconnect_min=0.05, reconnect_max=0.2) as client:
        await client.wait_connected(30.0)
        # On the main connection: a lane would hold the fragments (ordering is not measured here).
        await client.call_service("/hostile/fragments", timeout=20.0, isolated=False)
        await client.call_service("/hostile/after", timeout=5.0)
        assert client.connected
        assert client.connections_made == 1
