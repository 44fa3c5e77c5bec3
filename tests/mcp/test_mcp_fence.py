"""The navigation fence judges every motion goal the robot can be sent, on its footprint, and fails closed.

An MCP session under the server's own guard drives the simulated Nav2 world (both dialects; Kilted's
``nav_msgs/Goals`` shape on ROS 2 only) with keep-out zones, by every carrier a goal can take:
``publish_action``, ROS 2's ``<action>/_action/send_goal`` through ``publish_service``, ROS 1's actionlib
``<action>/goal`` and the goal pose topics through ``publish_topic``, and ``navigate_to``. A raw rosbridge
socket subscribed to every motion action's goal traffic (ROS 2: its status list; ROS 1: its goal topic)
watches that a refused goal never reaches the robot, and sees an allowed one (the control) arrive.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import pytest
import websockets
from mcp_harness import open_session, text_of

from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.world import TURTLE_HOME

MakeSim = Callable[..., Awaitable[SimulatedRobot]]

HOME = TURTLE_HOME  # the robot starts at (HOME, HOME) facing +x
#: Keep-out zones east and west of the robot (a metre away) and in a corner of the room.
ZONES = {
    "east": [[6.6, 4.5], [7.6, 4.5], [7.6, 6.5], [6.6, 6.5]],
    "west": [[3.0, 4.5], [4.0, 4.5], [4.0, 6.5], [3.0, 6.5]],
    "corner": [[8.0, 1.0], [10.5, 1.0], [10.5, 3.0], [8.0, 3.0]],
}
POLICY = {"navigation": {"keep_out": ZONES}}
#: Every Nav2 motion action the world serves: name → type's last part.
MOTION_ACTIONS = {
    "navigate_to_pose": "NavigateToPose",
    "navigate_through_poses": "NavigateThroughPoses",
    "follow_path": "FollowPath",
    "drive_on_heading": "DriveOnHeading",
    "backup": "BackUp",
    "spin": "Spin",
    "assisted_teleop": "AssistedTeleop",
    "follow_waypoints": "FollowWaypoints",
    "dock_robot": "DockRobot",
    "undock_robot": "UndockRobot",
}


def stamped(x: float, y: float, frame: str = "map") -> dict[str, Any]:
    return {"header": {"frame_id": frame}, "pose": {"position": {"x": x, "y": y}, "orientation": {"w": 1.0}}}


def drive(metres: float, speed: float = 0.2) -> dict[str, Any]:
    """A DriveOnHeading / BackUp goal."""
    return {"target": {"x": metres}, "speed": speed, "time_allowance": {"sec": 30}}


#: Goals the fence must refuse under POLICY: (action, goal, what the refusal names).
REFUSED: list[tuple[str, dict[str, Any], str]] = [
    (
        "follow_path",
        {"path": {"header": {"frame_id": "map"}, "poses": [stamped(5.8, HOME), stamped(7.0, HOME)]}},
        "keep-out zone 'east'",
    ),
    ("drive_on_heading", drive(2.0), "keep-out zone 'east'"),
    ("drive_on_heading", drive(100.0, 5.0), "off the map"),
    # Ends beyond the zone, in free space: the straight drive through it is what is refused.
    ("drive_on_heading", drive(3.5), "keep-out zone 'east'"),
    ("backup", drive(2.0), "keep-out zone 'west'"),
    ("assisted_teleop", {"time_allowance": {"sec": 10}}, "cannot be placed"),
    (
        "dock_robot",
        {"use_dock_id": False, "dock_pose": stamped(7.0, 5.5), "dock_type": "charger"},
        "keep-out zone 'east'",
    ),
    ("dock_robot", {"use_dock_id": True, "dock_id": "home"}, "cannot be placed"),
    ("undock_robot", {"dock_type": "charger"}, "cannot be placed"),
    ("follow_waypoints", {"poses": [stamped(4.5, 7.5), stamped(9.0, 2.0)]}, "keep-out zone 'corner'"),
    ("navigate_through_poses", {"poses": [stamped(4.5, 7.5), stamped(9.0, 2.0)]}, "keep-out zone 'corner'"),
]


def carriers(robot: SimulatedRobot, action: str, goal: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """Every tool call that sends *goal* to *action* in the robot's dialect."""
    leaf = MOTION_ACTIONS[action]
    if robot.dialect == "ros1":
        return [
            (
                "publish_action",
                {"action_name": f"/{action}", "action_type": f"nav2_msgs/{leaf}Action", "goal": goal},
            ),
            (
                "publish_topic",
                {
                    "topic": f"/{action}/goal",
                    "message_type": f"nav2_msgs/{leaf}ActionGoal",
                    "message": {"goal": goal},
                },
            ),
        ]
    return [
        (
            "publish_action",
            {"action_name": f"/{action}", "action_type": f"nav2_msgs/action/{leaf}", "goal": goal},
        ),
        (
            "publish_service",
            {
                "service": f"/{action}/_action/send_goal",
                "service_type": f"nav2_msgs/action/{leaf}_SendGoal",
                "request": {"goal_id": {"uuid": list(range(16))}, "goal": goal},
            },
        ),
    ]


