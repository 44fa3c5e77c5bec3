"""Moving the simulated arm (ROS 2) through an MCP session: joint goals and named poses reached; out-of-limit,
over-speed, out-of-workspace and keep-out goals refused by every carrier with nothing sent (a raw socket
watches the controller's goal status and trajectory topic, and the arm counts what reached it); cancel,
stop_robot and the E-STOP stop the arm where it is; the gripper opens and closes."""

from __future__ import annotations

import asyncio
import base64
import contextlib
import json
import math
from collections.abc import AsyncIterator, Awaitable, Callable
from io import BytesIO
from typing import Any

import pytest
import websockets
from mcp.client.session import ClientRequestContext
from mcp.types import ElicitRequestParams, ElicitResult, ImageContent
from mcp_harness import open_session, text_of
from PIL import Image

from arm_fixture import ROBOT as FIXTURE_ROBOT
from rosbridge_mcp_server.robot.arm.kinematics import Chain, translation
from rosbridge_mcp_server.safety import emergency_stop, parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.nodes.arm import ARM_JOINTS, FINGER, HOME, NAMED_POSES

MakeSim = Callable[..., Awaitable[SimulatedRobot]]
FOLLOW = "/arm_controller/follow_joint_trajectory"
TOPIC = "/arm_controller/joint_trajectory"
#: ros_control's (ROS 1) trajectory topic.
TOPIC1 = "/arm_controller/command"
#: The tool starts at (0.28, 0.02, 0.86) in base_link. A table it must stay above, and a person to its left.
BOXES = {
    "arm": {
        "workspace": {"table": [[-1.0, -1.0, 0.45], [1.0, 1.0, 1.3]]},
        "keep_out": {"person": [[-1.0, 0.2, 0.0], [1.0, 1.0, 2.0]]},
    }
}


def trajectory(target: dict[str, float], seconds: float) -> dict[str, Any]:
    """HOME with *target* (radians) set, reached at *seconds*."""
    sec = int(seconds)
    return {
        "joint_names": list(ARM_JOINTS),
        "points": [
            {
                "positions": [target.get(name, HOME[name]) for name in ARM_JOINTS],
                "time_from_start": {"sec": sec, "nanosec": round((seconds - sec) * 1e9)},
            }
        ],
    }


def is_ros1(robot: SimulatedRobot) -> bool:
    return not robot.arm.kit.ros2


def respelt(traj: dict[str, Any]) -> dict[str, Any]:
    """*traj* with ROS 1's ``{secs, nsecs}`` times."""
    points = [
        {
            **point,
            "time_from_start": {
                "secs": point["time_from_start"]["sec"],
                "nsecs": point["time_from_start"]["nanosec"],
            },
        }
        for point in traj["points"]
    ]
    return {**traj, "points": points}


def carriers(traj: dict[str, Any], ros1: bool = False) -> list[tuple[str, dict[str, Any]]]:
    """Every raw tool call that sends *traj* to the arm controller (ROS 1: actionlib's and ros_control's)."""
    if ros1:
        goal1 = {"trajectory": respelt(traj)}
        return [
            (
                "publish_action",
                {
                    "action_name": FOLLOW,
                    "action_type": "control_msgs/FollowJointTrajectoryAction",
                    "goal": goal1,
                },
            ),
            (
                "publish_topic",
                {
                    "topic": f"{FOLLOW}/goal",
                    "message_type": "control_msgs/FollowJointTrajectoryActionGoal",
                    "message": {"goal_id": {"id": "raw-1"}, "goal": goal1},
                },
            ),
            (
                "publish_topic",
                {
                    "topic": TOPIC1,
                    "message_type": "trajectory_msgs/JointTrajectory",
                    "message": respelt(traj),
                },
            ),
        ]
    goal = {"trajectory": traj}
    return [
        (
            "publish_action",
            {"action_name": FOLLOW, "action_type": "control_msgs/action/FollowJointTrajectory", "goal": goal},
        ),
        (
            "publish_service",
            {
                "service": f"{FOLLOW}/_action/send_goal",
                "service_type": "control_msgs/action/FollowJointTrajectory_SendGoal",
                "request": {"goal_id": {"uuid": list(range(16))}, "goal": goal},
            },
        ),
        (
            "publish_topic",
            {"topic": TOPIC, "message_type": "trajectory_msgs/msg/JointTrajectory", "message": traj},
        ),
    ]


