"""Fixtures for client tests: a started ``RosbridgeClient`` per simulated robot, closed afterwards."""

from __future__ import annotations

import socket
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import pytest

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.sim import SimulatedRobot

MakeClient = Callable[..., Awaitable[RosbridgeClient]]

#: Short backoff so reconnect tests stay fast.
FAST_RECONNECT: dict[str, Any] = {"reconnect_min": 0.05, "reconnect_max": 0.2, "connect_timeout": 2.0}


def unused_port() -> int:
    """A loopback port nothing listens on (bound, then released)."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
    return port


@pytest.fixture
async def make_client() -> AsyncIterator[MakeClient]:
    """Factory: ``await make_client(robot_or_url, connected=True, **options)`` → a started client."""
    clients: list[RosbridgeClient] = []

    async def make(
        target: SimulatedRobot | str, *, connected: bool = True, **options: Any
    ) -> RosbridgeClient:
        url = target if isinstance(target, str) else target.url
        client = RosbridgeClient(url, **{**FAST_RECONNECT, **options})
        clients.append(client)
        await client.start()
        if connected:
            await client.wait_connected(5.0)
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
