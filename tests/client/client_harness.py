"""Helpers for the client tests (fixtures live in this folder's conftest.py)."""

from __future__ import annotations

import socket
from collections.abc import Awaitable, Callable
from typing import Any

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.sim import SimulatedRobot

__all__ = ["FAST_RECONNECT", "MakeClient", "MakeSim", "busy_lanes", "idle_lanes", "unused_port"]

MakeClient = Callable[..., Awaitable[RosbridgeClient]]
MakeSim = Callable[..., Awaitable[SimulatedRobot]]

#: Short backoff so reconnect tests stay fast.
FAST_RECONNECT: dict[str, Any] = {"reconnect_min": 0.05, "reconnect_max": 0.2, "connect_timeout": 2.0}


def unused_port() -> int:
    """A loopback port nothing listens on (bound, then released)."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
    return port


def idle_lanes(client: RosbridgeClient) -> int:
    """How many pooled lanes wait, open, for a next call."""
    return len(client.lanes._idle)


def busy_lanes(client: RosbridgeClient) -> int:
    """How many pooled lanes carry a call now."""
    return len(client.lanes._busy)
