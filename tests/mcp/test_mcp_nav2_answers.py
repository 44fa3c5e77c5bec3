"""Answers sized for a model on the Nav2 world, through an MCP client session, in both dialects and on a
fleet: every graph tool's text within the budget, structured content the same page, the rest reachable by
filter and paging."""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator
from typing import Any

import pytest
import pytest_asyncio
from mcp_harness import Session, open_session, parameter_names, service_rows, text_of
from websockets.asyncio.client import connect

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.graph import is_hidden
from rosbridge_mcp_server.tools.paging import TEXT_BUDGET

ROBOTS: dict[str, dict[str, Any]] = {
    "ros2": {"dialect": "ros2", "world": "nav2"},
    "ros1": {"dialect": "ros1", "world": "nav2"},
    "ros2-fleet": {"dialect": "ros2", "world": "nav2", "robots": 3},
}


#: Starting a Nav2 world and an MCP session on it (the server learns over a thousand service types) takes
#: seconds: each of the three is started once per test worker for the module, on the module's event loop.
pytestmark = pytest.mark.asyncio(loop_scope="module")


@pytest_asyncio.fixture(scope="module", loop_scope="module", params=list(ROBOTS))
async def nav2(request: pytest.FixtureRequest) -> AsyncIterator[SimulatedRobot]:
    """A Nav2 robot shared by the module's tests: ROS 2, ROS 1, and a ROS 2 fleet of three."""
    robot = SimulatedRobot(action_step=0.05, slow_service_seconds=1.0, **ROBOTS[request.param])
    await robot.start()
    try:
        yield robot
    finally:
        await robot.stop()


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def session(nav2: SimulatedRobot) -> AsyncIterator[Session]:
    """An MCP session on the Nav2 robot, shared by the module's tests (they only read, but for one goal)."""
    async with open_session(nav2.url) as opened:
        yield opened


def prefix(robot: SimulatedRobot) -> str:
    """The first robot's namespace ("" for one robot)."""
    return robot.nav2.robots[0].namespace


def graph_calls(robot: SimulatedRobot) -> list[tuple[str, dict[str, Any]]]:
    """Every graph tool with arguments a model would use first on this robot."""
    ns = prefix(robot)
    sep = ":" if robot.dialect == "ros2" else "/"
    vx_max = "FollowPath.vx_max" if robot.dialect == "ros2" else "FollowPath/vx_max"
    return [
        ("list_topics", {}),
        ("list_services", {}),
        ("list_actions", {}),
        ("list_nodes", {}),
        ("list_parameters", {}),
        ("list_parameters", {"node": f"{ns}/controller_server"}),
        ("get_node_info", {"node": f"{ns}/controller_server"}),
        ("get_node_info", {"node": f"{ns}/global_costmap/global_costmap"}),
        ("get_topic_info", {"topic": f"{ns}/scan"}),
        ("get_topic_info", {"topic": f"{ns}/tf"}),
        ("describe_type", {"type_name": "nav_msgs/msg/OccupancyGrid"}),
        ("get_parameter", {"name": f"{ns}/controller_server{sep}{vx_max}"}),
    ]


async def test_every_graph_tool_answers_within_the_budget(session: Session, nav2: SimulatedRobot) -> None:
    """Each graph tool's text is at most 8,000 characters and its structured content about the same page."""
    for name, arguments in graph_calls(nav2):
        result = await session.ok(name, arguments)
        text = text_of(result)
        structured = json.dumps(result.structured_content)
        assert len(text) <= TEXT_BUDGET, (name, arguments, len(text))
        assert len(structured) <= 1.5 * len(text) + 2_000, (name, arguments, len(text), len(structured))


async def pages(session: Session, tool: str, arguments: dict[str, Any]) -> list[dict[str, Any]]:
    """Every page of a list tool, following ``more`` from offset 0."""
    found: list[dict[str, Any]] = []
    offset = 0
    while True:
        result = await session.ok(tool, {**arguments, "offset": offset})
        data = result.structured_content
        assert data is not None
        assert len(text_of(result)) <= TEXT_BUDGET
        found.append(data)
        if not data["more"]:
            return found
        assert f"offset={data['offset'] + page_size(tool, data)}" in text_of(result)
        offset = data["offset"] + page_size(tool, data)


def page_size(tool: str, data: dict[str, Any]) -> int:
    """How many rows a page of ``tool`` holds."""
    if tool == "list_parameters":
        return sum(len(group["names"]) for group in data["nodes"])
    return len(data[tool.removeprefix("list_")])


async def test_every_topic_is_reachable_by_paging(session: Session, nav2: SimulatedRobot) -> None:
    """Paging list_topics with a small limit yields each topic of the graph once."""
    listed = [
        row["name"] for page in await pages(session, "list_topics", {"limit": 30}) for row in page["topics"]
    ]
    expected = [t for t, _ in nav2.graph.topics(include_hidden=nav2.dialect == "ros1")]
    assert sorted(listed) == sorted(expected)
    assert len(listed) == len(set(listed))


async def test_every_service_is_reachable_by_filter_and_paging(
    session: Session, nav2: SimulatedRobot
) -> None:
    """filter "*" lists every service a row each; paged, they are all the graph's services."""
    listed = [
        row["name"]
        for page in await pages(session, "list_services", {"filter": "*", "limit": 120})
        for row in page["services"]
    ]
    expected = [s for s in nav2.graph.services if nav2.dialect == "ros1" or not is_hidden(s)]
    assert sorted(listed) == sorted(expected)