class Watcher:
    """A raw rosbridge socket subscribed to every motion action's goal traffic and the goal pose topics."""

    def __init__(self, ws: Any) -> None:
        self.ws = ws
        self.seen: list[tuple[str, dict[str, Any]]] = []
        self.changed = asyncio.Event()

    async def read(self) -> None:
        async for raw in self.ws:
            frame = json.loads(raw)
            if frame.get("op") != "publish" or frame["msg"].get("status_list") == []:
                continue
            self.seen.append((frame["topic"], frame["msg"]))
            self.changed.set()

    async def wait_for(self, topic: str) -> dict[str, Any]:
        async with asyncio.timeout(10.0):
            while True:
                for seen, message in self.seen:
                    if seen == topic:
                        return message
                self.changed.clear()
                await self.changed.wait()


@contextlib.asynccontextmanager
async def watching(robot: SimulatedRobot) -> AsyncIterator[Watcher]:
    subscriptions: list[tuple[str, str]] = []
    for action, leaf in {**MOTION_ACTIONS, "move_base": "MoveBase"}.items():
        if robot.dialect == "ros1":
            package = "move_base_msgs" if action == "move_base" else "nav2_msgs"
            subscriptions.append((f"/{action}/goal", f"{package}/{leaf}ActionGoal"))
        elif action != "move_base":
            subscriptions.append((f"/{action}/_action/status", "action_msgs/msg/GoalStatusArray"))
    pose_type = "geometry_msgs/PoseStamped" if robot.dialect == "ros1" else "geometry_msgs/msg/PoseStamped"
    subscriptions += [("/goal_pose", pose_type), ("/move_base_simple/goal", pose_type)]
    async with websockets.connect(robot.url) as ws:
        for topic, msg_type in subscriptions:
            await ws.send(json.dumps({"op": "subscribe", "topic": topic, "type": msg_type}))
        watcher = Watcher(ws)
        reader = asyncio.create_task(watcher.read())
        try:
            yield watcher
        finally:
            reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reader


def received(robot: SimulatedRobot) -> list[dict[str, Any]]:
    """Every goal the world's ROS 2 motion action servers accepted."""
    return [goal for server in robot.nav2.actions for goal in server.received]


