"""diagnose through an MCP client session on the simulated Nav2 world, in both dialects: a healthy robot
reports no problem; each fault (alone, and two at once) is named in the first lines, pointing at the right
topic, frame or node; focus narrows; an unknown focus names the choices; a robot without /rosout,
/diagnostics or lifecycle services says so and reports the rest."""

from __future__ import annotations

import asyncio
import json
import re
import time
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from typing import Any

import pytest
import websockets
from mcp_harness import Session, open_session, text_of

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.robot.diagnosis import WINDOW
from rosbridge_mcp_server.robot.diagnosis.streams import AGAIN
from rosbridge_mcp_server.robot.log_keeper import LogKeeper
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.tools.paging import TEXT_BUDGET

TOOLS = ("diagnose", "read_logs", "list_nodes")
WAIT = 15.0

#: What each fault's first finding is about: (area, subject, words its line must carry).
FAULT_SIGNS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "scan-stopped": ("streams", "/scan", ("/rplidar_node publishes /scan", "nothing arrived")),
    "tf-stale": ("tf", "odom -> base_footprint", ("odom → base_footprint",)),
    "driver-error": ("diagnostics", "rplidar_node: RPLidar A2M8", ("ERROR rplidar_node", "Motor stalled")),
    "controller-inactive": ("lifecycle", "/controller_server", ("/controller_server is inactive",)),
    "log-errors": ("logs", "/controller_server", ("[ERROR] /controller_server: Failed to make progress",)),
    "node-gone": ("graph", "/amcl", ("Node /amcl is gone",)),
}
#: What each fault's first finding says to call next, word for word (robot/ gives the steps, the tool words
#: them).
FAULT_NEXT: dict[str, str] = {
    "scan-stopped": (
        'subscribe_topic {"topic": "/scan", "timeout": 5}; get_node_info {"node": "/rplidar_node"}'
    ),
    "tf-stale": 'get_transform {"target_frame": "odom", "source_frame": "base_footprint", "timeout": 5}',
    "driver-error": (
        'subscribe_topic {"topic": "/diagnostics", "count": 8, "duration": 3, "fields": ["status"]} (its '
        "publishers take turns: one message is likely another's)"
    ),
    "controller-inactive": (
        'read_logs {"node": "/controller_server", "level": "info"} for why; activating it acts on the robot '
        "(its lifecycle manager's manage_nodes, or its change_state service, transition 3): ask the user "
        "first"
    ),
    "log-errors": 'read_logs {"node": "/controller_server", "level": "info"}',
    "node-gone": 'read_logs {"node": "/amcl", "level": "info"} for its last words; list_nodes',
}
SINGLE = [
    (dialect, fault)
    for dialect in ("ros2", "ros1")
    for fault in FAULT_SIGNS
    if not (dialect == "ros1" and fault == "controller-inactive")
]
PAIRS = [
    ("ros2", ("scan-stopped", "controller-inactive")),
    ("ros2", ("node-gone", "log-errors")),
    ("ros1", ("tf-stale", "driver-error")),
    ("ros1", ("node-gone", "scan-stopped")),
]


def keeper_of(ros: RosbridgeClient) -> LogKeeper:
    """The session's log keeper (a watcher of the client)."""
    found = [w for w in ros.watchers if isinstance(w, LogKeeper)]
    assert found, "the server keeps no log"
    return found[0]


async def until(check: Callable[[], bool], what: str, timeout: float = WAIT) -> None:
    """Wait (bounded) until *check* holds: the log and diagnostics arrive in the background."""
    deadline = time.monotonic() + timeout
    while not check():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        await asyncio.sleep(0.02)


