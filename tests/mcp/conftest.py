"""Fixtures for the MCP tests: a session on each simulated robot (helpers live in ``mcp_harness``)."""

from __future__ import annotations

from collections.abc import AsyncIterator
from pathlib import Path

import pytest
from mcp_harness import Session, open_session

from rosbridge_mcp_server.sim import SimulatedRobot


@pytest.fixture
async def session(sim: SimulatedRobot) -> AsyncIterator[Session]:
    """A session on each dialect's robot (the test runs once per dialect)."""
    async with open_session(sim.url) as opened:
        yield opened


@pytest.fixture
async def session_ros2(sim_ros2: SimulatedRobot) -> AsyncIterator[Session]:
    """A session on the ROS 2 (Jazzy-like) robot."""
    async with open_session(sim_ros2.url) as opened:
        yield opened


@pytest.fixture
async def session_ros1(sim_ros1: SimulatedRobot) -> AsyncIterator[Session]:
    """A session on the ROS 1 (Noetic-like) robot."""
    async with open_session(sim_ros1.url) as opened:
        yield opened


@pytest.fixture
async def session_dir(sim: SimulatedRobot, tmp_path: Path) -> AsyncIterator[tuple[Session, Path]]:
    """A session on each dialect's robot whose recording directory is a fresh temporary folder."""
    directory = tmp_path / "recordings"
    async with open_session(sim.url, record_dir=str(directory)) as opened:
        yield opened, directory