@pytest.fixture(params=["ros2", "ros1"])
async def nav2(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    robot = await make_sim(dialect=request.param, world="nav2")
    robot.nav2.navigator.speed = 8.0
    return robot


async def test_every_motion_goal_the_fence_rules_out_is_refused_by_every_carrier(
    nav2: SimulatedRobot,
) -> None:
    """FollowPath, DriveOnHeading (end point and the straight drive), BackUp, AssistedTeleop, DockRobot by
    pose and by id, UndockRobot, FollowWaypoints, NavigateThroughPoses: each refused by publish_action and by
    its other carrier, naming why, with nothing sent; an allowed drive (the control) is seen arriving."""
    policy = parse_policy(POLICY, where="fence.toml")
    wrong: list[str] = []
    async with open_session(nav2.url, guard=None, policy=policy) as session, watching(nav2) as watcher:
        for action, goal, why in REFUSED:
            for tool, arguments in carriers(nav2, action, goal):
                result = await session.call(tool, arguments)
                text = text_of(result)
                if not result.is_error or why not in text or "nothing was sent" not in text:
                    wrong.append(f"{tool} {action} {goal}: {text[:300]}")
        assert not watcher.seen, watcher.seen
        if nav2.dialect == "ros2":
            assert received(nav2) == []
        control = await session.call("publish_action", carriers(nav2, "drive_on_heading", drive(0.5))[0][1])
        assert not control.is_error, text_of(control)
        seen = "/drive_on_heading/goal" if nav2.dialect == "ros1" else "/drive_on_heading/_action/status"
        await watcher.wait_for(seen)
    assert not wrong, "\n".join(wrong)


async def test_kilted_through_poses_are_read_as_nav_msgs_goals(make_sim: MakeSim) -> None:
    """Kilted's NavigateThroughPoses takes ``poses`` as nav_msgs/Goals: a waypoint in keep-out is refused by
    both carriers (not read as one pose at (0, 0)); free waypoints in that shape are driven, navigate_to's
    too."""
    robot = await make_sim(dialect="ros2", world="nav2", distro="kilted")
    robot.nav2.navigator.speed = 8.0
    policy = parse_policy(POLICY, where="fence.toml")
    into = {"poses": {"header": {"frame_id": "map"}, "goals": [stamped(4.5, 7.5), stamped(9.0, 2.0)]}}
    async with open_session(robot.url, guard=None, policy=policy) as session, watching(robot) as watcher:
        for tool, arguments in carriers(robot, "navigate_through_poses", into):
            text = await session.error(tool, arguments)
            assert "keep-out zone 'corner'" in text, text
            assert "nothing was sent" in text
        assert not watcher.seen
        assert received(robot) == []
        free = {"poses": {"header": {"frame_id": "map"}, "goals": [stamped(4.5, 7.5), stamped(3.0, 7.5)]}}
        done = await session.ok("publish_action", dict(carriers(robot, "navigate_through_poses", free)[0][1]))
        assert "succeeded" in text_of(done).lower(), text_of(done)
        here = robot.nav2.robots[0]
        assert math.hypot(here.x - 3.0, here.y - 7.5) < 0.2
        # navigate_to's own waypoints go out in Kilted's shape too.
        driven = await session.ok("navigate_to", {"goal": [[4.0, 7.0], [5.0, 7.5, 0]]})
        assert (driven.structured_content or {})["succeeded"], text_of(driven)
    assert math.hypot(here.x - 5.0, here.y - 7.5) < 0.2


async def test_the_robot_footprint_is_judged_not_the_goal_point(nav2: SimulatedRobot) -> None:
    """A goal 1 cm outside keep-out puts the robot's body (robot_radius, 0.2 m by default) 19 cm inside it:
    refused by navigate_to and publish_action. A Spin is judged at the robot's own pose."""
    policy = parse_policy(POLICY, where="fence.toml")
    action = "move_base" if nav2.dialect == "ros1" else "navigate_to_pose"
    edge = 6.59
    if nav2.dialect == "ros1":
        by_action = {
            "action_name": "/move_base",
            "action_type": "move_base_msgs/MoveBaseAction",
            "goal": {"target_pose": stamped(edge, HOME)},
        }
    else:
        by_action = carriers(nav2, action, {"pose": stamped(edge, HOME)})[0][1]
    async with open_session(nav2.url, guard=None, policy=policy) as session, watching(nav2) as watcher:
        for tool, arguments in (
            ("navigate_to", {"goal": {"x": edge, "y": HOME}}),
            ("publish_action", by_action),
        ):
            text = await session.error(tool, arguments)
            assert "keep-out zone 'east'" in text, text
            assert "0.2 m" in text, text
            assert "nothing was sent" in text
        assert not watcher.seen
    # The robot stands 0.1 m from a zone: a Spin there sweeps its body into it.
    near = {"navigation": {"keep_out": {"near": [[5.65, 4.5], [6.0, 4.5], [6.0, 6.5], [5.65, 6.5]]}}}
    async with (
        open_session(nav2.url, guard=None, policy=parse_policy(near, where="near.toml")) as session,
        watching(nav2) as watcher,
    ):
        for tool, arguments in carriers(nav2, "spin", {"target_yaw": 3.14, "time_allowance": {"sec": 10}}):
            text = await session.error(tool, arguments)
            assert "keep-out zone 'near'" in text, text
        assert not watcher.seen


async def test_navigation_confirm_motion_asks_for_every_goal_by_any_carrier(nav2: SimulatedRobot) -> None:
    """[navigation] confirm = "motion" alone: a goal pose topic, an actionlib goal topic, a send_goal call and
    every behaviour action are asked about; the person declines and nothing reaches the robot."""
    from test_mcp_safety import Person

    policy = parse_policy({"navigation": {"confirm": "motion"}}, where="confirm.toml")
    pose_type = "geometry_msgs/PoseStamped" if nav2.dialect == "ros1" else "geometry_msgs/msg/PoseStamped"
    calls: list[tuple[str, dict[str, Any]]] = [
        ("publish_topic", {"topic": "/goal_pose", "message_type": pose_type, "message": stamped(4.0, 7.0)}),
        (
            "publish_topic",
            {"topic": "/move_base_simple/goal", "message_type": pose_type, "message": stamped(4.0, 7.0)},
        ),
    ]
    if nav2.dialect == "ros1":
        calls.append(
            (
                "publish_topic",
                {
                    "topic": "/move_base/goal",
                    "message_type": "move_base_msgs/MoveBaseActionGoal",
                    "message": {"goal": {"target_pose": stamped(4.0, 7.0)}},
                },
            )
        )
    for action, goal in (
        ("navigate_to_pose", {"pose": stamped(4.0, 7.0)}),
        ("drive_on_heading", drive(0.5)),
        ("spin", {"target_yaw": 1.0, "time_allowance": {"sec": 10}}),
        ("assisted_teleop", {"time_allowance": {"sec": 10}}),
        ("undock_robot", {"dock_type": "charger"}),
    ):
        calls += carriers(nav2, action, goal)
    person = Person("decline")
    async with (
        open_session(nav2.url, guard=None, policy=policy, elicitation_callback=person) as session,
        watching(nav2) as watcher,
    ):
        unasked = []
        for tool, arguments in calls:
            text = await session.error(tool, arguments)
            if "declined" not in text:
                target = arguments.get("topic") or arguments.get("service") or arguments.get("action_name")
                unasked.append(f"{tool} {target}: {text[:200]}")
        assert not unasked, "\n".join(unasked)
        assert len(person.questions) == len(calls)
        assert not watcher.seen
    # The person is told where the goal is, whatever carried it.
    assert "Goal in map: x=4.00 y=7.00 m" in person.questions[0]
    assert any("Drives the robot 0.50 m forward along its heading." in q for q in person.questions)
    assert nav2.nav2.robots[0].x == pytest.approx(HOME)


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_every_spelling_of_a_navigation_type_gets_the_map_check(
    make_sim: MakeSim, dialect: str
) -> None:
    """No policy at all: a goal into the room's pillar is refused however its type is spelt, and by the
    actionlib goal topic, as the usual spelling is."""
    robot = await make_sim(dialect=dialect, world="nav2")
    pillar = stamped(8.5, 8.5)
    if dialect == "ros1":
        calls = [
            (
                "publish_action",
                {"action_name": "/move_base", "action_type": spelling, "goal": {"target_pose": pillar}},
            )
            for spelling in (
                "move_base_msgs/MoveBaseAction",
                "move_base_msgs/MoveBase",
                "move_base_msgs/MoveBaseActionGoal",
                "move_base_msgs/action/MoveBase",
            )
        ] + [
            (
                "publish_topic",
                {
                    "topic": "/move_base/goal",
                    "message_type": "move_base_msgs/MoveBaseActionGoal",
                    "message": {"goal": {"target_pose": pillar}},
                },
            ),
        ]
    else:
        calls = [
            (
                "publish_action",
                {"action_name": "/navigate_to_pose", "action_type": spelling, "goal": {"pose": pillar}},
            )
            for spelling in (
                "nav2_msgs/action/NavigateToPose",
                "nav2_msgs/NavigateToPose",
                "nav2_msgs/NavigateToPoseAction",
                "nav2_msgs/NavigateToPoseActionGoal",
            )
        ] + carriers(robot, "navigate_to_pose", {"pose": pillar})[1:]
    async with open_session(robot.url, guard=None) as session, watching(robot) as watcher:
        for tool, arguments in calls:
            text = await session.error(tool, arguments)
            assert "obstacle" in text, (arguments, text)
            assert "nothing was sent" in text
        assert not watcher.seen


@pytest.mark.parametrize("mode", ["refuse", "clamp"])
async def test_a_drive_on_heading_speed_meets_the_velocity_cap(nav2: SimulatedRobot, mode: str) -> None:
    """[velocity] max_linear 0.5: DriveOnHeading at 5 m/s is refused (mode refuse) or sent at 0.5 m/s
    (mode clamp), whichever carrier takes it; the raw socket sees the clamped speed."""
    policy = parse_policy({"velocity": {"max_linear": 0.5, "mode": mode}}, where="caps.toml")
    calls = carriers(nav2, "drive_on_heading", drive(1.0, 5.0))
    if mode == "clamp" and nav2.dialect == "ros2":
        calls = calls[:1]  # the simulated bridge cannot call a hidden _action/send_goal service
    async with open_session(nav2.url, guard=None, policy=policy) as session, watching(nav2) as watcher:
        for tool, arguments in calls:
            result = await session.call(tool, arguments)
            text = text_of(result)
            if mode == "refuse":
                assert result.is_error, text
                assert "max_linear 0.5 m/s" in text, text
                assert "nothing was sent" in text
            else:
                assert not result.is_error, text
                if tool == "publish_topic":
                    assert "lowered the goal's speed to the [velocity] max_linear cap" in text, text
        if mode == "refuse":
            assert not watcher.seen
            return
        if nav2.dialect == "ros1":
            message = await watcher.wait_for("/drive_on_heading/goal")
            speeds = [m["goal"]["speed"] for topic, m in watcher.seen if topic == "/drive_on_heading/goal"]
            assert speeds, message
            assert all(s == pytest.approx(0.5) for s in speeds), message
        else:
            speeds = [goal["speed"] for goal in received(nav2)]
            assert speeds == [pytest.approx(0.5)] * len(calls)