class Watcher:
    """A raw rosbridge socket on the controller's goal status and its trajectory topic."""

    def __init__(self, ws: Any) -> None:
        self.ws = ws
        self.seen: list[str] = []

    async def read(self) -> None:
        async for raw in self.ws:
            frame = json.loads(raw)
            if frame.get("op") == "publish" and frame["msg"].get("status_list") != []:
                self.seen.append(frame["topic"])


def status_topic(robot: SimulatedRobot) -> str:
    return f"{FOLLOW}/status" if is_ros1(robot) else f"{FOLLOW}/_action/status"


@contextlib.asynccontextmanager
async def watching(robot: SimulatedRobot) -> AsyncIterator[Watcher]:
    async with websockets.connect(robot.url) as ws:
        watched = (
            (
                (status_topic(robot), "actionlib_msgs/GoalStatusArray"),
                (TOPIC1, "trajectory_msgs/JointTrajectory"),
            )
            if is_ros1(robot)
            else (
                (status_topic(robot), "action_msgs/msg/GoalStatusArray"),
                (TOPIC, "trajectory_msgs/msg/JointTrajectory"),
            )
        )
        for topic, msg_type in watched:
            await ws.send(json.dumps({"op": "subscribe", "topic": topic, "type": msg_type}))
        watcher = Watcher(ws)
        reader = asyncio.create_task(watcher.read())
        try:
            yield watcher
        finally:
            reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reader


@pytest.fixture
async def arm(make_sim: MakeSim) -> SimulatedRobot:
    return await make_sim(dialect="ros2", world="arm")


@pytest.fixture(params=["ros2", "ros1"])
async def any_arm(make_sim: MakeSim, request: pytest.FixtureRequest) -> SimulatedRobot:
    """The simulated arm on each dialect (ROS 1: actionlib and ros_control's names)."""
    return await make_sim(dialect=request.param, world="arm")


def nothing_reached(robot: SimulatedRobot) -> bool:
    return not robot.arm.received_goals and not robot.arm.received_trajectories


async def test_a_joint_goal_is_reached_within_tolerance_at_the_allowed_speed(any_arm: SimulatedRobot) -> None:
    arm = any_arm
    async with open_session(arm.url, guard=None, policy=parse_policy({}, where="t")) as session:
        result = await session.ok("move_arm", {"joints": {"elbow_joint": 45, "wrist_1_joint": -30}})
        data = result.structured_content or {}
        assert data["succeeded"], text_of(result)
        assert data["largest_error"] < 0.5
        assert arm.arm.positions["elbow_joint"] == pytest.approx(math.radians(45), abs=0.01)
        assert arm.arm.positions["wrist_1_joint"] == pytest.approx(math.radians(-30), abs=0.01)
        # Timed by the tool at a quarter of the URDF speeds: 3 rad/s × 0.25 moves elbow 0.41 rad in ≥ 0.55 s.
        sent = arm.arm.received_goals[-1]["trajectory"]["points"][-1]["time_from_start"]
        seconds = sent["secs"] + sent["nsecs"] / 1e9 if is_ros1(arm) else sent["sec"] + sent["nanosec"] / 1e9
        assert seconds >= (1.2 - math.radians(45)) / 0.75
        relative = await session.ok("move_arm", {"joints": {"elbow_joint": 10}, "relative": True})
        assert (relative.structured_content or {})["succeeded"]
        assert arm.arm.positions["elbow_joint"] == pytest.approx(math.radians(55), abs=0.01)


async def test_a_named_pose_is_reached(any_arm: SimulatedRobot) -> None:
    arm = any_arm
    async with open_session(arm.url, guard=None, policy=parse_policy({}, where="t")) as session:
        result = await session.ok("move_arm", {"pose": "ready"})
        assert (result.structured_content or {})["succeeded"], text_of(result)
        unknown = await session.error("move_arm", {"pose": "dance"})
    assert [arm.arm.positions[n] for n in ARM_JOINTS] == pytest.approx(NAMED_POSES["ready"], abs=0.01)
    assert "No named pose 'dance' in the SRDF. Known poses: closed, home, open, ready, zero" in unknown


