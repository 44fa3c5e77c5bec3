"""Connecting in the background, detecting the bridge, reconnecting, and failing fast when down."""

from __future__ import annotations

import asyncio
import json
import logging
import time
from collections.abc import AsyncIterator
from typing import Any

import pytest
from client_harness import MakeClient, MakeSim, busy_lanes, unused_port
from websockets.asyncio.server import ServerConnection, serve

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.errors import ConnectionLostError, NotConnectedError
from rosbridge_mcp_server.sim import SimulatedRobot


async def test_start_returns_at_once_without_a_bridge_and_calls_name_the_url(make_client: MakeClient) -> None:
    """With nothing listening, start() returns, and a call raises NotConnectedError naming the URL."""
    url = f"ws://127.0.0.1:{unused_port()}"
    client = await make_client(url, connected=False, connect_timeout=0.5)
    assert not client.connected
    with pytest.raises(NotConnectedError) as caught:
        await client.call_service("/add_two_ints", {"a": 1, "b": 2})
    assert url in str(caught.value)
    with pytest.raises(NotConnectedError, match="nothing was sent"):
        await client.publish("/turtle1/cmd_vel", "geometry_msgs/Twist", {})


async def test_wait_connected_gives_up_after_its_timeout_with_the_last_error(make_client: MakeClient) -> None:
    """wait_connected raises NotConnectedError (with the reason) when no bridge appears in time."""
    client = await make_client(f"ws://127.0.0.1:{unused_port()}", connected=False)
    with pytest.raises(NotConnectedError, match=r"no connection within 0\.3 s"):
        await client.wait_connected(0.3)


async def test_client_connects_in_the_background_once_the_bridge_appears(make_client: MakeClient) -> None:
    """A client started before the robot connects on its own when the robot comes up."""
    port = unused_port()
    client = await make_client(f"ws://127.0.0.1:{port}", connected=False)
    async with SimulatedRobot(port=port, action_step=0.05, slow_service_seconds=1.0):
        await client.wait_connected(30.0)
        assert (await client.call_service("/add_two_ints", {"a": 2, "b": 3}))["sum"] == 5


