"""The fence stands on what the model cannot write, and what moves the robot or the fence is asked about
(issue 35, findings 2, 4 and 7), attacked through a real MCP session in both dialects on the Nav2 world.

What reaches the robot is read from the robot itself (the messages and calls it received, a raw rosbridge
socket of the test's own, the simulated world's true pose), after a barrier publish: the server's frames
arrive in order, so anything it sent before the barrier has arrived when the barrier has.
"""

from __future__ import annotations

import asyncio
import io
import itertools
import json
import math
from collections.abc import Awaitable, Callable
from typing import Any

import pytest
from mcp_harness import Session, open_session, text_of
from test_mcp_effects import Person, watching

from rosbridge_mcp_server.safety import Audit, Operator, Policy, PolicyGuard, parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]
TEST_SPEED = 8.0
#: odom sits at (5.544, 5.544) in map in the Nav2 world: (-2, 1) in odom is (3.544, 6.544) in map.
PIT = [[3.0, 6.0], [4.1, 6.0], [4.1, 7.1], [3.0, 7.1]]
_marks = itertools.count(1)


def rules(**navigation: Any) -> Policy:
    return parse_policy({"navigation": {"keep_out": {"pit": PIT}, **navigation}}, where="test.toml")


def spelt(sim: SimulatedRobot, type_name: str) -> str:
    """``pkg/msg/Type`` as the robot's dialect spells it."""
    return type_name if sim.dialect == "ros2" else type_name.replace("/msg/", "/").replace("/srv/", "/")