@asynccontextmanager
async def broken(
    dialect: str, faults: tuple[str, ...], tools: tuple[str, ...] | None = TOOLS
) -> AsyncIterator[tuple[SimulatedRobot, Session]]:
    """A Nav2 robot with *faults* and an MCP session on it (with *tools*; None: all), once the server has had
    its first look (its log subscribed, the nodes seen, the faults that show over time shown)."""
    robot = SimulatedRobot(dialect=dialect, world="nav2", faults=faults, action_step=0.05)  # type: ignore[arg-type]
    robot.nav2.health.node_gone_after = 3_600  # taken out below, once the server has looked
    async with robot, open_session(robot.url, tools=tools) as session:
        keeper = keeper_of(session.ros)
        await asyncio.wait_for(keeper.ready.wait(), WAIT)
        await until(lambda: keeper.nodes_seen is not None, "the first look at the nodes")
        await until(lambda: len(keeper.board) >= 4, "the drivers' diagnostics")
        if "node-gone" in faults:
            robot.nav2.health.take_out()
        if "log-errors" in faults:
            await until(lambda: keeper.ring.tally.groups, "an error in the log")
        yield robot, session


def findings_text(text: str) -> list[str]:
    """The finding lines of a diagnose text (the count first, 'Checked' last)."""
    return [
        line for line in text.splitlines()[1:] if not line.startswith(("Checked in", "Not checked", "  →"))
    ]


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_a_healthy_nav2_robot_reports_no_problem(dialect: str) -> None:
    async with broken(dialect, ()) as (_robot, session):
        result = await session.ok("diagnose")
    text = text_of(result)
    data = result.structured_content
    assert data is not None
    # An area not checked is never passed as healthy: ROS 1 has no lifecycle nodes.
    expected = (
        "No problem found."
        if dialect == "ros2"
        else "No problem found in the areas checked (not checked: lifecycle)."
    )
    assert text.startswith(expected), text
    assert data["problems"] == data["warnings"] == 0
    assert data["findings"] == []
    checked = data["checked"]
    assert "4 statuses, 4 OK" in checked["diagnostics"]
    assert checked["streams"].startswith("9 of 9 key streams flowing"), checked
    assert {"map", "odom", "base_footprint", "base_link", "laser"} <= set(data["frames"])
    assert all(rate and rate > 0 for rate in data["streams"].values()), data["streams"]
    if dialect == "ros2":
        assert checked["lifecycle"] == "16 of 16 lifecycle nodes active"
        assert data["unavailable"] == {}
    else:
        assert data["unavailable"] == {"lifecycle": "ROS 1 has no lifecycle nodes"}
    assert len(text) <= TEXT_BUDGET


@pytest.mark.parametrize(("dialect", "fault"), SINGLE)
async def test_each_fault_is_named_first_and_points_at_its_topic_frame_or_node(
    dialect: str, fault: str
) -> None:
    async with broken(dialect, (fault,)) as (_robot, session):
        result = await session.ok("diagnose")
    text = text_of(result)
    data = result.structured_content
    assert data is not None
    area, subject, words = FAULT_SIGNS[fault]
    first = data["findings"][0]
    assert (first["severity"], first["area"], first["subject"]) == ("problem", area, subject), text
    lines = text.splitlines()
    assert lines[0].startswith(f"{data['problems']} problem"), text
    assert all(word in lines[1] for word in words), text
    assert lines[2] == f"  → {FAULT_NEXT[fault]}", text
    assert first["next"] == FAULT_NEXT[fault]


@pytest.mark.parametrize(("dialect", "faults"), PAIRS)
async def test_two_faults_at_once_are_both_named_in_the_first_lines(
    dialect: str, faults: tuple[str, str]
) -> None:
    async with broken(dialect, faults) as (_robot, session):
        result = await session.ok("diagnose")
    text = text_of(result)
    data = result.structured_content
    assert data is not None
    first = findings_text(text)[:4]
    for fault in faults:
        area, subject, words = FAULT_SIGNS[fault]
        assert any(all(word in line for word in words) for line in first), (fault, text)
        assert any(f["area"] == area and f["subject"] == subject for f in data["findings"][:4]), (fault, data)