async def _silent_server() -> tuple[asyncio.Server, int, asyncio.Event, list[asyncio.StreamWriter]]:
    """A TCP server that accepts and then says nothing, so a WebSocket handshake hangs."""
    accepted = asyncio.Event()
    writers: list[asyncio.StreamWriter] = []

    async def hold(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        writers.append(writer)
        accepted.set()

    server = await asyncio.start_server(hold, "127.0.0.1", 0)
    return server, server.sockets[0].getsockname()[1], accepted, writers


async def test_during_a_connection_attempt_publish_fails_at_once_but_reads_wait_for_it(
    make_client: MakeClient,
) -> None:
    """While an attempt is in progress publish raises at once; a read waits up to connect_timeout."""
    server, port, accepted, writers = await _silent_server()
    try:
        client = await make_client(f"ws://127.0.0.1:{port}", connected=False, connect_timeout=0.6)
        await asyncio.wait_for(accepted.wait(), 5.0)
        # The publish fails while the attempt it would have waited for is still under way: the read made
        # next still finds that attempt running and ends with its timeout, not with a refusal at once.
        with pytest.raises(NotConnectedError) as refused:
            await client.publish("/turtle1/cmd_vel", "geometry_msgs/Twist", {})
        assert "within" not in str(refused.value), "publish must never wait for a connection"
        started = time.monotonic()
        with pytest.raises(NotConnectedError, match=r"no WebSocket answer within 0\.6 s"):
            await client.call_service("/rosapi/topics")
        assert time.monotonic() - started >= 0.2, "a read waits for the attempt in progress"
    finally:
        server.close()
        for writer in writers:
            writer.close()
            await writer.wait_closed()
        await server.wait_closed()


@pytest.mark.parametrize(
    ("robot_kwargs", "version", "distro", "in_order"),
    [
        ({"dialect": "ros2"}, 2, "jazzy", False),
        ({"dialect": "ros2", "in_order": True}, 2, "humble", True),
        ({"dialect": "ros1"}, 1, None, False),
    ],
    ids=["jazzy", "humble", "ros1"],
)
async def test_ros_info_detects_the_dialect_of_the_bridge(
    make_sim: MakeSim,
    make_client: MakeClient,
    *,
    robot_kwargs: dict[str, Any],
    version: int,
    distro: str | None,
    in_order: bool,
) -> None:
    """get_ros_version tells ROS 2 and its distro (ROS 1 by its type names); in-order bridges are measured."""
    robot = await make_sim(**robot_kwargs)
    client = await make_client(robot)
    info = await client.ros_info()
    assert info.version == version
    assert info.distro == distro
    session = client.session
    assert session is not None
    # Measured on the bridge after connecting (the conftest's client waits for it).
    assert session.lanes_by_default is in_order


async def test_client_reconnects_after_the_bridge_drops_every_connection(
    sim: SimulatedRobot, make_client: MakeClient
) -> None:
    """After drop_connections the client reconnects by itself and later calls succeed."""
    client = await make_client(sim)
    await sim.drop_connections()
    await client.wait_disconnected(5.0)
    await client.wait_connected(30.0)
    assert (await client.call_service("/add_two_ints", {"a": 20, "b": 22}))["sum"] == 42
    assert client.connections_made == 2


async def test_a_call_in_flight_fails_fast_with_connection_lost_when_the_connection_drops(
    sim: SimulatedRobot, make_client: MakeClient
) -> None:
    """A slow service call in flight ends with ConnectionLostError at the drop, not at its timeout."""
    client = await make_client(sim)
    call = asyncio.create_task(client.call_service("/slow_service", timeout=20.0))
    await sim.wait_for(lambda world: world.service_calls.get("/slow_service", 0) >= 1)
    await sim.drop_connections()
    with pytest.raises(ConnectionLostError, match="/slow_service"):
        await asyncio.wait_for(call, 15.0)  # the call's own timeout is 20 s
    await client.wait_connected(30.0)
    assert (await client.call_service("/add_two_ints", {"a": 1, "b": 1}))["sum"] == 2


async def test_a_drop_on_humble_fails_calls_waiting_on_lanes_too(
    sim_humble: SimulatedRobot, make_client: MakeClient
) -> None:
    """Lanes are connections like any other: a call waiting on one fails at once on a drop."""
    client = await make_client(sim_humble)
    call = asyncio.create_task(client.call_service("/slow_service", timeout=20.0))
    await sim_humble.wait_for(lambda world: world.service_calls.get("/slow_service", 0) >= 1)
    await sim_humble.drop_connections()
    with pytest.raises(ConnectionLostError):
        await asyncio.wait_for(call, 15.0)
    await client.wait_connected(30.0)
    assert busy_lanes(client) == 0


async def test_close_is_idempotent_and_later_calls_raise_not_connected(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """close() twice is fine; afterwards every call raises NotConnectedError."""
    client = await make_client(sim_ros2)
    await client.close()
    await client.close()
    assert not client.connected
    with pytest.raises(NotConnectedError):
        await client.call_service("/add_two_ints", {"a": 1, "b": 1})
    with pytest.raises(NotConnectedError):
        await client.publish("/chatter", "std_msgs/String", {"data": "x"})


async def test_close_releases_every_connection_to_the_bridge(sim_humble: SimulatedRobot) -> None:
    """After close() the robot sees no connection from us, lanes included."""
    async with RosbridgeClient(sim_humble.url) as client:
        await client.wait_connected(30.0)
        await asyncio.gather(*(client.call_service("/add_two_ints", {"a": i, "b": 0}) for i in range(5)))
        assert sim_humble.connection_count >= 2
    await sim_humble.wait_for(lambda _world: sim_humble.connection_count == 0, 15.0)


@pytest.fixture
async def unread_probe_bridge() -> AsyncIterator[tuple[str, asyncio.Event]]:
    """A bridge that answers its first connection's calls (a Jazzy without status replies: the client
    measures call ordering) and never reads a frame on the others (the probe's two sockets); the event says
    both are open."""
    opened: list[ServerConnection] = []
    probing = asyncio.Event()

    async def handle(ws: ServerConnection) -> None:
        opened.append(ws)
        if len(opened) > 1:
            if len(opened) == 3:
                probing.set()
            await ws.wait_closed()
            return
        async for raw in ws:
            request: dict[str, Any] = json.loads(raw)
            if request.get("op") == "call_service":
                values = {"version": 2, "distro": "jazzy"}
                reply = {"op": "service_response", "id": request["id"], "result": True, "values": values}
                await ws.send(json.dumps(reply))

    # max_queue=1: a socket whose frames go unread stops being read, so its closing handshake never completes.
    async with serve(handle, "127.0.0.1", 0, compression=None, max_queue=1, close_timeout=0.2) as server:
        port = server.sockets[0].getsockname()[1]
        yield f"ws://127.0.0.1:{port}", probing


async def test_close_drops_a_call_ordering_probe_in_flight_at_once(
    unread_probe_bridge: tuple[str, asyncio.Event], make_client: MakeClient
) -> None:
    """close() cancels the connect-time ordering probe and drops its sockets without a closing handshake."""
    url, probing = unread_probe_bridge
    client = await make_client(url)
    await asyncio.wait_for(probing.wait(), 5.0)
    # close() waits for the client's background tasks, the probe included (its unadvertise is confirmed for up
    # to 1 s). 3 s is below what the unanswered probe takes on its own (5 s) and what a closing handshake
    # waits for its close frame (10 s).
    await asyncio.wait_for(client.close(), 3.0)
    assert client.closed
    assert client.session is None


async def _refusing_server(enough: int) -> tuple[asyncio.Server, int, asyncio.Event]:
    """A TCP server that closes every connection at once; the event is set after *enough* attempts."""
    attempts = [0]
    reached = asyncio.Event()

    async def refuse(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        attempts[0] += 1
        if attempts[0] >= enough:
            reached.set()
        writer.close()

    server = await asyncio.start_server(refuse, "127.0.0.1", 0)
    return server, server.sockets[0].getsockname()[1], reached


async def test_failed_attempts_are_logged_once_and_retried_with_backoff(
    make_client: MakeClient, caplog: pytest.LogCaptureFixture
) -> None:
    """Reconnect attempts go on (backing off); the warning is logged once, not per attempt."""
    caplog.set_level(logging.INFO, logger="rosbridge_mcp_server.client")
    server, port, four_attempts = await _refusing_server(4)
    try:
        await make_client(f"ws://127.0.0.1:{port}", connected=False, reconnect_min=0.02, reconnect_max=0.05)
        await asyncio.wait_for(four_attempts.wait(), 10.0)
    finally:
        server.close()
    warnings = [
        r for r in caplog.records if r.levelno >= logging.WARNING and "Cannot reach" in r.getMessage()
    ]
    assert len(warnings) == 1
