"""read_logs through an MCP client session on the simulated Nav2 world, in both dialects: the lines the
robot's nodes log on /rosout (ROS 1: passed on by rosout on /rosout_agg) are kept from connect, filtered by
level, node glob, text and since, folded, and paged within the text budget."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from typing import Any

import pytest
import pytest_asyncio
from mcp_harness import Session, open_session, text_of
from test_mcp_diagnose import TOOLS, WAIT, keeper_of, until

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.tools.paging import TEXT_BUDGET

pytestmark = pytest.mark.asyncio(loop_scope="module")

#: (node, level, text) the test logs on the robot, in this order.
LINES = [
    *[("controller_server", "error", "Failed to make progress")] * 5,
    ("bt_navigator", "warn", "Goal 7 failed"),
    ("bt_navigator", "warn", "Goal 8 failed"),
    ("amcl", "info", "Setting pose (0.000000): 5.544 5.544 0.000"),
    ("local_costmap/local_costmap", "warn", "Sensor origin at (12.3, 4.5) is out of map bounds"),
]


@pytest_asyncio.fixture(scope="module", loop_scope="module", params=["ros2", "ros1"])
async def logged(request: pytest.FixtureRequest) -> AsyncIterator[tuple[SimulatedRobot, Session]]:
    """A Nav2 robot whose nodes have logged :data:`LINES` since the server connected."""
    robot = SimulatedRobot(dialect=request.param, world="nav2")
    async with robot, open_session(robot.url, tools=TOOLS) as session:
        keeper = keeper_of(session.ros)
        await asyncio.wait_for(keeper.ready.wait(), WAIT)
        expected = keeper.ring.received + len(LINES)
        nav2 = robot.nav2.robots[0]
        for node, level, text in LINES:
            robot.nav2.health.log(nav2, node, level, text)
        await until(lambda: keeper.ring.received >= expected, "the logged lines")
        yield robot, session


async def test_the_default_shows_warnings_and_errors_folded(logged: tuple[SimulatedRobot, Session]) -> None:
    _robot, session = logged
    result = await session.ok("read_logs")
    text = text_of(result)
    data = result.structured_content
    assert data is not None
    groups = [(g["level"], g["node"], g["text"], g["count"]) for g in data["groups"]]
    assert groups == [
        ("error", "/controller_server", "Failed to make progress", 5),
        ("warn", "/bt_navigator", "Goal 8 failed", 2),
        ("warn", "/local_costmap/local_costmap", "Sensor origin at (12.3, 4.5) is out of map bounds", 1),
    ]
    assert data["lines"] == 8
    assert data["count"] == 3
    assert data["more"] == 0
    assert data["source"] == ("/rosout" if _robot.dialect == "ros2" else "/rosout_agg")
    assert text.startswith("8 lines at warn or above in 3 groups, read from /rosout")
    assert "[ERROR] /controller_server: Failed to make progress (×5 in " in text
    assert "last " in text
    assert " ago)" in text
    assert "Setting pose" not in text


async def test_level_node_text_and_since_filter(logged: tuple[SimulatedRobot, Session]) -> None:
    _robot, session = logged
    info = (await session.ok("read_logs", {"level": "info", "node": "amcl"})).structured_content
    glob = (await session.ok("read_logs", {"node": "*costmap*"})).structured_content
    errors = (await session.ok("read_logs", {"level": "error"})).structured_content
    needle = (await session.ok("read_logs", {"text": "PROGRESS", "level": "debug"})).structured_content
    everything = (await session.ok("read_logs", {"level": "debug", "since": 3600})).structured_content
    assert info is not None
    assert glob is not None
    assert errors is not None
    assert needle is not None
    assert everything is not None
    assert [(g["node"], g["level"]) for g in info["groups"]] == [("/amcl", "info")]
    assert [g["node"] for g in glob["groups"]] == ["/local_costmap/local_costmap"]
    assert [g["level"] for g in errors["groups"]] == ["error"]
    assert [(g["text"], g["count"]) for g in needle["groups"]] == [("Failed to make progress", 5)]
    assert everything["lines"] >= len(LINES)
    recent = await session.ok("read_logs", {"level": "debug", "since": 0.001})
    assert recent.structured_content is not None
    assert recent.structured_content["groups"] == []
    assert text_of(recent).startswith("Nothing logged at any level in the last 0.001 s since ")


@pytest.mark.parametrize(
    ("written", "level"),
    [("warning", "warn"), ("WARN", "warn"), ("err", "error"), ("critical", "fatal"), ("Information", "info")],
)
async def test_a_level_in_another_case_or_its_other_name_is_the_level(
    logged: tuple[SimulatedRobot, Session], written: str, level: str
) -> None:
    """ "warning" (Python's name), "err" and "crit" (syslog's), any case: read as warn, error, fatal."""
    _robot, session = logged
    aliased = await session.ok("read_logs", {"level": written})
    named = await session.ok("read_logs", {"level": level})
    assert aliased.structured_content is not None
    assert named.structured_content is not None

    def groups(data: dict[str, Any]) -> list[tuple[str, str, str, int]]:
        return [(g["level"], g["node"], g["text"], g["count"]) for g in data["groups"]]

    assert groups(aliased.structured_content) == groups(named.structured_content)
    assert f" at {level} or above" in text_of(aliased)


async def test_a_level_that_is_none_names_the_levels(logged: tuple[SimulatedRobot, Session]) -> None:
    _robot, session = logged
    error = await session.error("read_logs", {"level": "loud"})
    assert "'debug', 'info', 'warn', 'error' or 'fatal' (got 'loud')" in error


async def test_nothing_logged_says_since_when(logged: tuple[SimulatedRobot, Session]) -> None:
    _robot, session = logged
    result = await session.ok("read_logs", {"level": "fatal"})
    assert text_of(result).startswith("Nothing logged at fatal or above since ")
    assert "the ring keeps the last 5,000 lines and 10 min" in text_of(result)


async def test_many_groups_page_within_the_budget_and_walk_every_group(
    logged: tuple[SimulatedRobot, Session],
) -> None:
    robot, session = logged
    keeper = keeper_of(session.ros)
    nav2 = robot.nav2.robots[0]
    names = [f"{a}{b}" for a in "abcdefgh" for b in "abcdefgh"]  # 64 texts that do not fold
    expected = keeper.ring.received + len(names)
    for name in names:
        robot.nav2.health.log(nav2, "planner_server", "warn", f"Plugin {name} failed: " + "x" * 300)
    await until(lambda: keeper.ring.received >= expected, "the plugin lines")
    seen: list[str] = []
    offset = 0
    while True:
        result = await session.ok("read_logs", {"node": "/planner_server", "limit": 40, "offset": offset})
        text = text_of(result)
        data = result.structured_content
        assert data is not None
        assert len(text) <= TEXT_BUDGET
        seen += [g["text"].split(":")[0] for g in data["groups"]]
        if not data["more"]:
            break
        offset += len(data["groups"])
        assert f"call again with offset {offset}" in text
    assert sorted(seen) == sorted(f"Plugin {name} failed" for name in names)
    assert offset > 0  # the budget cut the pages below the limit
