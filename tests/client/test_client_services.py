"""Service calls: replies matched by id, errors with the bridge's text, deadlines, lanes on Humble."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from client_harness import MakeClient, MakeSim, busy_lanes, idle_lanes

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.errors import RequestTimeoutError, ServiceError
from rosbridge_mcp_server.sim import SimulatedRobot


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is done with the answers is tested."""
    return True


async def test_a_hundred_concurrent_calls_each_get_their_own_reply(client: RosbridgeClient) -> None:
    """100 /add_two_ints calls at once on one connection: every caller gets its own sum."""
    results = await asyncio.gather(
        *(client.call_service("/add_two_ints", {"a": i, "b": 1000}) for i in range(100))
    )
    assert [r["sum"] for r in results] == [i + 1000 for i in range(100)]
    info = await client.ros_info()
    if info.version == 2:
        assert client.lanes.opened == 0, "a threaded ROS 2 bridge multiplexes calls on the main connection"
    else:
        # rosbridge 0.11.17 answers a second call in flight on one socket ~40 ms late: calls are spread.
        assert 1 <= client.lanes.opened <= client.lanes.cap


async def test_ros1_calls_one_after_another_stay_on_the_main_connection(
    make_sim: MakeSim, make_client: MakeClient
) -> None:
    """On ROS 1 a call goes on the main connection when no other call is in flight there."""
    client = await make_client(await make_sim(dialect="ros1"))
    for i in range(5):
        assert (await client.call_service("/add_two_ints", {"a": i, "b": 1}))["sum"] == i + 1
    assert client.lanes.opened == 0


async def test_a_hundred_concurrent_calls_on_humble_use_a_bounded_pool_of_lanes(
    sim_humble: SimulatedRobot, make_client: MakeClient
) -> None:
    """On an in-order bridge calls run on pooled lanes, never more than the cap at once."""
    # A lane opens within the connect timeout; 100 calls at once on a loaded machine need more than the 2 s
    # the test clients use by default.
    client = await make_client(sim_humble, lane_cap=4, connect_timeout=10.0)
    results = await asyncio.gather(
        *(client.call_service("/add_two_ints", {"a": i, "b": 1}) for i in range(100))
    )
    assert [r["sum"] for r in results] == [i + 1 for i in range(100)]
    assert 1 <= client.lanes.opened <= 4
    assert busy_lanes(client) == 0
    assert sim_humble.connection_count <= 1 + 4


async def test_a_missing_service_fails_with_the_bridge_text(client: RosbridgeClient) -> None:
    """A service that does not exist raises ServiceError carrying "Service /x does not exist"."""
    with pytest.raises(ServiceError, match="Service /no_such_service does not exist") as caught:
        await client.call_service("/no_such_service")
    assert caught.value.service == "/no_such_service"


@pytest.mark.parametrize(
    ("robot_options", "timeout", "error", "text"),
    [
        # ROS 1 has no service timeout field: our own deadline ends the call.
        pytest.param(
            {"dialect": "ros1"},
            0.3,
            RequestTimeoutError,
            r"service /slow_service within 0\.3 s",
            id="ros1",
        ),
        # On ROS 2 the call's timeout field makes the bridge answer "Timeout exceeded" before our deadline.
        pytest.param(
            {"dialect": "ros2", "slow_service_seconds": 10.0},
            5.0,
            ServiceError,
            "Timeout exceeded while waiting for service response",
            id="jazzy",
        ),
        pytest.param(
            {"dialect": "ros2", "in_order": True, "slow_service_seconds": 10.0},
            5.0,
            ServiceError,
            "Timeout exceeded while waiting for service response",
            id="humble",
        ),
    ],
)
async def test_a_slow_service_past_its_timeout_fails_as_the_dialect_allows(
    *,
    make_sim: MakeSim,
    make_client: MakeClient,
    robot_options: dict[str, Any],
    timeout: float,
    error: type[Exception],
    text: str,
) -> None:
    """A call past its timeout fails (ROS 2: with the bridge's own text) and leaves nothing pending."""
    robot = await make_sim(**robot_options)
    client = await make_client(robot)
    with pytest.raises(error, match=text):
        await client.call_service("/slow_service", timeout=timeout)
    assert client.session is not None
    assert client.session.connection.pending == {}


