"""``navigate_to`` on the Nav2 world in both dialects, through an in-memory MCP session under the server's own
guard: a goal in free space is reached (the pose from ``get_transform``), progress comes, the picture shows
the path; a goal in an obstacle, off the map or outside the geofence is refused before anything is sent (a raw
rosbridge socket sees no goal), and ``publish_action`` on the same action is refused the same way; a cancel of
the MCP call and ``stop_robot`` stop the robot; named places, relative moves and frames."""

from __future__ import annotations

import asyncio
import base64
import contextlib
import io
import json
import math
import re
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import pytest
import websockets
from mcp.types import ImageContent
from mcp_harness import Session, open_session, text_of
from PIL import Image

from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.world import TURTLE_HOME

MakeSim = Callable[..., Awaitable[SimulatedRobot]]

#: The sim drives this many times faster than a real robot, so that a test drive takes a second or two.
TEST_SPEED = 8.0
#: A goal that may go: 0.3 m straight ahead of the robot at home, facing the way it faces (reached in a
#: fraction of a second; a goal behind it costs two turns, seconds at the controller's gentle approach).
CONTROL = (TURTLE_HOME + 0.3, TURTLE_HOME)

POLICY = {
    "navigation": {
        "max_goal_distance": 6.0,
        "keep_out": {"corner": [[8.0, 1.0], [10.5, 1.0], [10.5, 3.0], [8.0, 3.0]]},
    },
    "places": {"door": [2.0, 8.0, 90], "dock": {"x": 3.0, "y": 3.0, "yaw": 180}},
}