async def test_focus_narrows_to_an_area_a_word_or_a_node() -> None:
    async with broken("ros2", ("driver-error", "controller-inactive", "log-errors")) as (_robot, session):
        sensors = (await session.ok("diagnose", {"focus": "sensors"})).structured_content
        lifecycle = (await session.ok("diagnose", {"focus": "lifecycle"})).structured_content
        node = (await session.ok("diagnose", {"focus": "/controller_server"})).structured_content
        bare = (await session.ok("diagnose", {"focus": "controller_server"})).structured_content
        navigation = (await session.ok("diagnose", {"focus": "navigation"})).structured_content
    assert sensors is not None
    assert lifecycle is not None
    assert node is not None
    assert bare is not None
    assert navigation is not None
    assert [f["area"] for f in sensors["findings"]] == ["diagnostics"]
    assert set(sensors["checked"]) == {"diagnostics", "streams"}
    assert [(f["area"], f["subject"]) for f in lifecycle["findings"]] == [("lifecycle", "/controller_server")]
    assert {f["area"] for f in node["findings"]} == {"lifecycle", "logs"}
    assert all("/controller_server" in f["nodes"] for f in node["findings"])
    assert [(f["area"], f["subject"]) for f in node["findings"]] == [
        (f["area"], f["subject"]) for f in bare["findings"]
    ]
    assert "diagnostics" not in navigation["checked"]
    assert {f["area"] for f in navigation["findings"]} >= {"lifecycle", "logs"}


async def test_an_unknown_focus_names_the_choices() -> None:
    async with broken("ros2", ()) as (_robot, session):
        error = await session.error("diagnose", {"focus": "wheels"})
    assert "'wheels'" in error
    for choice in ("navigation", "sensors", "tf", "lifecycle", "a node of the graph", "list_nodes"):
        assert choice in error, error


async def test_a_robot_without_rosout_diagnostics_or_lifecycle_says_so_and_reports_the_rest() -> None:
    """The turtle world has no /diagnostics and no lifecycle node; its /rosout is taken out of the graph."""
    robot = SimulatedRobot(dialect="ros2")
    for name in list(robot.graph.nodes):
        if "/rosout" in robot.graph.nodes[name].publishes:
            robot.graph.remove_publisher(name, "/rosout")
    async with robot, open_session(robot.url, tools=TOOLS) as session:
        keeper = keeper_of(session.ros)
        await asyncio.wait_for(keeper.ready.wait(), WAIT)
        result = await session.ok("diagnose")
        logs = await session.ok("read_logs")
    data = result.structured_content
    assert data is not None
    assert data["unavailable"] == {
        "diagnostics": "the robot has no /diagnostics topic",
        "lifecycle": "no node offers lifecycle services (get_state)",
        "logs": "the robot has no /rosout topic",
    }
    assert {"graph", "streams", "tf"} <= set(data["checked"])
    assert "/scan" in data["streams"]
    assert "/turtle1/cmd_vel" not in data["streams"]
    assert "Not checked: " in text_of(result)
    assert "no /rosout topic" in text_of(result)
    assert "no /rosout topic" in text_of(logs)
    assert logs.structured_content is not None
    assert logs.structured_content["source"] is None


async def test_a_rate_far_below_the_one_seen_before_is_a_warning() -> None:
    """The session remembers each stream's rate; a stream at under half of it is named."""
    async with broken("ros2", ()) as (_robot, session):
        await session.ok("diagnose", {"focus": "streams"})
        keeper = keeper_of(session.ros)
        # As if the lidar had run four times faster before, and every other stream four times slower: a loaded
        # machine's second look may find any stream slower (seen: an IMU at 3.8 Hz after 9.1), and only /scan
        # is meant to be named.
        for topic in keeper.rates:
            keeper.rates[topic] = keeper.rates[topic] * (4 if topic == "/scan" else 0.25)
        result = await session.ok("diagnose", {"focus": "streams"})
    data = result.structured_content
    assert data is not None
    assert [(f["severity"], f["subject"]) for f in data["findings"]] == [("warning", "/scan")], data
    assert "under half" in data["findings"][0]["summary"]


