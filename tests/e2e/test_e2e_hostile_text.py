"""End to end: no string from the robot ends the server. A raw rosbridge client puts unpaired UTF-16
surrogates (``"\\ud800"`` in the JSON, which no text can hold) into every kind of field the server reads: a
log line, a topic's message, a service's reply, a name in rosapi's listings and a parameter's value. The
console script, on stdio (where one such string used to end the process) and on Streamable HTTP, reads
each through an MCP client session and keeps answering; the string reaches the model as U+FFFD."""

from __future__ import annotations

import asyncio
import contextlib
import json
import time
from collections.abc import AsyncIterator
from typing import Any

import pytest
import websockets
from e2e_transports import serving
from mcp.types import CallToolResult, TextContent
from websockets.asyncio.client import ClientConnection

from mcp import Client
from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 90.0  # a bound on an event, not a pause: a busy machine (load 20 on 2 cores) still passes
LOG_TOPICS = {"ros2": ("/rosout", "rcl_interfaces/msg/Log"), "ros1": ("/rosout_agg", "rosgraph_msgs/Log")}
#: A lone surrogate as JSON text carries it (json.dumps would write a valid escape of the str we give it).
LONE = "\\ud800"


def _with_lone_surrogate(op: dict[str, Any]) -> str:
    """*op* as JSON text, every ``@@`` in it written as an unpaired surrogate escape."""
    return json.dumps(op).replace("@@", LONE)


def _text(result: CallToolResult) -> str:
    return "\n".join(block.text for block in result.content if isinstance(block, TextContent))


async def _ok(session: Client, name: str, arguments: dict[str, Any]) -> CallToolResult:
    result = await asyncio.wait_for(session.call_tool(name, arguments), WAIT)
    assert not result.is_error, (name, _text(result))
    return result


@contextlib.asynccontextmanager
async def _hostile_peer(robot: SimulatedRobot, dialect: str) -> AsyncIterator[ClientConnection]:
    """A raw client that answers its service ``/hostile_trigger`` with a lone surrogate, and has advertised
    the log topic, ``/hostile_chatter`` and a topic whose very name holds one."""
    string = "std_msgs/msg/String" if dialect == "ros2" else "std_msgs/String"
    trigger = "std_srvs/srv/Trigger" if dialect == "ros2" else "std_srvs/Trigger"
    topic, log_type = LOG_TOPICS[dialect]
    async with websockets.connect(robot.url, max_size=None) as raw:
        await raw.send(json.dumps({"op": "advertise", "topic": topic, "type": log_type}))
        await raw.send(json.dumps({"op": "advertise", "topic": "/hostile_chatter", "type": string}))
        await raw.send(_with_lone_surrogate({"op": "advertise", "topic": "/hostile@@", "type": string}))
        await raw.send(
            json.dumps({"op": "advertise_service", "service": "/hostile_trigger", "type": trigger})
        )

        async def answer() -> None:
            async for frame in raw:
                request = json.loads(frame)
                if request.get("op") == "call_service":
                    reply = {
                        "op": "service_response",
                        "service": request["service"],
                        "id": request["id"],
                        "values": {"success": True, "message": "done @@ here"},
                        "result": True,
                    }
                    await raw.send(_with_lone_surrogate(reply))

        answering = asyncio.create_task(answer())
        try:
            yield raw
        finally:
            answering.cancel()


async def _while_publishing(raw: ClientConnection, op: str, call: Any) -> Any:
    """*call* awaited while *op* is published every 50 ms (a stream the call subscribes to mid-way)."""

    async def publish() -> None:
        while True:
            await raw.send(op)
            await asyncio.sleep(0.05)

    publishing = asyncio.create_task(publish())
    try:
        return await call
    finally:
        publishing.cancel()


@pytest.mark.parametrize("transport", ["stdio", "http"])
@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_lone_surrogates_in_every_field_the_server_reads_never_end_it(
    transport: str, dialect: str
) -> None:
    robot = SimulatedRobot(dialect=dialect, world="nav2")  # type: ignore[arg-type]
    async with (
        robot,
        _hostile_peer(robot, dialect) as raw,
        serving(transport, "--url", robot.url) as served,
        served.connect() as session,
    ):
        # A log line whose name, text and file hold one: read_logs and diagnose read it.
        line = {"level": 40 if dialect == "ros2" else 8, "name": "hostile@@node", "msg": "failed @@ twice"}
        line |= {"file": "a@@.cpp", "function": "f", "line": 1}
        started = time.monotonic()
        while "failed" not in _text(await _ok(session, "read_logs", {"level": "error"})):
            assert time.monotonic() - started < WAIT, "the log line never arrived"
            await raw.send(
                _with_lone_surrogate({"op": "publish", "topic": LOG_TOPICS[dialect][0], "msg": line})
            )
        logs = _text(await _ok(session, "read_logs", {"level": "error"}))
        assert "failed \ufffd twice" in logs
        assert "\ufffd" in _text(await _ok(session, "diagnose", {"focus": "logs"}))
        # A topic's message.
        chatter = _with_lone_surrogate(
            {"op": "publish", "topic": "/hostile_chatter", "msg": {"data": "hi @@"}}
        )
        message = await _while_publishing(
            raw,
            chatter,
            _ok(session, "subscribe_topic", {"topic": "/hostile_chatter", "count": 1, "timeout": 10}),
        )
        assert "hi \ufffd" in _text(message)
        # A service's reply.
        trigger = "std_srvs/srv/Trigger" if dialect == "ros2" else "std_srvs/Trigger"
        request = {"service": "/hostile_trigger", "service_type": trigger, "request": {}}
        reply = await _ok(session, "publish_service", request)
        assert "done \ufffd here" in _text(reply)
        # A name in rosapi's listings.
        assert "/hostile\ufffd" in _text(await _ok(session, "list_topics", {"filter": "hostile"}))
        # A parameter's value (ROS 1: rosapi's JSON text inside the frame, read as JSON by the server).
        if dialect == "ros2":
            value = {"type": 4, "string_value": "base@@"}
            args = {"parameters": [{"name": "base_frame_id", "value": value}]}
            await raw.send(
                _with_lone_surrogate({"op": "call_service", "service": "/amcl/set_parameters", "args": args})
            )
            name = "/amcl:base_frame_id"
        else:
            args = {"name": "/amcl/base_frame_id", "value": '"base@@"'}
            await raw.send(
                _with_lone_surrogate({"op": "call_service", "service": "/rosapi/set_param", "args": args})
            )
            name = "/amcl/base_frame_id"
        # ROS 2: read as U+FFFD where the frame is decoded; ROS 1: rosapi's JSON text inside the frame is read
        # later, and the answer shows the lone surrogate as an escape.
        shown = "base\ufffd" if dialect == "ros2" else "base\\ud800"
        started = time.monotonic()
        while shown not in _text(parameter := await _ok(session, "get_parameter", {"name": name})):
            assert time.monotonic() - started < WAIT, _text(parameter)
        # The server still answers.
        assert "/hostile_chatter" in _text(
            await _ok(session, "get_topic_info", {"topic": "/hostile_chatter"})
        )
