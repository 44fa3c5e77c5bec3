"""The client on the simulated robot's in-memory transport: what a socket would show, shown without one."""

from __future__ import annotations

import asyncio

import pytest
from client_harness import MakeClient, MakeSim

from rosbridge_mcp_server.errors import NotConnectedError
from rosbridge_mcp_server.sim import SimulatedRobot


@pytest.fixture
def sim_in_memory() -> bool:
    """Every robot here opens no port."""
    return True


async def test_a_robot_started_in_memory_opens_no_port_and_answers_calls(
    sim: SimulatedRobot, make_client: MakeClient
) -> None:
    """No listening socket; the client detects the bridge, measures its ordering and gets its replies."""
    client = await make_client(sim)
    assert not sim.listening
    assert sim.connection_count >= 1
    assert (await client.call_service("/add_two_ints", {"a": 2, "b": 3}))["sum"] == 5
    assert (await client.ros_info()).version == (2 if sim.dialect == "ros2" else 1)


async def test_a_dropped_connection_says_its_close_code_and_the_client_reconnects(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """drop_connections closes with 1001 as on a socket; the client comes back by itself."""
    client = await make_client(sim_ros2)
    first = client.session
    assert first is not None
    await sim_ros2.drop_connections()
    await asyncio.wait_for(first.connection.closed.wait(), 5.0)
    assert first.connection.close_reason == "the connection closed (code 1001: simulated connection drop)"
    await client.wait_connected(30.0)
    assert client.session is not first
    assert (await client.call_service("/add_two_ints", {"a": 1, "b": 1}))["sum"] == 2


async def test_a_stopped_robot_refuses_the_connection_until_it_starts_again(
    make_sim: MakeSim, make_client: MakeClient
) -> None:
    """While stopped a call fails at once naming the refusal; after start() the client reconnects."""
    robot = await make_sim(dialect="ros2")
    client = await make_client(robot)
    await robot.stop()
    with pytest.raises(NotConnectedError, match="Connect call failed"):
        await client.call_service("/add_two_ints", {"a": 1, "b": 1}, timeout=2.0)
    await robot.start(listen=False)
    await client.wait_connected(30.0)
    assert (await client.call_service("/add_two_ints", {"a": 1, "b": 1}))["sum"] == 2


async def test_closing_the_client_closes_its_connections_on_the_bridge(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """The bridge sees the client's close (its connections cleaned up, as on a socket)."""
    client = await make_client(sim_ros2)
    assert sim_ros2.connection_count >= 1
    await client.close()
    await sim_ros2.wait_for(lambda _world: sim_ros2.connection_count == 0, 15.0)


async def test_a_frame_above_the_bridge_s_limit_closes_the_connection_with_1009(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """Tornado's 10 MiB incoming limit holds in memory too (the client's own check refuses such a frame first,
    so it is written on the transport itself): the connection closes with 1009."""
    client = await make_client(sim_ros2)
    session = client.session
    assert session is not None
    frame = b'{"op": "publish", "topic": "/big", "msg": {"data": "' + b"x" * (11 * 1024 * 1024) + b'"}}'
    await session.connection.transport.send(frame, 1.0)
    await asyncio.wait_for(session.connection.closed.wait(), 5.0)
    assert session.connection.close_reason == "the connection closed (code 1009: message too big)"