async def test_diagnose_listens_to_every_stream_side_by_side() -> None:
    """The streams are heard in one window, all at once (one window per topic would take ten seconds): the
    robot sees every stream subscribed at the same time. How long diagnose takes is the benchmark's figure
    (scripts/bench.py), not a bound here."""
    streams = ("/scan", "/odom", "/tf", "/imu/data", "/joint_states")
    async with broken("ros2", ()) as (robot, session):
        assert not any(robot.bridge.has_subscribers(topic) for topic in streams if topic != "/tf")
        call = asyncio.create_task(session.ok("diagnose"))
        # /scan, subscribed, notifies the world ten times a second: the check is made again until it holds.
        await robot.world.wait_for(lambda _: all(robot.bridge.has_subscribers(t) for t in streams), WAIT)
        result = await asyncio.wait_for(call, WAIT)
    data: dict[str, Any] | None = result.structured_content
    assert data is not None
    assert data["findings"] == [], data


async def test_a_frame_with_two_parents_and_a_stale_transform_are_named() -> None:
    """Another client publishes on /tf a second parent for base_footprint and a transform stamped 5 s ago."""
    async with broken("ros2", ()) as (_robot, session), websockets.connect(_robot.url) as other:
        await other.send(json.dumps({"op": "advertise", "topic": "/tf", "type": "tf2_msgs/msg/TFMessage"}))

        def transform(parent: str, child: str, age: float) -> dict[str, Any]:
            now = time.time() - age
            stamp = {"sec": int(now), "nanosec": int((now % 1) * 1e9)}
            return {
                "header": {"stamp": stamp, "frame_id": parent},
                "child_frame_id": child,
                "transform": {"translation": {"x": 1.0}, "rotation": {"w": 1.0}},
            }

        async def publish() -> None:
            while True:
                msg = {
                    "transforms": [transform("map", "base_footprint", 0.0), transform("odom", "dock", 5.0)]
                }
                await other.send(json.dumps({"op": "publish", "topic": "/tf", "msg": msg}))
                await asyncio.sleep(0.05)

        publishing = asyncio.create_task(publish())
        try:
            result = await session.ok("diagnose", {"focus": "tf"})
        finally:
            publishing.cancel()
    data = result.structured_content
    assert data is not None
    subjects = {f["subject"]: f["summary"] for f in data["findings"]}
    assert "base_footprint" in subjects
    assert "2 parents (map, odom)" in subjects["base_footprint"]
    assert "odom -> dock" in subjects
    assert "stale" in subjects["odom -> dock"]


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_a_process_frozen_through_the_window_raises_no_false_alarm(dialect: str) -> None:
    """The whole process (server and simulated robot share it) freezes for longer than the window, as a loaded
    machine does: nothing arrives in the window, yet every stream is healthy. Silent streams are heard again
    before they are judged, so no problem is named; a stream that is really silent still is, heard for longer.

    The freeze is a blocking sleep on purpose: it is the attack (a starved process), not a wait."""
    streams = ("/scan", "/odom", "/imu/data", "/joint_states")
    async with broken(dialect, ("scan-stopped",)) as (robot, session):
        call = asyncio.create_task(session.ok("diagnose", {"focus": "streams"}))
        await until(lambda: all(robot.bridge.has_subscribers(t) for t in streams), "the streams subscribed")
        time.sleep(WINDOW + 0.3)  # noqa: ASYNC251 -- the frozen process is what is tested
        result = await asyncio.wait_for(call, WAIT)
    data = result.structured_content
    assert data is not None
    assert [(f["severity"], f["subject"]) for f in data["findings"]] == [("problem", "/scan")], data
    # Every stream but the stopped one has a rate: one message (all a frozen window may give) is heard again.
    assert all(rate for topic, rate in data["streams"].items() if topic != "/scan"), data["streams"]
    summary = data["findings"][0]["summary"]
    heard_for = float(re.search(r"nothing arrived in ([\d.]+) s", summary)[1])  # type: ignore[index]
    assert heard_for >= WINDOW + AGAIN, summary