async def test_the_unfiltered_services_page_and_groups_cover_every_service(
    session: Session, nav2: SimulatedRobot
) -> None:
    """Without a filter: the robot's own services paged, every node's grouped; together, each service once."""
    found = await pages(session, "list_services", {})
    rows = [row["name"] for page in found for row in service_rows({**page, "groups": []})]
    rows += [row["name"] for row in service_rows({**found[0], "services": []})]
    expected = [s for s in nav2.graph.services if nav2.dialect == "ros1" or not is_hidden(s)]
    assert sorted(rows) == sorted(expected)


async def test_every_parameter_is_reachable_by_paging(session: Session, nav2: SimulatedRobot) -> None:
    """Paging list_parameters yields every parameter of the robot once (over a thousand on ROS 2)."""
    found = await pages(session, "list_parameters", {})
    names = [name for page in found for name in parameter_names(page)]
    assert len(names) == len(set(names)) == found[0]["count"]
    sep = ":" if nav2.dialect == "ros2" else "/"
    assert f"{prefix(nav2)}/amcl{sep}max_particles" in names
    assert sorted(names) == sorted(nav2.world.params)
    if nav2.dialect == "ros2":
        assert len(names) >= 1000


async def test_a_filter_narrows_by_name_or_type_and_says_how_many_matched(session: Session) -> None:
    """A substring on types (nav2_msgs) and a glob on names (*costmap*) keep only what matches."""
    by_type = await session.ok("list_topics", {"filter": "nav2_msgs"})
    by_glob = await session.ok("list_topics", {"filter": "*costmap*"})
    assert by_type.structured_content is not None
    assert by_glob.structured_content is not None
    assert all("nav2_msgs" in row["type"] for row in by_type.structured_content["topics"])
    assert by_glob.structured_content["topics"]
    assert all("costmap" in row["name"] for row in by_glob.structured_content["topics"])
    assert "match '*costmap*'" in text_of(by_glob)


async def test_a_node_s_parameters_can_be_filtered(session: Session, nav2: SimulatedRobot) -> None:
    """list_parameters with node and filter keeps that node's matching names, grouped under the node."""
    node = f"{prefix(nav2)}/controller_server"
    data = (await session.ok("list_parameters", {"node": node, "filter": "*vx_max*"})).structured_content
    assert data is not None
    assert data["nodes"][0]["node"] == node
    assert parameter_names(data) == [f"{node}{data['separator']}{name}" for name in data["nodes"][0]["names"]]
    assert all("vx_max" in name for name in data["nodes"][0]["names"])


async def test_a_bad_page_argument_is_an_error_naming_it(session: Session) -> None:
    """A negative offset or a zero limit is refused before anything is asked."""
    assert "offset" in await session.error("list_topics", {"offset": -1})
    assert "limit" in await session.error("list_nodes", {"limit": 0})


async def test_publish_action_navigates_the_robot_in_either_dialect(
    session: Session, nav2: SimulatedRobot
) -> None:
    """NavigateToPose through publish_action: the goal succeeds and the robot stands at the goal."""
    ns = prefix(nav2)
    nav2.nav2.navigator.speed = 5.0  # a test drive of a second or two
    action_type = (
        "nav2_msgs/action/NavigateToPose" if nav2.dialect == "ros2" else "nav2_msgs/NavigateToPoseAction"
    )
    goal = {"pose": {"header": {"frame_id": "map"}, "pose": {"position": {"x": 3.0, "y": 4.0}}}}
    result = await session.ok(
        "publish_action",
        {"action_name": f"{ns}/navigate_to_pose", "action_type": action_type, "goal": goal, "timeout": 10},
    )
    assert (result.structured_content or {})["succeeded"] is True
    robot = nav2.nav2.robots[0]
    assert robot.x == pytest.approx(3.0, abs=0.05)
    assert robot.y == pytest.approx(4.0, abs=0.05)


@pytest.mark.asyncio(loop_scope="function")  # its robot and session are its own
async def test_get_node_info_filters_and_keeps_a_large_node_within_the_budget(
    session_ros2: Session, sim_ros2: SimulatedRobot
) -> None:
    """A node with 400 topics: the text stays within 8,000 characters and says how many more; a filter
    narrows to what matches."""
    async with connect(sim_ros2.url) as client:
        for i in range(400):
            topic = f"/fleet_status/robot_{i:03d}/battery_percentage"
            advertise = {"op": "advertise", "topic": topic, "type": "std_msgs/msg/Float32", "id": f"a{i}"}
            await client.send(json.dumps(advertise))
        # An advertise takes effect as it arrives: once this later call is answered, every topic is there.
        await client.send(json.dumps({"op": "call_service", "id": "barrier", "service": "/rosapi/get_time"}))
        async with asyncio.timeout(5):
            while json.loads(await client.recv()).get("id") != "barrier":
                pass
        whole = await session_ros2.ok("get_node_info", {"node": "/rosbridge_websocket"})
        narrow = await session_ros2.ok(
            "get_node_info", {"node": "/rosbridge_websocket", "filter": "*robot_01?/*"}
        )
    assert len(text_of(whole)) <= TEXT_BUDGET
    assert (whole.structured_content or {})["more"] > 0
    assert "more not shown" in text_of(whole)
    rows = (narrow.structured_content or {})["publications"]
    assert [row["name"] for row in rows] == [
        f"/fleet_status/robot_{i:03d}/battery_percentage" for i in range(10, 20)
    ]