@pytest.mark.parametrize("in_order", [False, True], ids=["jazzy", "humble"])
async def test_a_slow_service_does_not_delay_a_concurrent_call(
    make_sim: MakeSim, make_client: MakeClient, in_order: bool
) -> None:
    """While a 2 s service runs, /rosapi/topics answers at once (Humble: thanks to lanes)."""
    robot = await make_sim(dialect="ros2", in_order=in_order, slow_service_seconds=2.0)
    client = await make_client(robot)
    slow = asyncio.create_task(client.call_service("/slow_service", timeout=10.0))
    await robot.wait_for(lambda world: world.service_calls.get("/slow_service", 0) >= 1)
    topics = await client.call_service("/rosapi/topics", timeout=1.5)
    assert "/chatter" in topics["topics"]
    assert not slow.done()
    slow.cancel()


async def test_isolated_calls_run_on_a_lane_even_on_a_threaded_bridge(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """isolated=True puts the call on a lane of its own; the lane is kept for reuse."""
    client = await make_client(sim_ros2)
    assert (await client.call_service("/add_two_ints", {"a": 1, "b": 2}, isolated=True))["sum"] == 3
    assert client.lanes.opened == 1
    assert idle_lanes(client) == 1
    assert (await client.call_service("/add_two_ints", {"a": 1, "b": 3}, isolated=True))["sum"] == 4
    assert client.lanes.opened == 1, "an idle lane is reused"


async def test_a_lane_whose_call_timed_out_is_closed_not_reused(
    sim_ros1: SimulatedRobot, make_client: MakeClient
) -> None:
    """After a timeout the bridge may still be busy on that lane, so it is closed."""
    client = await make_client(sim_ros1)
    with pytest.raises(RequestTimeoutError):
        await client.call_service("/slow_service", timeout=0.2, isolated=True)
    assert idle_lanes(client) == 0
    assert busy_lanes(client) == 0


async def test_calls_beyond_the_lane_cap_wait_within_their_deadline(
    sim_humble: SimulatedRobot, make_client: MakeClient
) -> None:
    """With every lane busy, another call waits for one and times out at its own deadline."""
    client = await make_client(sim_humble, lane_cap=1)
    slow = asyncio.create_task(client.call_service("/slow_service", timeout=10.0))
    await sim_humble.wait_for(lambda world: world.service_calls.get("/slow_service", 0) >= 1)
    with pytest.raises(RequestTimeoutError, match="lanes to the bridge were busy"):
        await client.call_service("/add_two_ints", {"a": 1, "b": 1}, timeout=0.2)
    assert (await slow)["success"] is True
    assert (await client.call_service("/add_two_ints", {"a": 1, "b": 1}, timeout=2.0))["sum"] == 2


async def test_cancelling_a_call_leaves_no_pending_entry(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """A cancelled call removes its id from the pending table (memory stays bounded)."""
    client = await make_client(sim_ros2)
    call = asyncio.create_task(client.call_service("/slow_service", timeout=10.0))
    await sim_ros2.wait_for(lambda world: world.service_calls.get("/slow_service", 0) >= 1)
    assert client.session is not None
    assert len(client.session.connection.pending) == 1
    call.cancel()
    with pytest.raises(asyncio.CancelledError):
        await call
    assert client.session.connection.pending == {}


async def test_ros1_service_failures_carry_the_bridge_text(
    sim_ros1: SimulatedRobot, make_client: MakeClient
) -> None:
    """Bad arguments come back as ServiceError with what the bridge said about them."""
    client = await make_client(sim_ros1)
    with pytest.raises(ServiceError) as caught:
        await client.call_service("/add_two_ints", {"a": "one", "b": 2})
    assert caught.value.message


async def test_idle_lanes_are_closed_after_a_while(
    sim_humble: SimulatedRobot, make_client: MakeClient
) -> None:
    """A lane left idle longer than lane_idle_seconds is closed; the robot sees only the main connection."""
    client = await make_client(sim_humble, lane_idle_seconds=0.1)
    await asyncio.gather(*(client.call_service("/add_two_ints", {"a": i, "b": 0}) for i in range(3)))
    assert client.lanes.opened >= 1
    await sim_humble.wait_for(lambda _world: sim_humble.connection_count == 1, 15.0)
    assert idle_lanes(client) == 0
