"""Learning the service types stops at a look-up that times out: a stuck rosapi costs one timeout, not one per
service (simulated rosapi 2.1.0, which hangs for good when asked about a parameter of its own)."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable

import pytest

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.errors import RequestTimeoutError
from rosbridge_mcp_server.robot.graph import RosGraph
from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]


async def test_learning_stops_at_the_first_look_up_that_times_out(make_sim: MakeSim) -> None:
    """rosapi hangs after the first service_type: the second one times out, and no third is asked."""
    robot = await make_sim(dialect="ros2", in_order=True, distro="jazzy", rosapi="2.1.0", rosapi_latency=1.0)
    # rosapi takes 1 s a call: the test has that long to queue its hanging call behind the first look-up,
    # which a loaded machine needs (0.2 s was lost under load, and a third look-up was asked).
    async with RosbridgeClient(robot.url, request_timeout=2.5) as client:
        await client.wait_connected(30.0)
        graph = RosGraph(client)
        learning = asyncio.create_task(graph.learn_service_types())
        # The first look-up comes after ros_info and the service list, each 1 s of rosapi, and beside the
        # client's ordering measurement: a loaded machine can take several seconds to get there.
        await robot.world.wait_for(lambda w: w.service_calls.get("/rosapi/service_type") == 1, 20.0)
        # Queued behind that look-up (rosapi answers one call at a time): after it, rosapi answers nothing.
        hang = asyncio.create_task(
            client.call_service("/rosapi/get_param", {"name": "/rosapi:x", "default_value": ""}, timeout=5.0)
        )
        with pytest.raises(RequestTimeoutError):
            await asyncio.wait_for(learning, 15.0)
        assert robot.world.service_calls["/rosapi/service_type"] == 2
        hang.cancel()
        with pytest.raises((asyncio.CancelledError, RequestTimeoutError)):
            await hang
