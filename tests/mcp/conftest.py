"""Fixtures for the MCP tests: a session on each simulated robot (helpers live in ``mcp_harness``).

The session's server reaches its robot in memory (no socket between them; the robot keeps its port, so a test
can still watch it on a raw socket); a module that tests the server's own socket handling (reconnects,
outages) overrides ``server_in_memory`` to return ``False``. See ``tests/sim_transport.py``.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
from mcp_harness import Session, open_session

from rosbridge_mcp_server.sim import SimulatedRobot


@pytest.fixture
def server_in_memory() -> bool:
    """Whether the session fixtures' server reaches its robot in memory."""
    return True


@pytest.fixture
def reach(server_in_memory: bool) -> Any:
    """``open_session``'s options for a robot: its in-memory dial unless the module keeps the socket."""

    def options(robot: SimulatedRobot) -> dict[str, Any]:
        return {"transport": robot.dial_in_memory} if server_in_memory or not robot.listening else {}

    return options


@pytest.fixture
async def session(sim: SimulatedRobot, reach: Any) -> AsyncIterator[Session]:
    """A session on each dialect's robot (the test runs once per dialect)."""
    async with open_session(sim.url, **reach(sim)) as opened:
        yield opened


@pytest.fixture
async def session_ros2(sim_ros2: SimulatedRobot, reach: Any) -> AsyncIterator[Session]:
    """A session on the ROS 2 (Jazzy-like) robot."""
    async with open_session(sim_ros2.url, **reach(sim_ros2)) as opened:
        yield opened


@pytest.fixture
async def session_ros1(sim_ros1: SimulatedRobot, reach: Any) -> AsyncIterator[Session]:
    """A session on the ROS 1 (Noetic-like) robot."""
    async with open_session(sim_ros1.url, **reach(sim_ros1)) as opened:
        yield opened


@pytest.fixture
async def session_dir(sim: SimulatedRobot, tmp_path: Path, reach: Any) -> AsyncIterator[tuple[Session, Path]]:
    """A session on each dialect's robot whose recording directory is a fresh temporary folder."""
    directory = tmp_path / "recordings"
    async with open_session(sim.url, record_dir=str(directory), **reach(sim)) as opened:
        yield opened, directory
