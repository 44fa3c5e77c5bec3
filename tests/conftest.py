"""Shared fixtures: simulated robots on port 0 (127.0.0.1) or in memory, started on the test's own loop.

``sim_ros2`` (Jazzy-like), ``sim_ros1`` (Noetic-like), ``sim_humble`` (ROS 2 with Humble's in-order
connections), ``sim`` (parametrized over both dialects) and ``make_sim(**kwargs)`` for anything else
(e.g. ``await make_sim(action_step=0.5)``). Goals step every 50 ms and ``/slow_service`` takes 1 s here so the
suite stays fast; pass other values to ``make_sim`` when a test needs them.
"""

from __future__ import annotations

import os
from collections.abc import AsyncIterator, Awaitable, Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from rosbridge_mcp_server.sim import SimulatedRobot

#: Defaults for robots in tests (faster than the standalone command's).
TEST_ROBOT_DEFAULTS: dict[str, Any] = {"action_step": 0.05, "slow_service_seconds": 1.0}

MakeSim = Callable[..., Awaitable[SimulatedRobot]]


#: Workers per core for ``-n auto``: the tests mostly wait on sockets and timers, so a core keeps four busy.
WORKERS_PER_CORE = 4


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """``-n auto`` fits the machine: four workers a core (eight on two cores), at most sixteen."""
    return max(1, min(16, WORKERS_PER_CORE * (os.cpu_count() or 1)))


@pytest.hookimpl(tryfirst=True)
def pytest_cmdline_main(config: pytest.Config) -> None:
    """Against a real bridge the tests run one at a time (no xdist workers): they share its one graph."""
    if os.environ.get("ROSBRIDGE_TEST_URL") and getattr(config.option, "numprocesses", None):
        config.option.numprocesses = 0
    _keep_bytecode_outside_the_tree(config.rootpath)


def _keep_bytecode_outside_the_tree(rootpath: Path) -> None:
    """Where PYTHONDONTWRITEBYTECODE is set (some CI images set it), no process keeps compiled bytecode, so
    every one the suite starts (eight workers, a server for each end-to-end test) compiles mcp, pydantic and
    this package from source again: about 1 s of CPU each, a quarter of the suite's CPU. The suite's processes
    keep theirs in ``.pytest_cache/pycache`` instead (git-ignored), never beside the sources. Run before the
    workers start, so they and every process they start inherit it."""
    if os.environ.pop("PYTHONDONTWRITEBYTECODE", None) is not None:
        os.environ.setdefault("PYTHONPYCACHEPREFIX", str(rootpath / ".pytest_cache" / "pycache"))


@pytest.fixture
def sim_in_memory() -> bool:
    """Whether ``make_sim`` starts robots without a port, reached in memory (a module overrides it to say so;
    see ``tests/sim_transport.py`` for which to pick)."""
    return False


@pytest.fixture
async def make_sim(sim_in_memory: bool) -> AsyncIterator[MakeSim]:
    """Factory: ``await make_sim(dialect="ros1", in_order=False, action_step=0.2, ...)`` → a started robot.

    ``in_memory=True`` starts it without a port (reach it with ``sim_transport.client_for``); by default the
    module's ``sim_in_memory`` decides.
    """
    robots: list[SimulatedRobot] = []

    async def make(*, in_memory: bool | None = None, **kwargs: Any) -> SimulatedRobot:
        robot = SimulatedRobot(**{**TEST_ROBOT_DEFAULTS, **kwargs})
        await robot.start(listen=not (sim_in_memory if in_memory is None else in_memory))
        robots.append(robot)
        return robot

    try:
        yield make
    finally:
        for robot in robots:
            await robot.stop()


@pytest.fixture
async def sim_ros2(make_sim: MakeSim) -> SimulatedRobot:
    """A started ROS 2 (Jazzy-like) simulated robot."""
    return await make_sim(dialect="ros2")


@pytest.fixture
async def sim_ros1(make_sim: MakeSim) -> SimulatedRobot:
    """A started ROS 1 (Noetic, rosbridge 0.11.17-like) simulated robot."""
    return await make_sim(dialect="ros1")


@pytest.fixture
async def sim_humble(make_sim: MakeSim) -> SimulatedRobot:
    """A started ROS 2 robot with Humble 2.0.x defaults: each connection's ops strictly in order."""
    return await make_sim(dialect="ros2", in_order=True)


@pytest.fixture(params=["ros2", "ros1"])
async def sim(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    """A started simulated robot of each dialect (the test runs once per dialect)."""
    return await make_sim(dialect=request.param)


@pytest.fixture(autouse=True)
def _server_files_in_a_test_directory(tmp_path: Path) -> Iterator[None]:
    """A server started by a test (in this process or a child) keeps its console's URL file and its
    recordings in directories of that test, not in the user's runtime and data directories."""
    chosen = {
        "ROSBRIDGE_MCP_RUNTIME_DIR": tmp_path / "runtime",
        "ROSBRIDGE_MCP_RECORD_DIR": tmp_path / "recordings",
    }
    previous = {name: os.environ.get(name) for name in chosen}
    os.environ.update({name: str(path) for name, path in chosen.items()})
    yield
    for name, value in previous.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value
