"""Every tool against a bridge whose rosapi answers with the wrong shapes: an answer, never a crash."""

from __future__ import annotations

import json
import logging
from collections.abc import AsyncIterator
from typing import Any

import pytest
from mcp_harness import open_session, text_of
from websockets.asyncio.server import ServerConnection, serve

#: What a broken or hostile bridge could put in ``values`` of a successful service response.
WRONG_VALUES: list[Any] = [
    5,
    "x",
    [1, 2],
    None,
    {},
    {"topics": 5, "types": None},
    {"topics": ["/a", 3], "types": [1]},
    {"services": [None]},
    {"type": 7},
    {"typedefs": [{"type": 5, "fieldnames": "x"}]},
    {
        "typedefs": [
            {"type": "std_msgs/String", "fieldnames": ["data"], "fieldtypes": [3], "fieldarraylen": ["a"]}
        ]
    },
    {"action_servers": [1, None]},
    {"publishers": "x", "subscribers": 5},
]
#: Arguments that reach the bridge for the tools that take some (others are called with none).
ARGUMENTS: dict[str, dict[str, Any]] = {
    "get_topic_info": {"topic": "/a"},
    "publish_topic": {"topic": "/a", "message_type": "std_msgs/msg/String", "message": {"data": "x"}},
    "publish_service": {"service": "/a", "service_type": "std_srvs/srv/Trigger", "timeout": 1},
    "publish_action": {"action_name": "/f", "action_type": "a/action/F", "timeout": 1},
    "cancel_action": {"action_name": "/f"},
}


class WrongRosapi:
    """Answers version detection properly, then every service call with ``self.values``."""

    def __init__(self) -> None:
        self.values: Any = None
        self.url = ""

    async def handler(self, ws: ServerConnection) -> None:
        async for raw in ws:
            request = json.loads(raw)
            if request.get("op") != "call_service":
                continue
            values = self.values
            if request["service"] == "/rosapi/get_ros_version":
                values = {"version": 2, "distro": "jazzy"}
            reply = {
                "op": "service_response",
                "id": request["id"],
                "service": request["service"],
                "result": True,
            }
            await ws.send(json.dumps(reply | {"values": values}))


@pytest.fixture
async def bridge() -> AsyncIterator[WrongRosapi]:
    wrong = WrongRosapi()
    async with serve(wrong.handler, "127.0.0.1", 0) as server:
        wrong.url = f"ws://127.0.0.1:{server.sockets[0].getsockname()[1]}"
        yield wrong


async def test_every_tool_answers_wrong_shapes_with_a_result_and_no_traceback(
    bridge: WrongRosapi, caplog: pytest.LogCaptureFixture
) -> None:
    """Each tool, each wrong shape: a result (not the generic error), the connection kept, no traceback."""
    async with open_session(bridge.url, request_timeout=2.0) as session:
        tools = [tool.name for tool in (await session.mcp.list_tools()).tools]
        with caplog.at_level(logging.INFO):
            for values in WRONG_VALUES:
                bridge.values = values
                for tool in tools:
                    result = await session.call(tool, ARGUMENTS.get(tool, {}))
                    assert "Error executing tool" not in text_of(result), (tool, values)
        assert session.ros.connections_made == 1
    assert not [r for r in caplog.records if r.exc_info], [
        r.getMessage()[:200] for r in caplog.records if r.exc_info
    ]