#: (arguments to move_arm, the raw trajectory, the policy, what the refusal names)
REFUSED: list[tuple[dict[str, Any], dict[str, Any], dict[str, Any], str]] = [
    (
        {"joints": {"elbow_joint": 170}},
        trajectory({"elbow_joint": math.radians(170)}, 60.0),
        {},
        "elbow_joint at 170.0°, outside its URDF limits -160.0° … 160.0°",
    ),
    ({}, trajectory({"elbow_joint": 0.2}, 1.0), {}, "moves elbow_joint at 57.3°/s, faster than 43.0°/s"),
    (
        {"joints": {"shoulder_lift_joint": 100, "elbow_joint": 10}},
        trajectory({"shoulder_lift_joint": math.radians(100), "elbow_joint": math.radians(10)}, 30.0),
        BOXES,
        "outside the workspace (table)",
    ),
    (
        {"joints": {"shoulder_pan_joint": 90}},
        trajectory({"shoulder_pan_joint": math.radians(90)}, 30.0),
        BOXES,
        "into the keep-out box person",
    ),
]


def _ceiling_above_the_raised_forearm() -> dict[str, Any]:
    """A keep-out box 1 cm above the highest centre-line point of raising the elbow to 0.2 rad: the links'
    bodies (the sim's URDF gives them 3–6 cm cylinders) enter it, their centre lines do not."""
    chain = Chain(FIXTURE_ROBOT, FIXTURE_ROBOT.root, "tool0")
    top = 0.0
    for k in range(1001):
        held = {name: value + (0.2 - value) * k / 1000 if name == "elbow_joint" else value
                for name, value in HOME.items()}  # fmt: skip
        top = max([top] + [translation(pose)[2] for _, pose in chain.poses(held)])
    return {"arm": {"keep_out": {"ceiling": [[-2.0, -2.0, top + 0.01], [2.0, 2.0, 3.0]]}}}


REFUSED.append(
    (
        {"joints": {"elbow_joint": math.degrees(0.2)}},
        trajectory({"elbow_joint": 0.2}, 20.0),
        _ceiling_above_the_raised_forearm(),
        "into the keep-out box ceiling",
    )
)


@pytest.mark.parametrize(("by_tool", "raw", "policy", "why"), REFUSED)
async def test_a_goal_beyond_a_limit_is_refused_by_every_carrier_with_nothing_sent(
    any_arm: SimulatedRobot, by_tool: dict[str, Any], raw: dict[str, Any], policy: dict[str, Any], why: str
) -> None:
    arm, ros1 = any_arm, is_ros1(any_arm)
    wrong: list[str] = []
    async with (
        open_session(arm.url, guard=None, policy=parse_policy(policy, where="arm.toml")) as session,
        watching(arm) as watcher,
    ):
        calls = carriers(raw, ros1) + ([("move_arm", by_tool)] if by_tool else [])
        for tool, arguments in calls:
            result = await session.call(tool, arguments)
            text = text_of(result)
            if not result.is_error or why not in text or "nothing was sent" not in text:
                wrong.append(f"{tool}: {text[:300]}")
        assert nothing_reached(arm), (arm.arm.received_goals, arm.arm.received_trajectories)
        # The control: a slow small goal by the same carriers reaches the arm (the watcher sees it).
        control = await session.call(*carriers(trajectory({"wrist_3_joint": 0.05}, 2.0), ros1)[0])
        assert not control.is_error, text_of(control)
        assert arm.arm.received_goals
    assert status_topic(arm) in watcher.seen
    assert TOPIC not in watcher.seen
    assert TOPIC1 not in watcher.seen
    assert not wrong, "\n".join(wrong)


async def moving(robot: SimulatedRobot) -> None:
    await robot.wait_for(
        lambda _: robot.arm.run is not None and robot.arm.velocities["shoulder_pan_joint"], 5.0
    )


async def stopped_within(robot: SimulatedRobot, seconds: float) -> None:
    await robot.wait_for(lambda _: robot.arm.run is None and not any(robot.arm.velocities.values()), seconds)