@pytest.fixture(params=["ros2", "ros1"])
async def nav2(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    robot = await make_sim(dialect=request.param, world="nav2")
    robot.nav2.navigator.speed = TEST_SPEED
    return robot


@pytest.fixture
async def session(nav2: SimulatedRobot) -> AsyncIterator[Session]:
    async with open_session(nav2.url, guard=None, policy=parse_policy(POLICY, where="test.toml")) as opened:
        yield opened


def goal_topic(robot: SimulatedRobot) -> tuple[str, str]:
    """What a raw client subscribes to see every navigation goal the bridge is given."""
    if robot.dialect == "ros1":
        return "/move_base/goal", "move_base_msgs/MoveBaseActionGoal"
    return "/navigate_to_pose/_action/status", "action_msgs/msg/GoalStatusArray"


async def pose_of(session: Session) -> tuple[float, float, float]:
    """The robot's pose in the map from get_transform: x, y, yaw in degrees."""
    result = await session.ok("get_transform", {"target_frame": "map", "source_frame": "base_link"})
    data = result.structured_content or {}
    return data["translation"]["x"], data["translation"]["y"], data["rotation"]["yaw"]


def picture(result: Any) -> Image.Image:
    images = [block for block in result.content if isinstance(block, ImageContent)]
    assert images, "no picture in the answer"
    return Image.open(io.BytesIO(base64.b64decode(images[0].data)))


def green_pixels(image: Image.Image) -> int:
    """Pixels of the path colour (pictures/drawing.PATH_COLOUR)."""
    from rosbridge_mcp_server.pictures.drawing import PATH_COLOUR

    raw = image.convert("RGB").tobytes()
    return sum(1 for i in range(0, len(raw), 3) if tuple(raw[i : i + 3]) == PATH_COLOUR)


def yaw_error(a: float, b: float) -> float:
    return abs(math.degrees(math.atan2(math.sin(math.radians(a - b)), math.cos(math.radians(a - b)))))


async def test_a_goal_in_free_space_is_reached_with_progress_and_a_picture(
    session: Session, nav2: SimulatedRobot
) -> None:
    result = await session.ok("navigate_to", {"goal": {"x": 2.5, "y": 7.5, "yaw": 90}})
    data = result.structured_content or {}
    assert data["succeeded"], text_of(result)
    x, y, yaw = await pose_of(session)
    assert math.hypot(x - 2.5, y - 7.5) < 0.2
    assert yaw_error(yaw, 90) < 10
    assert session.progress, "no progress reported"
    assert any("m to go" in (message or "") for _, _, message in session.progress)
    assert "drove" in text_of(result)
    assert green_pixels(picture(result)) > 50


async def test_a_goal_in_an_obstacle_is_refused_before_anything_is_sent(
    session: Session, nav2: SimulatedRobot
) -> None:
    before = len(nav2.world.goals)
    # The pillar of the room is at (8.5, 8.5), 0.5 m round.
    text = await session.error("navigate_to", {"goal": {"x": 8.5, "y": 8.5}})
    assert "obstacle" in text
    assert "nothing was sent" in text
    assert len(nav2.world.goals) == before


class GoalWatcher:
    """A raw rosbridge subscriber on its own socket to what a navigation goal makes the bridge publish
    (ROS 1: the goal itself on ``/move_base/goal``; ROS 2: the status list, sent when a goal comes)."""

    def __init__(self, ws: Any, topic: str) -> None:
        self.ws = ws
        self.topic = topic
        self.received: list[dict[str, Any]] = []
        self.changed = asyncio.Event()

    async def read(self) -> None:
        async for raw in self.ws:
            frame = json.loads(raw)
            if frame.get("op") == "publish" and frame.get("topic") == self.topic:
                message = frame["msg"]
                # ROS 2: an empty status list is no goal.
                if message.get("status_list") == []:
                    continue
                self.received.append(message)
                self.changed.set()

    async def wait_for_any(self) -> None:
        async with asyncio.timeout(10.0):
            while not self.received:
                self.changed.clear()
                await self.changed.wait()


@contextlib.asynccontextmanager
async def watching(robot: SimulatedRobot) -> AsyncIterator[GoalWatcher]:
    topic, msg_type = goal_topic(robot)
    async with websockets.connect(robot.url) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": topic, "type": msg_type}))
        watcher = GoalWatcher(ws, topic)
        reader = asyncio.create_task(watcher.read())
        try:
            yield watcher
        finally:
            reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reader


def raw_goal(robot: SimulatedRobot, x: float, y: float) -> dict[str, Any]:
    """publish_action's arguments for a goal to (x, y) spelt by hand, in the robot's dialect."""
    stamped = {
        "header": {"frame_id": "map"},
        "pose": {"position": {"x": x, "y": y}, "orientation": {"w": 1.0}},
    }
    if robot.dialect == "ros1":
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


@pytest.mark.parametrize(
    ("goal", "why"),
    [
        ((8.5, 8.5), "obstacle"),  # the room's pillar
        ((8.5, 7.9), "nearer than the robot's margin"),  # beside it
        ((25.0, 3.0), "off the map"),
        ((9.0, 2.0), "keep-out zone 'corner'"),
        ((1.0, 0.6), "beyond the maximum goal distance 6 m"),
    ],
)
async def test_a_goal_the_map_or_the_policy_rules_out_is_refused_on_both_paths_and_never_sent(
    session: Session, nav2: SimulatedRobot, goal: tuple[float, float], why: str
) -> None:
    async with watching(nav2) as watcher:
        text = await session.error("navigate_to", {"goal": {"x": goal[0], "y": goal[1]}})
        assert why in text
        assert "nothing was sent" in text
        raw = await session.error("publish_action", raw_goal(nav2, *goal))
        assert why in raw
        assert "nothing was sent" in raw
        # A goal that may go is seen by the raw socket: the watcher would have seen the refused ones.
        control = await session.call("publish_action", dict(raw_goal(nav2, *CONTROL), timeout=30))
        await watcher.wait_for_any()
    assert not control.is_error, text_of(control)
    sent = watcher.received
    if nav2.dialect == "ros1":
        assert [m["goal"]["target_pose"]["pose"]["position"]["x"] for m in sent] == [CONTROL[0]]
    else:
        assert len({status["goal_info"]["goal_id"]["uuid"] for m in sent for status in m["status_list"]}) == 1


async def test_a_keep_out_refusal_asks_for_a_goal_outside_the_zone(session: Session) -> None:
    """The policy has only keep-out zones: the refusal says to choose a goal clear of them, not "inside the
    allowed area" (there is none)."""
    text = await session.error("navigate_to", {"goal": {"x": 9.0, "y": 2.0}})
    assert "keep-out zone 'corner'" in text
    assert "allowed area" not in text, text
    assert "Choose a goal clear of the keep-out zones." in text, text


async def test_a_refusal_draws_the_goal_on_the_map(session: Session) -> None:
    result = await session.call("navigate_to", {"goal": [9.0, 2.0]})
    assert result.is_error
    image = picture(result)
    raw = image.convert("RGB").tobytes()
    colours = {tuple(raw[i : i + 3]) for i in range(0, len(raw), 3)}
    assert (220, 40, 160) in colours  # the goal
    assert (210, 30, 30) in colours  # the keep-out zone


async def test_a_named_place_and_a_relative_move_are_reached(session: Session, nav2: SimulatedRobot) -> None:
    reached = await session.ok("navigate_to", {"goal": "dock"})
    assert (reached.structured_content or {})["succeeded"], text_of(reached)
    x, y, yaw = await pose_of(session)
    assert math.hypot(x - 3.0, y - 3.0) < 0.2
    assert yaw_error(yaw, 180) < 10
    # Facing -x at (3, 3): one metre forward and a quarter turn left ends at (2, 3) facing -y.
    moved = await session.ok("navigate_to", {"forward": 1.0, "turn": 90})
    assert (moved.structured_content or {})["succeeded"], text_of(moved)
    x, y, yaw = await pose_of(session)
    assert math.hypot(x - 2.0, y - 3.0) < 0.2
    assert yaw_error(yaw, -90) < 10


async def test_an_unknown_place_names_the_places(session: Session) -> None:
    text = await session.error("navigate_to", {"goal": "kitchen"})
    assert "kitchen" in text
    assert "dock, door" in text


async def test_a_goal_in_the_odom_frame_is_placed_through_tf(session: Session) -> None:
    """odom sits 5.54 m along x and y from map in the Nav2 world: (-2, 1) in odom is (3.54, 6.54) in map."""
    result = await session.ok("navigate_to", {"goal": {"x": -2.0, "y": 1.0, "yaw": 0}, "frame": "odom"})
    data = result.structured_content or {}
    assert data["succeeded"], text_of(result)
    x, y, _ = await pose_of(session)
    assert math.hypot(x - 3.544, y - 6.544) < 0.2


async def test_a_goal_in_an_unknown_frame_is_refused_with_the_reason(session: Session) -> None:
    text = await session.error("navigate_to", {"goal": {"x": 1.0, "y": 1.0}, "frame": "kitchen_table"})
    assert "kitchen_table" in text
    assert "Nothing was sent" in text


async def test_cancelling_the_call_stops_the_robot_and_cancels_the_goal(
    session: Session, nav2: SimulatedRobot
) -> None:
    robot = nav2.nav2.robots[0]
    call = asyncio.create_task(session.call("navigate_to", {"goal": {"x": 1.5, "y": 2.0}}))
    await nav2.wait_for(lambda world: robot.linear > 0.1, timeout=10.0)
    call.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await call
    # Stopped short of the goal: the navigator stops there only when its goal is cancelled; one that went on
    # would drive to the goal and stop only there.
    await nav2.wait_for(lambda world: robot.linear == 0.0 and robot.angular == 0.0, timeout=10.0)
    x, y = robot.x, robot.y
    assert math.hypot(x - 1.5, y - 2.0) > 0.5


async def test_stop_robot_stops_the_robot_and_ends_the_goal(session: Session, nav2: SimulatedRobot) -> None:
    robot = nav2.nav2.robots[0]
    call = asyncio.create_task(session.call("navigate_to", {"goal": {"x": 1.5, "y": 9.0}}))
    await nav2.wait_for(lambda world: robot.linear > 0.1, timeout=10.0)
    stopped = await session.ok("stop_robot")
    # Not succeeded (below): a robot the stop did not stop would drive on and stop only at the goal.
    await nav2.wait_for(lambda world: robot.linear == 0.0 and robot.angular == 0.0, timeout=10.0)
    result = await asyncio.wait_for(call, 10.0)
    data = result.structured_content or {}
    assert not data["succeeded"]
    assert data["canceled_by"] == "stop_robot"
    assert "(cancelled by stop_robot)" in text_of(result)
    assert (stopped.structured_content or {})["goals_cancelled"]


async def test_no_navigator_is_said_and_nothing_is_sent(make_sim: MakeSim) -> None:
    """The turtle world has a map and /tf but no navigate_to_pose action server."""
    robot = await make_sim(dialect="ros2")
    async with open_session(robot.url, guard=None) as opened:
        text = await opened.error("navigate_to", {"goal": {"x": 1.0, "y": 1.0}})
    assert "Nav2 is not ready: no action server /navigate_to_pose" in text
    assert "Nothing was sent" in text


async def test_on_the_turtle_demo_the_missing_navigator_points_at_the_nav2_demo(make_sim: MakeSim) -> None:
    """The plain demo (turtlesim) has no Nav2: the answer says which demo has it."""
    robot = await make_sim(dialect="ros2")
    async with open_session(robot.url, guard=None) as opened:
        text = await opened.error("navigate_to", {"goal": {"x": 1.0, "y": 1.0}})
    assert "turtlesim has no Nav2; the built-in demo has one: --demo --demo-world nav2" in text, text
    assert text.endswith("Nothing was sent."), text


async def test_reasons_that_end_in_a_stop_are_joined_without_a_double_one(make_sim: MakeSim) -> None:
    """A robot without /tf: "... nothing publishes transforms. Nothing was sent.", not "transforms.. ..."."""
    robot = await make_sim(dialect="ros2")
    for name in list(robot.graph.nodes):
        for topic in ("/tf", "/tf_static"):
            if topic in robot.graph.nodes[name].publishes:
                robot.graph.remove_publisher(name, topic)
    async with open_session(robot.url, guard=None) as opened:
        text = await opened.error("navigate_to", {"goal": {"x": 1.0, "y": 1.0}})
    assert "nothing publishes transforms" in text, text
    assert re.search(r"[^.]\.\.(?!\.)", text) is None, text
    assert text.endswith(". Nothing was sent."), text


@pytest.mark.parametrize(
    ("goal", "said"),
    [
        ({"x": 1, "y": 2, "theta": 90}, 'unknown theta. Did you mean "yaw" (degrees) for "theta"?'),
        ({"x": 1, "y": 2, "yaww": 90}, 'Did you mean "yaw" (degrees) for "yaww"?'),
        ({"x": 1}, "no y."),
        ([{"x": 1, "y": 2}, {"x": 1, "heading": 3}], 'goal[1] must be {"x": m, "y": m, "yaw": degrees}'),
        ({"x": "one", "y": 2}, 'goal.x must be a finite number, not "one"'),
    ],
)
async def test_a_goal_written_wrong_names_the_key_meant_and_sends_nothing(
    session: Session, nav2: SimulatedRobot, goal: Any, said: str
) -> None:
    """A turtlesim-style theta, a misspelt yaw, a missing y, a bad waypoint, a word for a number: each
    answer says what is wrong in JSON as it was written, what was meant, and that nothing was sent."""
    text = await session.error("navigate_to", {"goal": goal})
    assert said in text, text
    assert text.endswith("Nothing was sent."), text
    assert "waypoints[" not in text
    assert "'x'" not in text, text  # JSON as written, not a Python dict
    assert nav2.world.goals == {}


async def test_an_inactive_navigator_is_said_and_nothing_is_sent(make_sim: MakeSim) -> None:
    robot = await make_sim(dialect="ros2", world="nav2")
    robot.nav2.robots[0].states["bt_navigator"] = 2  # inactive
    async with open_session(robot.url, guard=None) as opened, watching(robot) as watcher:
        text = await opened.error("navigate_to", {"goal": {"x": 4.0, "y": 4.0}})
    assert "Nav2 is not ready" in text
    assert "bt_navigator is inactive, not active" in text
    assert not watcher.received
    assert not robot.world.goals


async def test_waypoints_are_driven_in_a_row_on_ros2_and_refused_on_ros1(
    session: Session, nav2: SimulatedRobot
) -> None:
    goal = [{"x": 4.0, "y": 7.0}, [2.5, 7.0, 180]]
    if nav2.dialect == "ros1":
        text = await session.error("navigate_to", {"goal": goal})
        assert "NavigateThroughPoses" in text
        return
    result = await session.ok("navigate_to", {"goal": goal})
    assert (result.structured_content or {})["succeeded"], text_of(result)
    x, y, yaw = await pose_of(session)
    assert math.hypot(x - 2.5, y - 7.0) < 0.2
    assert yaw_error(yaw, 180) < 10
    assert "(4.00, 7.00" in text_of(result)


async def test_a_timeout_cancels_the_goal_and_stops_the_robot(session: Session, nav2: SimulatedRobot) -> None:
    nav2.nav2.navigator.speed = 1.0  # a real robot's pace: it cannot arrive within the timeout
    result = await session.ok("navigate_to", {"goal": {"x": 2.0, "y": 5.5}, "timeout": 1.0})
    data = result.structured_content or {}
    assert not data["succeeded"]
    assert data["canceled_by"] == "timeout"
    robot = nav2.nav2.robots[0]
    await nav2.wait_for(lambda world: robot.linear == 0.0 and robot.angular == 0.0, timeout=0.5)


@pytest.mark.parametrize("mode", ["legacy", "auto"])
async def test_navigation_confirm_asks_with_the_goal_and_a_decline_sends_nothing(
    make_sim: MakeSim, mode: str
) -> None:
    """[navigation] confirm = "motion": the person is asked with the goal on the map, in the handshake
    protocol (elicitation mid-call) and in 2026-07-28's input rounds (the question must read the same twice);
    a decline sends nothing, an accept drives."""
    from test_mcp_safety import Person

    robot = await make_sim(dialect="ros2", world="nav2")
    robot.nav2.navigator.speed = TEST_SPEED
    rules = parse_policy({"navigation": {"confirm": "motion"}, "places": POLICY["places"]}, where="t.toml")
    declining, accepting = Person("decline"), Person()
    async with open_session(
        robot.url, mode=mode, guard=None, policy=rules, elicitation_callback=declining
    ) as opened:
        refused = await opened.error("navigate_to", {"goal": "dock"})
    assert "declined" in refused
    assert not robot.world.goals
    [question] = declining.questions
    assert "Goal in map: x=3.00 y=3.00 m yaw=180°" in question
    async with open_session(
        robot.url, mode=mode, guard=None, policy=rules, elicitation_callback=accepting
    ) as opened:
        reached = await opened.ok("navigate_to", {"goal": "dock"})
    assert (reached.structured_content or {})["succeeded"], text_of(reached)
    assert len(accepting.questions) == 1


async def test_a_navigation_goal_sent_as_a_topic_or_a_service_call_meets_the_geofence_too(
    session: Session, nav2: SimulatedRobot
) -> None:
    """With [navigation] limits, a goal by another carrier (actionlib's goal topic, ROS 2's send_goal service,
    a goal pose topic) is read out of its carrier, placed on the map and judged as publish_action's is."""
    stamped = {
        "header": {"frame_id": "map"},
        "pose": {"position": {"x": 9.0, "y": 2.0}, "orientation": {"w": 1.0}},
    }
    if nav2.dialect == "ros1":
        carried = [
            (
                "publish_topic",
                {
                    "topic": "/move_base/goal",
                    "message_type": "move_base_msgs/MoveBaseActionGoal",
                    "message": {"goal": {"target_pose": stamped}},
                },
            ),
            (
                "publish_topic",
                {
                    "topic": "/move_base_simple/goal",
                    "message_type": "geometry_msgs/PoseStamped",
                    "message": stamped,
                },
            ),
        ]
    else:
        carried = [
            (
                "publish_service",
                {
                    "service": "/navigate_to_pose/_action/send_goal",
                    "service_type": "nav2_msgs/action/NavigateToPose_SendGoal",
                    "request": {"goal_id": {"uuid": list(range(16))}, "goal": {"pose": stamped}},
                },
            ),
            (
                "publish_topic",
                {"topic": "/goal_pose", "message_type": "geometry_msgs/msg/PoseStamped", "message": stamped},
            ),
        ]
    before = len(nav2.world.goals)
    async with watching(nav2) as watcher:
        for tool, arguments in carried:
            text = await session.error(tool, arguments)
            assert "keep-out zone 'corner'" in text, text
            assert "nothing was sent" in text
        # The same goal by publish_action is judged the same way.
        assert "keep-out zone 'corner'" in await session.error("publish_action", raw_goal(nav2, 9.0, 2.0))
    assert watcher.received == []
    assert len(nav2.world.goals) == before
    published = {topic for topic in nav2.world.published if "goal" in topic}
    assert published == set(), published
