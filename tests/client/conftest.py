"""Fixtures for client tests: a started ``RosbridgeClient`` per simulated robot, closed afterwards."""

from __future__ import annotations

from collections.abc import AsyncIterator
from typing import Any

import pytest
from client_harness import FAST_RECONNECT, MakeClient

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.sim import SimulatedRobot
from sim_transport import client_for


@pytest.fixture
async def make_client() -> AsyncIterator[MakeClient]:
    """Factory: ``await make_client(robot_or_url, connected=True, **options)`` → a started client."""
    clients: list[RosbridgeClient] = []

    async def make(
        target: SimulatedRobot | str, *, connected: bool = True, **options: Any
    ) -> RosbridgeClient:
        if isinstance(target, str):
            client = RosbridgeClient(target, **{**FAST_RECONNECT, **options})
        else:
            client = client_for(target, **{**FAST_RECONNECT, **options})
        clients.append(client)
        await client.start()
        if connected:
            await client.wait_connected(30.0)
            if not isinstance(target, str):
                await ordering_known(client)
        return client

    try:
        yield make
    finally:
        for client in clients:
            await client.close()


@pytest.fixture
async def client(sim: SimulatedRobot, make_client: MakeClient) -> RosbridgeClient:
    """A connected client of each dialect's robot."""
    return await make_client(sim)


async def ordering_known(client: RosbridgeClient) -> None:
    """Wait until the client knows whether the bridge holds calls up (measured in the background)."""
    assert await client.ordering_known(10.0) or not client.connected