@pytest.mark.parametrize("how", ["stop_robot", "estop", "mcp_cancel"])
async def test_stop_robot_the_estop_and_a_cancel_stop_the_arm_where_it_is(
    any_arm: SimulatedRobot, how: str
) -> None:
    """A 90° pan at a quarter of 2 rad/s takes 3.1 s; each stop ends it within 0.5 s, short of the goal."""
    arm = any_arm
    async with open_session(arm.url, guard=None, policy=parse_policy({}, where="t")) as session:
        call = asyncio.create_task(session.call("move_arm", {"joints": {"shoulder_pan_joint": 90}}))
        await moving(arm)
        if how == "stop_robot":
            await session.ok("stop_robot")
        elif how == "estop":
            assert session.robot is not None
            await emergency_stop(session.robot, by="console")
        else:
            call.cancel()
        await stopped_within(arm, 0.5)
        with contextlib.suppress(asyncio.CancelledError):
            result = await asyncio.wait_for(call, 15.0)
            if how != "mcp_cancel":
                assert (result.structured_content or {})["canceled_by"] in ("stop_robot", "estop"), text_of(
                    result
                )
    assert 0.0 < arm.arm.positions["shoulder_pan_joint"] < math.radians(85)


async def test_the_gripper_closes_and_opens_and_a_position_beyond_its_travel_is_refused(
    any_arm: SimulatedRobot,
) -> None:
    arm = any_arm
    gripper_type = (
        "control_msgs/GripperCommandAction" if is_ros1(arm) else "control_msgs/action/GripperCommand"
    )
    policy = parse_policy({"arm": {"max_gripper_effort": 20}}, where="t")
    async with open_session(arm.url, guard=None, policy=policy) as session:
        closed = await session.ok("move_gripper", {"command": "close"})
        assert (closed.structured_content or {})["succeeded"], text_of(closed)
        assert arm.arm.positions[FINGER] == pytest.approx(0.0, abs=1e-6)
        opened = await session.ok("move_gripper", {"command": "open", "max_effort": 5})
        assert (opened.structured_content or {})["reached_goal"]
        assert arm.arm.positions[FINGER] == pytest.approx(0.04, abs=1e-6)
        sent = len(arm.arm.gripper_goals)
        far = await session.error("move_gripper", {"position": 0.08})
        strong = await session.error("move_gripper", {"position": 0.02, "max_effort": 30})
        raw = await session.error(
            "publish_action",
            {
                "action_name": "/gripper_controller/gripper_cmd",
                "action_type": gripper_type,
                "goal": {"command": {"position": 0.02, "max_effort": 0}},
            },
        )
        assert len(arm.arm.gripper_goals) == sent
    assert "gripper_finger_joint at 0.080 m, outside its URDF limits 0.000 m … 0.040 m" in far
    assert "max_effort 30, beyond 20" in strong
    assert "0 would mean no limit" in raw


async def test_a_controller_switch_needs_a_person_while_arm_boxes_are_set(arm: SimulatedRobot) -> None:
    request = {"activate_controllers": [], "deactivate_controllers": ["arm_controller"], "strictness": 1}
    arguments = {
        "service": "/controller_manager/switch_controller",
        "service_type": "controller_manager_msgs/srv/SwitchController",
        "request": request,
    }
    async with open_session(arm.url, guard=None, policy=parse_policy(BOXES, where="t")) as session:
        text = await session.error("publish_service", arguments)
    assert "requires a person to confirm" in text
    assert arm.arm.controllers.is_active("arm_controller")


async def test_what_the_judge_reads_cannot_be_written_to_widen_the_limits(arm: SimulatedRobot) -> None:
    """A forged URDF with the elbow free to ±3.14 rad on /robot_description (or its parameter), forged joint
    states: each refused, so the out-of-limit goal after them is still refused and nothing reaches the arm."""
    urdf = '<robot name="forged"><link name="base_link"/></robot>'
    async with (
        open_session(arm.url, guard=None, policy=parse_policy({}, where="t")) as session,
        watching(arm) as watcher,
    ):
        attempts = [
            (
                "publish_topic",
                {
                    "topic": "/robot_description",
                    "message_type": "std_msgs/msg/String",
                    "message": {"data": urdf},
                },
            ),
            (
                "publish_topic",
                {
                    "topic": "/joint_states",
                    "message_type": "sensor_msgs/msg/JointState",
                    "message": {"name": ["elbow_joint"], "position": [2.7]},
                },
            ),
            ("set_parameter", {"name": "/robot_state_publisher:robot_description", "value": urdf}),
            (
                "publish_service",
                {
                    "service": "/robot_state_publisher/set_parameters",
                    "service_type": "rcl_interfaces/srv/SetParameters",
                    "request": {
                        "parameters": [
                            {"name": "robot_description", "value": {"type": 4, "string_value": urdf}}
                        ]
                    },
                },
            ),
        ]
        for tool, arguments in attempts:
            text = await session.error(tool, arguments)
            assert "the URDF's limits always hold" in text, text
            assert "nothing was sent" in text
        still = await session.error("move_arm", {"joints": {"elbow_joint": 170}})
        assert "outside its URDF limits -160.0° … 160.0°" in still
        assert nothing_reached(arm)
    assert TOPIC not in watcher.seen