@pytest.fixture(params=["ros2", "ros1"])
async def nav2(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    robot = await make_sim(dialect=request.param, world="nav2")
    robot.nav2.navigator.speed = TEST_SPEED
    return robot


async def barrier(session: Session, sim: SimulatedRobot) -> None:
    """Everything the server sent before this has reached the robot."""
    topic = f"/barrier_{next(_marks)}"
    message = {"topic": topic, "message_type": spelt(sim, "std_msgs/msg/String"), "message": {"data": "b"}}
    await session.ok("publish_topic", message)
    await sim.wait_for(lambda world: topic in world.published)


def forged_tf(
    sim: SimulatedRobot, x: float, y: float, *, parent: str = "map", child: str = "odom"
) -> dict[str, Any]:
    transform = {
        "header": {"frame_id": parent, "stamp": {"sec": 0, "nanosec": 0}},
        "child_frame_id": child,
        "transform": {
            "translation": {"x": x, "y": y, "z": 0.0},
            "rotation": {"x": 0, "y": 0, "z": 0, "w": 1},
        },
    }
    return {
        "topic": "/tf",
        "message_type": spelt(sim, "tf2_msgs/msg/TFMessage"),
        "message": {"transforms": [transform]},
    }


def fence_writes(sim: SimulatedRobot) -> list[tuple[str, dict[str, Any]]]:
    """Writes of what the fence or localisation reads: by name, by type under another name, namespaced."""
    pose = spelt(sim, "geometry_msgs/msg/PoseWithCovarianceStamped")
    grid = spelt(sim, "nav_msgs/msg/OccupancyGrid")
    writes: list[tuple[str, dict[str, Any]]] = [
        ("publish_topic", forged_tf(sim, 4.0, 3.0)),
        ("publish_topic", {**forged_tf(sim, 4.0, 3.0), "topic": "/robot1/tf_static"}),
        ("publish_topic", {"topic": "/initialpose", "message_type": pose, "message": {}}),
        ("publish_topic", {"topic": "/relocalise_here", "message_type": pose, "message": {}}),
        ("publish_topic", {"topic": "/map", "message_type": grid, "message": {}}),
        ("publish_topic", {"topic": "/keepout_filter_mask", "message_type": grid, "message": {}}),
        (
            "publish_topic",
            {
                "topic": "/speed_limit",
                "message_type": spelt(sim, "nav2_msgs/msg/SpeedLimit"),
                "message": {"speed_limit": 5.0},
            },
        ),
    ]
    if sim.dialect == "ros2":
        writes += [
            (
                "publish_service",
                {
                    "service": "/set_initial_pose",
                    "service_type": "nav2_msgs/srv/SetInitialPose",
                    "request": {},
                },
            ),
            (
                "publish_service",
                {
                    "service": "/map_server/load_map",
                    "service_type": "nav2_msgs/srv/LoadMap",
                    "request": {"map_url": "/tmp/elsewhere.yaml"},
                },
            ),
        ]
    return writes


def target(arguments: dict[str, Any]) -> str:
    return str(arguments.get("topic") or arguments.get("service"))


async def test_writes_to_what_the_fence_reads_are_refused_while_zones_are_set(nav2: SimulatedRobot) -> None:
    """No [topics] or [services] rules at all: [navigation]'s keep-out alone refuses every fence write,
    by name and by type, and none of them reaches the robot."""
    stream = io.StringIO()
    guard = PolicyGuard(rules(), Audit(stream))
    async with open_session(nav2.url, guard=guard, policy=rules()) as session:
        texts = {target(args): await session.error(tool, args) for tool, args in fence_writes(nav2)}
        await barrier(session, nav2)
    audit = {entry["name"]: entry for entry in map(json.loads, stream.getvalue().splitlines())}
    for name, text in texts.items():
        assert f"on {name} writes what the safety fence and localisation read" in text, text
        assert "allow_fence_writes" in text
        assert name not in nav2.world.published
        assert nav2.world.service_calls.get(name, 0) == 0
        assert audit[name]["outcome"] == "refused"
        assert audit[name]["detail"] == f"[navigation] fence write: {name}"
        assert [effect["kind"] for effect in audit[name]["effects"]] == ["fence"]


async def test_allow_fence_writes_lets_only_what_it_names_through(nav2: SimulatedRobot) -> None:
    """allow_fence_writes = ["/initialpose"]: the operator's relocalisation goes, /tf does not."""
    pose = spelt(nav2, "geometry_msgs/msg/PoseWithCovarianceStamped")
    initial = {"topic": "/initialpose", "message_type": pose, "message": {"header": {"frame_id": "map"}}}
    async with open_session(
        nav2.url, guard=None, policy=rules(allow_fence_writes=["/initialpose"])
    ) as session:
        await session.ok("publish_topic", initial)
        text = await session.error("publish_topic", forged_tf(nav2, 4.0, 3.0))
        await barrier(session, nav2)
    assert "/initialpose" in nav2.world.published
    assert "/tf" not in nav2.world.published
    assert "allow_fence_writes" in text


def odom_goal(sim: SimulatedRobot, x: float, y: float) -> dict[str, Any]:
    """publish_action's arguments for a navigation goal to (x, y) in the odom frame, in the robot's dialect:
    the navigator places it through its own (true) transforms, the fence through what /tf says."""
    pose = {"position": {"x": x, "y": y}, "orientation": {"w": 1.0}}
    stamped = {"header": {"frame_id": "odom"}, "pose": pose}
    if sim.dialect == "ros1":
        return {
            "action_name": "/move_base",
            "action_type": "move_base_msgs/MoveBaseAction",
            "goal": {"target_pose": stamped},
        }
    return {
        "action_name": "/navigate_to_pose",
        "action_type": "nav2_msgs/action/NavigateToPose",
        "goal": {"pose": stamped},
    }


async def test_a_forged_tf_cannot_carry_a_goal_into_keep_out(nav2: SimulatedRobot) -> None:
    """The attack of finding 2: a 50 Hz /tf stream moving map→odom 1.5 m, and while it runs a goal in odom
    whose true place is in the keep-out zone. The stream is refused, the goal is judged where it truly is, and
    the robot never enters the zone."""
    stream = {**forged_tf(nav2, 4.0, 3.0), "rate_hz": 50, "duration": 3}
    robot = nav2.nav2.robots[0]
    tf_type = spelt(nav2, "tf2_msgs/msg/TFMessage")
    async with watching(nav2) as watcher, open_session(nav2.url, guard=None, policy=rules()) as session:
        await watcher.subscribe("/tf", tf_type)
        await watcher.wait_for("/tf", lambda message: True)  # the robot's own: the raw socket hears /tf
        streaming = asyncio.create_task(session.call("publish_topic", stream))
        forged = asyncio.create_task(nav2.wait_for(lambda world: "/tf" in world.published, timeout=10))
        await asyncio.wait({streaming, forged}, return_when=asyncio.FIRST_COMPLETED)
        goal = await session.call("publish_action", {**odom_goal(nav2, -2.0, 1.0), "timeout": 30})
        refused = await streaming
        forged.cancel()
        await barrier(session, nav2)
    assert math.hypot(robot.x - 3.544, robot.y - 6.544) > 1.0, (robot.x, robot.y)
    assert refused.is_error
    assert "/tf writes what the safety fence and localisation read" in text_of(refused)
    assert goal.is_error
    assert "pit" in text_of(goal), text_of(goal)
    assert "/tf" not in nav2.world.published
    heard = [t["transform"]["translation"] for m in watcher.seen["/tf"] for t in m["transforms"]]
    assert not any((t["x"], t["y"]) == (4.0, 3.0) for t in heard)


async def test_a_forged_map_to_base_link_in_a_fleet_cannot_stretch_the_distance(make_sim: MakeSim) -> None:
    """In a namespaced fleet a forged ``map → base_link`` on /robot1/tf, streamed while a goal 5 m away is
    sent, once let it through max_goal_distance = 2 (the robot drove 4.98 m). The stream is refused by name
    (namespaced) as it is by type under another name; the goal is judged from the true pose."""
    sim = await make_sim(dialect="ros2", world="nav2", robots=2)
    sim.nav2.navigator.speed = TEST_SPEED
    robot = sim.nav2.robots[0]
    start = (robot.x, robot.y)
    goal_x, goal_y = start[0] - 4.0, start[1] + 3.0
    policy = parse_policy({"navigation": {"max_goal_distance": 2.0}}, where="test.toml")
    forged = forged_tf(sim, goal_x + 0.5, goal_y, child="base_link")
    stream = {**forged, "topic": "/robot1/tf", "rate_hz": 50, "duration": 3}
    stamped = {"header": {"frame_id": "map"}, "pose": {"position": {"x": goal_x, "y": goal_y}}}
    goal = {
        "action_name": "/robot1/navigate_to_pose",
        "action_type": "nav2_msgs/action/NavigateToPose",
        "goal": {"pose": {**stamped, "pose": {**stamped["pose"], "orientation": {"w": 1.0}}}},
        "timeout": 30,
    }
    async with open_session(sim.url, guard=None, policy=policy) as session:
        streaming = asyncio.create_task(session.call("publish_topic", stream))
        arrived = asyncio.create_task(sim.wait_for(lambda world: "/robot1/tf" in world.published, timeout=10))
        await asyncio.wait({streaming, arrived}, return_when=asyncio.FIRST_COMPLETED)
        sent = await session.call("publish_action", goal)
        refused = await streaming
        arrived.cancel()
        elsewhere = await session.call("publish_topic", {**forged, "topic": "/robot1/elsewhere"})
        await barrier(session, sim)
    assert math.hypot(robot.x - start[0], robot.y - start[1]) < 0.5, (start, robot.x, robot.y)
    assert refused.is_error
    assert sent.is_error
    assert "max_goal_distance" in text_of(sent) or "maximum goal distance" in text_of(sent), text_of(sent)
    assert elsewhere.is_error
    for text in (text_of(refused), text_of(elsewhere)):
        assert "writes what the safety fence and localisation read" in text
    assert "/robot1/tf" not in sim.world.published
    assert "/robot1/elsewhere" not in sim.world.published


def motion_writes(sim: SimulatedRobot) -> list[tuple[str, dict[str, Any]]]:
    joy = {
        "topic": "/joy",
        "message_type": spelt(sim, "sensor_msgs/msg/Joy"),
        "message": {"axes": [1.0, 0.0], "buttons": [1]},
    }
    writes = [("publish_topic", joy), *fence_writes(sim)[2:]]
    if sim.dialect == "ros2":
        change = {"transition": {"id": 4, "label": "deactivate"}}
        manage = {"command": 1}  # PAUSE
        writes += [
            (
                "publish_service",
                {
                    "service": "/controller_server/change_state",
                    "service_type": "lifecycle_msgs/srv/ChangeState",
                    "request": change,
                },
            ),
            (
                "publish_service",
                {
                    "service": "/lifecycle_manager_navigation/manage_nodes",
                    "service_type": "nav2_msgs/srv/ManageLifecycleNodes",
                    "request": manage,
                },
            ),
        ]
    return writes


async def test_confirm_motion_asks_before_a_joystick_and_every_fence_write(nav2: SimulatedRobot) -> None:
    """confirm = "motion", no zones: /joy (teleop turns it into velocity), /initialpose, /speed_limit, the
    masks, the map, AMCL's and map_server's services, a controller's lifecycle transition and Nav2's lifecycle
    manager are each asked about; declined, none reaches the robot."""
    person = Person("decline")
    policy = parse_policy({"confirm": "motion"}, where="test.toml")
    writes = motion_writes(nav2)
    async with open_session(nav2.url, guard=None, policy=policy, elicitation_callback=person) as session:
        texts = [await session.error(tool, args) for tool, args in writes]
        await barrier(session, nav2)
    assert all("The person declined" in text for text in texts), texts
    assert len(person.questions) == len(writes)
    assert "teleop turns it into velocity" in person.questions[0]
    assert "a change of what the safety fence and localisation read" in person.questions[1]
    for _, args in writes:
        assert target(args) not in nav2.world.published
        assert nav2.world.service_calls.get(target(args), 0) == 0


async def test_a_reset_teleports_so_confirm_motion_asks(sim: SimulatedRobot) -> None:
    """turtlesim's /reset puts the turtle back at the start: declined, the turtle stays where it drove."""
    person = Person("decline")
    policy = parse_policy({"confirm": "motion"}, where="test.toml")
    teleport = "turtlesim/srv/TeleportAbsolute" if sim.dialect == "ros2" else "turtlesim/TeleportAbsolute"
    empty = spelt(sim, "std_srvs/srv/Empty")
    async with open_session(sim.url, guard=None, policy=policy, elicitation_callback=person) as session:
        person.action = "accept"
        await session.ok(
            "publish_service",
            {
                "service": "/turtle1/teleport_absolute",
                "service_type": teleport,
                "request": {"x": 1.0, "y": 1.0, "theta": 0.0},
            },
        )
        person.action = "decline"
        text = await session.error(
            "publish_service", {"service": "/reset", "service_type": empty, "request": {}}
        )
    assert "The person declined" in text
    assert "a reset" in person.questions[-1]
    assert sim.world.service_calls.get("/reset", 0) == 0
    assert (sim.world.turtle.x, sim.world.turtle.y) == (1.0, 1.0)


async def test_rosapi_set_param_served_under_another_name_meets_parameters_deny(sim: SimulatedRobot) -> None:
    """A service of rosapi's SetParam type (either spelling) under any name is a parameter write: [parameters]
    deny refuses it, and the service host (a raw socket of the test's own) never hears the call."""
    kind = "rosapi_msgs/srv/SetParam" if sim.dialect == "ros2" else "rosapi/SetParam"
    name = "/turtlesim:background_r" if sim.dialect == "ros2" else "/turtlesim/background_r"
    policy = parse_policy({"parameters": {"deny": [name]}}, where="test.toml")
    async with watching(sim) as host, open_session(sim.url, guard=None, policy=policy) as session:
        await host.ws.send(f'{{"op": "advertise_service", "service": "/innocent", "type": "{kind}"}}')
        await sim.wait_for(lambda world: "/innocent" in sim.graph.services, timeout=15)
        text = await session.error(
            "publish_service",
            {"service": "/innocent", "service_type": kind, "request": {"name": name, "value": "9"}},
        )
    assert f"[parameters] deny '{name}' matches {name}" in text
    assert sim.world.service_calls.get("/innocent", 0) == 0


async def test_the_person_sees_every_value_they_approve_on_both_paths(sim: SimulatedRobot) -> None:
    """Finding 7: a 4,000-space frame_id with a right-to-left override once pushed ``x: 9.0`` out of the
    question. The MCP client's question and the console's approval page both show it whole, the string cut
    and escaped; declined on both, nothing reaches the robot."""
    frame = " " * 4000 + "\u202emap"
    goal = {"header": {"frame_id": frame}, "pose": {"position": {"x": 9.0, "y": 2.5}}}
    call = {
        "topic": "/goal_pose",
        "message_type": spelt(sim, "geometry_msgs/msg/PoseStamped"),
        "message": goal,
    }
    person = Person("decline")
    client = parse_policy({"confirm": "motion"}, where="test.toml")
    async with open_session(sim.url, guard=None, policy=client, elicitation_callback=person) as session:
        await session.error("publish_topic", call)
    console = parse_policy({"confirm": "motion", "approvals": "console"}, where="test.toml")
    operator = Operator(present=True)
    asked = asyncio.Event()
    operator.listen(lambda: asked.set() if operator.pending else None)
    async with open_session(
        sim.url, guard=PolicyGuard(console, Audit(), operator), policy=console
    ) as session:
        calling = asyncio.create_task(session.call("publish_topic", call))
        await asyncio.wait_for(asked.wait(), 5.0)
        [pending] = operator.pending
        operator.answer(pending.id, False)
        assert (await asyncio.wait_for(calling, 15.0)).is_error
        await barrier(session, sim)
    for text in (person.questions[0], pending.question):
        assert "  pose.position.x: 9.0\n" in text
        assert "  pose.position.y: 2.5\n" in text
        assert "\u202e" not in text
        assert "(4004 characters, 3884 not shown)" in text
        assert len(text) < 2000
    assert "/goal_pose" not in sim.world.published
