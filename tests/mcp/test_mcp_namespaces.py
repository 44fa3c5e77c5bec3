"""Robots under a namespace on one bridge (the sim's Nav2 fleet, ``robots=2``: ``/robot1``, ``/robot2``), in
both dialects: ``navigate_to``, ``get_transform``, ``view_map`` and ``view_scan`` take ``namespace`` and use
that robot's action, map, scan and tf; without one, several robots are an error listing each robot's exact
call (checked against the tool's schema, and run); the one robot left with the names is found and said."""

from __future__ import annotations

import asyncio
import json
import math
import re
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import jsonschema
import pytest
import websockets
from mcp_harness import Session, open_session, text_of

from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.world import TURTLE_HOME

MakeSim = Callable[..., Awaitable[SimulatedRobot]]

TOOLS = ("navigate_to", "get_transform", "view_map", "view_scan", "diagnose")
#: A goal 0.4 m ahead of a robot at home (both robots start there), facing the way it faces.
GOAL = {"x": round(TURTLE_HOME + 0.4, 3), "y": round(TURTLE_HOME, 3), "yaw": 0}


@pytest.fixture(params=["ros2", "ros1"])
async def fleet(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    robot = await make_sim(dialect=request.param, world="nav2", robots=2)
    robot.nav2.navigator.speed = 8.0
    return robot


@pytest.fixture
async def session(fleet: SimulatedRobot) -> AsyncIterator[Session]:
    async with open_session(fleet.url, tools=TOOLS) as opened:
        yield opened


def suggested_calls(text: str) -> list[tuple[str, dict[str, Any]]]:
    """Every ``→ tool {json}`` line of an answer."""
    calls = []
    for line in text.splitlines():
        found = re.match(r"^→ (\w+) (\{.*\})$", line.strip())
        if found:
            calls.append((found.group(1), json.loads(found.group(2))))
    return calls


async def schema_of(session: Session, tool: str) -> dict[str, Any]:
    listed = await session.mcp.list_tools()
    return next(t.input_schema for t in listed.tools if t.name == tool)


async def check_suggestions(session: Session, tool: str, text: str) -> list[dict[str, Any]]:
    """The answer lists one call per robot, each valid against the tool's schema."""
    calls = suggested_calls(text)
    assert [name for name, _ in calls] == [tool, tool], text
    assert [arguments["namespace"] for _, arguments in calls] == ["/robot1", "/robot2"], text
    schema = await schema_of(session, tool)
    for _, arguments in calls:
        jsonschema.validate(arguments, schema)
    return [arguments for _, arguments in calls]


async def test_navigate_to_with_a_namespace_drives_that_robot_only(
    session: Session, fleet: SimulatedRobot
) -> None:
    first, second = fleet.nav2.robots
    before = (first.x, first.y)
    result = await session.ok("navigate_to", {"goal": GOAL, "namespace": "/robot2"})
    assert (result.structured_content or {})["succeeded"], text_of(result)
    assert math.hypot(second.x - GOAL["x"], second.y - GOAL["y"]) < 0.2
    assert (first.x, first.y) == before


async def test_navigate_to_without_a_namespace_lists_each_robots_call_and_they_run(
    session: Session, fleet: SimulatedRobot
) -> None:
    goals = len(fleet.world.goals)
    text = await session.error("navigate_to", {"goal": GOAL, "timeout": 60})
    assert "Nothing was guessed, nothing was sent." in text
    assert len(fleet.world.goals) == goals
    calls = await check_suggestions(session, "navigate_to", text)
    assert all(call["goal"] == GOAL and call["timeout"] == 60 for call in calls)
    result = await session.ok("navigate_to", calls[1])
    assert (result.structured_content or {})["succeeded"], text_of(result)
    second = fleet.nav2.robots[1]
    assert math.hypot(second.x - GOAL["x"], second.y - GOAL["y"]) < 0.2


async def test_get_transform_reads_the_robots_own_tf(session: Session, fleet: SimulatedRobot) -> None:
    second = fleet.nav2.robots[1]
    second.x, second.y = TURTLE_HOME + 1.0, TURTLE_HOME - 0.5
    fleet.world.notify()
    arguments = {"target_frame": "map", "source_frame": "base_link", "namespace": "/robot2", "timeout": 5}
    result = await session.ok("get_transform", arguments)
    data = result.structured_content or {}
    assert data["namespace"] == "/robot2"
    assert abs(data["translation"]["x"] - second.x) < 0.05
    assert abs(data["translation"]["y"] - second.y) < 0.05


async def test_get_transform_without_a_namespace_lists_each_robots_call(session: Session) -> None:
    text = await session.error(
        "get_transform", {"target_frame": "map", "source_frame": "base_link", "timeout": 4}
    )
    for arguments in await check_suggestions(session, "get_transform", text):
        assert arguments["timeout"] == 4
        result = await session.ok("get_transform", arguments)
        assert (result.structured_content or {})["namespace"] == arguments["namespace"]


@pytest.mark.parametrize("tool", ["view_map", "view_scan"])
async def test_pictures_take_the_namespace_or_list_each_robots_call(session: Session, tool: str) -> None:
    result = await session.ok(tool, {"namespace": "/robot1"})
    assert (result.structured_content or {})["topic"] == (
        "/robot1/map" if tool == "view_map" else "/robot1/scan"
    )
    text = await session.error(tool, {"max_size": 300})
    for arguments in await check_suggestions(session, tool, text):
        assert arguments["max_size"] == 300  # what was asked is repeated
        await session.ok(tool, arguments)


async def test_view_map_places_the_namespaced_robot_from_its_tf(
    session: Session, fleet: SimulatedRobot
) -> None:
    second = fleet.nav2.robots[1]
    result = await session.ok("view_map", {"namespace": "/robot2", "path_topic": "/plan"})
    robot = (result.structured_content or {})["robot"]
    assert robot is not None, text_of(result)
    assert abs(robot[0] - second.x) < 0.1
    assert abs(robot[1] - second.y) < 0.1


async def test_a_bad_namespace_is_refused_naming_it(session: Session) -> None:
    text = await session.error("get_transform", {"target_frame": "map", "source_frame": "base_link",
                                                 "namespace": "robot 2"})  # fmt: skip
    assert "namespace 'robot 2' is not a ROS namespace" in text


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_diagnose_checks_each_robots_tf_and_finds_a_fault_on_robot2(
    make_sim: MakeSim, dialect: str
) -> None:
    fleet = await make_sim(dialect=dialect, world="nav2", robots=2)
    async with open_session(fleet.url, tools=TOOLS) as session:
        healthy = await session.ok("diagnose", {"focus": "tf"})
        fleet.nav2.robots[1].quiet.add("odom->base_footprint")  # robot2's odometry tf stops
        result = await session.ok("diagnose", {"focus": "tf"})
        robot1 = await session.ok("diagnose", {"focus": "navigation", "namespace": "/robot1"})
        robot2 = await session.ok("diagnose", {"focus": "navigation", "namespace": "/robot2"})
        schema = await schema_of(session, "get_transform")
    data = healthy.structured_content or {}
    assert data["unavailable"] == {}, text_of(healthy)
    assert data["checked"]["tf"].startswith("/robot1/tf: "), data["checked"]
    assert "/robot2/tf: " in data["checked"]["tf"]
    assert data["findings"] == [], text_of(healthy)
    assert {"/robot1:base_link", "/robot2:base_link"} <= set(data["frames"])
    text = text_of(result)
    findings = (result.structured_content or {})["findings"]
    assert [f["subject"] for f in findings] == ["/robot2 odom -> base_footprint"], text
    assert "(tf of /robot2)" in findings[0]["summary"]
    call = findings[0]["next"]
    assert call == (
        'get_transform {"target_frame": "odom", "source_frame": "base_footprint", "timeout": 5, '
        '"namespace": "/robot2"}'
    )
    assert f"→ {call}" in text
    jsonschema.validate(json.loads(call.removeprefix("get_transform ")), schema)
    # A namespace narrows the look to that robot's tf and streams.
    one, two = robot1.structured_content or {}, robot2.structured_content or {}
    assert one["findings"] == [], text_of(robot1)
    assert one["checked"]["tf"].startswith("/robot1/tf: ")
    assert "/robot2" not in one["checked"]["tf"]
    assert all(topic.startswith("/robot1/") for topic in one["streams"]), one["streams"]
    assert [f["subject"] for f in two["findings"]] == ["/robot2 odom -> base_footprint"], text_of(robot2)


async def test_diagnose_never_calls_a_robot_healthy_when_it_skipped_its_tf(make_sim: MakeSim) -> None:
    """The turtle world with its tf taken out of the graph: the answer says tf was not checked."""
    robot = await make_sim(dialect="ros2")
    for name in list(robot.graph.nodes):
        for topic in ("/tf", "/tf_static"):
            while robot.graph.nodes[name].publishes.get(topic):
                robot.graph.remove_publisher(name, topic)
    async with open_session(robot.url, tools=TOOLS) as session:
        result = await session.ok("diagnose", {"focus": "tf"})
    text = text_of(result)
    assert not text.startswith("No problem found."), text
    assert text.startswith("No problem found in the areas checked (not checked: tf) (focus: tf)."), text
    assert "Not checked: tf: the robot has no /tf or /tf_static topic" in text


def leave_graph(robot: SimulatedRobot, namespace: str) -> None:
    """Every node under *namespace* leaves the graph (its topics, services and actions go with it)."""
    graph = robot.graph
    for name in [n for n in graph.nodes if n.startswith(f"{namespace}/")]:
        info = graph.nodes[name]
        for topic, count in list(info.publishes.items()):
            for _ in range(count):
                graph.remove_publisher(name, topic)
        for topic, count in list(info.subscribes.items()):
            for _ in range(count):
                graph.remove_subscriber(name, topic)
        for service in list(info.services):
            graph.remove_service(service)
        del graph.nodes[name]
    for action in [a for a in graph.actions if a.startswith(f"{namespace}/")]:
        del graph.actions[action]


async def test_the_one_robot_with_the_names_is_found_and_said(make_sim: MakeSim) -> None:
    """ROS 2 (the ROS 1 master never forgets a topic's type): only /robot2 is left on the bridge."""
    fleet = await make_sim(dialect="ros2", world="nav2", robots=2)
    fleet.nav2.navigator.speed = 8.0
    leave_graph(fleet, "/robot1")
    async with open_session(fleet.url, tools=TOOLS) as session:
        transform = await session.ok("get_transform", {"target_frame": "map", "source_frame": "base_link"})
        scan = await session.ok("view_scan", {})
        drive = await session.ok("navigate_to", {"goal": GOAL})
    assert text_of(transform).startswith("Using namespace /robot2: /tf is not in the graph, /robot2/tf is.")
    assert (transform.structured_content or {})["namespace"] == "/robot2"
    assert text_of(scan).startswith("Using namespace /robot2: /scan is not in the graph")
    assert (scan.structured_content or {})["topic"] == "/robot2/scan"
    assert text_of(drive).startswith("Using namespace /robot2: /navigate_to_pose is not in the graph")
    second = fleet.nav2.robots[1]
    assert math.hypot(second.x - GOAL["x"], second.y - GOAL["y"]) < 0.2


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_prefixed_frames_on_one_shared_tf_are_found_under_the_namespace(
    make_sim: MakeSim, dialect: str
) -> None:
    """The other multi-robot setup: one /tf, each robot's frames prefixed (robot2/odom → robot2/base_link);
    a raw client publishes robot2's link on the turtle robot's /tf."""
    robot = await make_sim(dialect=dialect)
    tf_type = "tf2_msgs/msg/TFMessage" if dialect == "ros2" else "tf2_msgs/TFMessage"
    link = {
        "header": {"frame_id": "robot2/odom", "stamp": {"sec": 1, "nanosec": 0}},
        "child_frame_id": "robot2/base_link",
        "transform": {"translation": {"x": 1.5, "y": -0.5, "z": 0.0}, "rotation": {"w": 1.0}},
    }

    async def publish(ws: Any) -> None:
        await ws.send(json.dumps({"op": "advertise", "topic": "/tf", "type": tf_type}))
        while True:  # a tf publisher at 20 Hz, as a robot's would be
            await ws.send(json.dumps({"op": "publish", "topic": "/tf", "msg": {"transforms": [link]}}))
            await asyncio.sleep(0.05)

    async with websockets.connect(robot.url) as ws, open_session(robot.url, tools=TOOLS) as session:
        publisher = asyncio.create_task(publish(ws))
        try:
            arguments = {"target_frame": "odom", "source_frame": "base_link", "namespace": "/robot2"}
            result = await session.ok("get_transform", {**arguments, "timeout": 5})
        finally:
            publisher.cancel()
    data = result.structured_content or {}
    assert data["target_frame"] == "robot2/odom"
    assert data["source_frame"] == "robot2/base_link"
    assert data["translation"] == {"x": 1.5, "y": -0.5, "z": 0.0}


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_the_fence_judges_a_namespaced_goal_by_that_robots_map_and_pose(
    make_sim: MakeSim, dialect: str
) -> None:
    """A goal to /robot2 by any carrier is placed with /robot2's map and tf: one too far from robot2 (not
    from the origin) is refused, one near it goes, under a policy with a maximum goal distance."""
    fleet = await make_sim(dialect=dialect, world="nav2", robots=2)
    fleet.nav2.navigator.speed = 8.0
    policy = parse_policy({"navigation": {"max_goal_distance": 2.0}}, where="test.toml")
    action, action_type, key = (
        ("/robot2/navigate_to_pose", "nav2_msgs/action/NavigateToPose", "pose")
        if dialect == "ros2"
        else ("/robot2/move_base", "move_base_msgs/MoveBaseAction", "target_pose")
    )

    def goal(x: float, y: float) -> dict[str, Any]:
        stamped = {
            "header": {"frame_id": "map"},
            "pose": {"position": {"x": x, "y": y}, "orientation": {"w": 1}},
        }
        return {"action_name": action, "action_type": action_type, "goal": {key: stamped}, "timeout": 30}

    async with open_session(
        fleet.url, guard=None, policy=policy, tools=(*TOOLS, "publish_action")
    ) as session:
        far = await session.error("publish_action", goal(TURTLE_HOME + 3.0, TURTLE_HOME))
        near = await session.call("publish_action", goal(GOAL["x"], GOAL["y"]))
    assert "beyond the maximum goal distance 2 m" in far, far
    assert "3.00 m from the robot" in far, far
    assert not near.is_error, text_of(near)
    second = fleet.nav2.robots[1]
    assert math.hypot(second.x - GOAL["x"], second.y - GOAL["y"]) < 0.2


async def test_view_map_of_a_robots_topic_places_that_robot_without_a_namespace(
    session: Session, fleet: SimulatedRobot
) -> None:
    """{"topic": "/robot2/map"}: the robot drawn is robot2, from /robot2/tf (several robots' tf, no guess)."""
    second = fleet.nav2.robots[1]
    second.x += 1.0
    result = await session.ok("view_map", {"topic": "/robot2/map"})
    robot = (result.structured_content or {})["robot"]
    assert robot is not None, text_of(result)
    assert abs(robot[0] - second.x) < 0.1