async def test_view_arm_says_when_moveit_runs_and_what_move_arm_does_with_it(arm: SimulatedRobot) -> None:
    async with open_session(arm.url) as session:
        without = text_of(await session.ok("view_arm"))
        arm.graph.node("/move_group")
        with_moveit = text_of(await session.ok("view_arm"))
    assert "MoveIt" not in without
    assert "MoveIt: /move_group runs. move_arm sends joint goals and named poses" in with_moveit


async def test_arm_confirm_motion_shows_the_joint_goal_and_a_no_sends_nothing(arm: SimulatedRobot) -> None:
    """[arm] confirm = "motion": move_arm and a raw JointTrajectory both ask, the question names the goal's
    joints in degrees and its time; declined, nothing reaches the arm; accepted, it moves."""
    questions: list[str] = []
    answer = {"action": "decline"}

    async def person(context: ClientRequestContext, params: ElicitRequestParams) -> ElicitResult:
        questions.append(params.message)
        if answer["action"] == "accept":
            return ElicitResult(action="accept", content={"approve": True})
        return ElicitResult(action="decline")

    policy = parse_policy({"arm": {"confirm": "motion"}}, where="t")
    async with open_session(arm.url, guard=None, policy=policy, elicitation_callback=person) as session:
        declined = await session.error("move_arm", {"joints": {"elbow_joint": 45}})
        raw = carriers(trajectory({"elbow_joint": 1.0}, 2.0))[2]
        await session.error(*raw)
        assert nothing_reached(arm)
        answer["action"] = "accept"
        moved = await session.ok("move_arm", {"joints": {"elbow_joint": 45}})
    assert "The person declined move_arm" in declined
    assert (
        "Moves the arm to shoulder_pan_joint 0.0°, shoulder_lift_joint -17.2°, elbow_joint 45.0°"
        in questions[0]
    )
    assert "in 0.6 s" in questions[0]
    assert "elbow_joint 57.3°" in questions[1]
    assert (moved.structured_content or {})["succeeded"]


async def test_move_arm_shows_the_arm_at_start_and_goal_from_the_side(arm: SimulatedRobot) -> None:
    """A refusal and a motion both come with the side view: a small PNG with the goal drawn in magenta."""

    def colours(result: Any) -> set[tuple[int, int, int]]:
        images = [block for block in result.content if isinstance(block, ImageContent)]
        assert len(images) == 1, result.content
        data = base64.b64decode(images[0].data)
        assert data.startswith(b"\x89PNG")
        assert len(data) < 30_000
        image = Image.open(BytesIO(data)).convert("RGB")
        return {colour for _, colour in image.getcolors(maxcolors=1 << 16) or []}

    async with open_session(arm.url, guard=None, policy=parse_policy(BOXES, where="t")) as session:
        refused = await session.call("move_arm", {"joints": {"shoulder_lift_joint": 100, "elbow_joint": 10}})
        assert refused.is_error
        assert "outside the workspace (table)" in text_of(refused)
        drawn = colours(refused)
        moved = await session.ok("move_arm", {"joints": {"wrist_1_joint": 20}})
    assert (220, 40, 160) in drawn  # the goal
    assert (30, 150, 60) in drawn  # the workspace box
    assert (220, 40, 160) in colours(moved)


async def test_on_a_robot_without_an_arm_move_arm_says_so_and_raw_trajectories_are_refused(
    make_sim: MakeSim,
) -> None:
    """The turtle world's description has no arm: move_arm says so; a raw trajectory is refused naming the
    joint the description lacks, with or without boxes."""
    turtle = await make_sim(dialect="ros2")
    async with open_session(turtle.url, guard=None, policy=parse_policy(BOXES, where="t")) as session:
        text = await session.error("move_arm", {"joints": {"elbow_joint": 10}})
        raw = await session.error(*carriers(trajectory({"elbow_joint": 1.0}, 5.0))[2])
    assert "has no movable joint: this robot has no arm. Nothing was sent." in text
    assert "'shoulder_pan_joint' is not a movable joint of the robot description" in raw
    assert TOPIC not in turtle.world.published
