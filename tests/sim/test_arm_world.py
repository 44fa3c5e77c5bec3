"""The arm world (ROS 2; ROS 1 in ``test_arm_world_ros1.py``): its description, joint states, trajectory and
gripper actions, controller manager and faults, as a ros2_control arm answers them (the ROS 2 lab's
NOTES.md, "The arm"), seen on a raw socket."""

from __future__ import annotations

from typing import Any

import pytest
from rawclient import RawClient

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.nodes.arm import ARM_JOINTS, FINGER, HOME

WAIT = 30.0
FOLLOW = "/arm_controller/follow_joint_trajectory"
FOLLOW_TYPE = "control_msgs/action/FollowJointTrajectory"


async def message(client: RawClient, topic: str, wait: float = WAIT) -> dict[str, Any]:
    frame = await client.recv_until(lambda f: f.get("op") == "publish" and f.get("topic") == topic, wait)
    return dict(frame["msg"])


def goal(positions: list[float], seconds: float = 0.4, names: list[str] | None = None) -> dict[str, Any]:
    sec = int(seconds)
    return {
        "trajectory": {
            "joint_names": names or list(ARM_JOINTS),
            "points": [
                {
                    "positions": positions,
                    "time_from_start": {"sec": sec, "nanosec": int((seconds - sec) * 1e9)},
                }
            ],
        }
    }


async def send_goal(client: RawClient, goal_id: str, args: dict[str, Any], action: str = FOLLOW) -> None:
    kind = FOLLOW_TYPE if action == FOLLOW else "control_msgs/action/GripperCommand"
    await client.send(
        {"op": "send_action_goal", "id": goal_id, "action": action, "action_type": kind, "args": args}
    )


async def result(client: RawClient, goal_id: str, wait: float = WAIT) -> dict[str, Any]:
    return await client.recv_until(lambda f: f.get("op") == "action_result" and f.get("id") == goal_id, wait)


async def test_the_description_joint_states_and_tf_agree_with_the_lab_arm() -> None:
    """The URDF holds the arm, /joint_states the 6 joints and the finger at home, /tf every moving link."""
    async with SimulatedRobot(world="arm") as robot, await RawClient.open(robot.url) as client:
        for topic in ("/robot_description", "/joint_states", "/robot_description_semantic", "/tf_static"):
            await client.send({"op": "subscribe", "topic": topic})
        urdf = (await message(client, "/robot_description"))["data"]
        assert all(f'<joint name="{name}" type="revolute">' in urdf for name in ARM_JOINTS)
        assert '<mimic joint="gripper_finger_joint"' in urdf
        states = await message(client, "/joint_states")
        assert states["name"] == [*ARM_JOINTS, FINGER]
        assert states["position"] == pytest.approx([HOME[name] for name in states["name"]])
        assert (
            '<group_state name="home" group="arm">'
            in (await message(client, "/robot_description_semantic"))["data"]
        )
        statics = {t["child_frame_id"] for t in (await message(client, "/tf_static"))["transforms"]}
        assert {"arm_base_link", "tool0", "gripper_base_link"} <= statics
        await client.send({"op": "subscribe", "topic": "/tf"})
        frame = await client.recv_until(
            lambda f: f.get("topic") == "/tf" and len(f["msg"]["transforms"]) > 1, WAIT
        )  # the arm's links (the turtle's odom → base_link comes on its own)
        moving = {t["child_frame_id"] for t in frame["msg"]["transforms"]}
        assert {
            "shoulder_link",
            "wrist_3_link",
            "gripper_left_finger_link",
            "gripper_right_finger_link",
        } <= moving


async def test_a_goal_is_followed_to_its_point_and_succeeds() -> None:
    """A 0.4 s goal moves the arm there: SUCCEEDED, error_code 0, "goal reached"."""
    target = [0.5, -0.5, 1.4, 0.0, 0.9, 0.0]
    async with SimulatedRobot(world="arm") as robot, await RawClient.open(robot.url) as client:
        await send_goal(client, "g1", goal(target))
        done = await result(client, "g1")
        assert (done["status"], done["values"]["error_code"], done["values"]["error_string"]) == (
            4,
            0,
            "goal reached",
        )
        assert [robot.arm.positions[name] for name in ARM_JOINTS] == pytest.approx(target)


async def test_a_cancel_stops_the_arm_where_it_is() -> None:
    """Cancelled midway: CANCELED, and the arm stays between start and target."""
    async with SimulatedRobot(world="arm") as robot, await RawClient.open(robot.url) as client:
        await send_goal(client, "g1", goal([2.0, -0.3, 1.2, 0.0, 0.8, 0.0], seconds=3.0))
        await robot.wait_for(lambda _: robot.arm.positions["shoulder_pan_joint"] > 0.2, timeout=WAIT)
        await client.send({"op": "cancel_action_goal", "action": FOLLOW, "id": "g1"})
        done = await result(client, "g1")
        assert done["status"] == 5
        stopped = robot.arm.positions["shoulder_pan_joint"]
        assert 0.2 < stopped < 2.0
        await client.send({"op": "call_service", "id": "b", "service": "/rosapi/get_time"})
        await client.reply("b")
        assert robot.arm.positions["shoulder_pan_joint"] == stopped
        assert robot.arm.run is None


@pytest.mark.parametrize(
    ("args", "code", "words"),
    [
        (goal([4.0, 0, 0, 0, 0, 0]), -1, "outside its limits"),
        (goal([0.0] * 6, names=[*ARM_JOINTS[:5], "nope_joint"]), -2, "not the controller's"),
        (goal([0.0] * 5, names=list(ARM_JOINTS[:5])), -2, "missing"),
        ({"trajectory": {"joint_names": list(ARM_JOINTS), "points": []}}, -1, "no points"),
    ],
)
async def test_a_bad_goal_is_accepted_and_aborted_with_ros2_controls_code(
    args: dict[str, Any], code: int, words: str
) -> None:
    """Out of limits −1, unknown or missing joints −2, no points −1; the arm does not move."""
    async with SimulatedRobot(world="arm") as robot, await RawClient.open(robot.url) as client:
        await send_goal(client, "bad", args)
        done = await result(client, "bad")
        assert (done["status"], done["values"]["error_code"]) == (6, code)
        assert words in done["values"]["error_string"]
        assert robot.arm.positions == pytest.approx(HOME)


async def test_with_reject_invalid_goals_an_out_of_limit_goal_is_rejected() -> None:
    """As ros2_controllers' JointTrajectoryController: the goal is rejected (not accepted); nothing runs."""
    async with SimulatedRobot(world="arm") as robot, await RawClient.open(robot.url) as client:
        robot.world.params["/arm_controller:reject_invalid_goals"] = True
        await send_goal(client, "bad", goal([4.0, 0, 0, 0, 0, 0]))
        done = await result(client, "bad")
        assert (done["result"], done["values"]) == (False, "Action goal was rejected")
        assert robot.arm.run is None
        assert robot.arm.positions == pytest.approx(HOME)


async def test_a_newer_goal_preempts_the_running_one() -> None:
    """The first goal ends ABORTED −1 "preempted…", the second runs to its point."""
    async with SimulatedRobot(world="arm") as robot, await RawClient.open(robot.url) as client:
        await send_goal(client, "g1", goal([1.0, -0.3, 1.2, 0.0, 0.8, 0.0], seconds=3.0))
        await robot.wait_for(lambda _: robot.arm.run is not None, timeout=WAIT)
        await send_goal(client, "g2", goal([-0.2, -0.3, 1.2, 0.0, 0.8, 0.0], seconds=0.3))
        first = await result(client, "g1")
        assert (first["status"], first["values"]["error_code"]) == (6, -1)
        assert "preempted" in first["values"]["error_string"]
        assert (await result(client, "g2"))["status"] == 4


async def test_the_trajectory_topic_moves_the_arm_too() -> None:
    """A JointTrajectory on /arm_controller/joint_trajectory runs like a goal."""
    async with SimulatedRobot(world="arm") as robot, await RawClient.open(robot.url) as client:
        await client.send(
            {
                "op": "publish",
                "topic": "/arm_controller/joint_trajectory",
                "msg": goal([0.3, -0.3, 1.2, 0.0, 0.8, 0.0], seconds=0.2)["trajectory"],
            }
        )
        await robot.wait_for(
            lambda _: robot.arm.positions["shoulder_pan_joint"] == pytest.approx(0.3), timeout=WAIT
        )


async def test_an_empty_trajectory_on_the_topic_is_ignored_as_ros2_control_ignores_it() -> None:
    """ros2_controllers refuse an empty trajectory ("Empty trajectory received.") and keep going; a hold (one
    point where the arm is, at 0 s, stamp 0) stops it where it is."""
    async with SimulatedRobot(world="arm") as robot, await RawClient.open(robot.url) as client:
        topic = "/arm_controller/joint_trajectory"
        await client.send(
            {"op": "publish", "topic": topic, "msg": goal([1.0, -0.3, 1.2, 0.0, 0.8, 0.0], 2)["trajectory"]}
        )
        await robot.wait_for(lambda _: robot.arm.positions["shoulder_pan_joint"] > 0.05, timeout=WAIT)
        await client.send(
            {"op": "publish", "topic": topic, "msg": {"joint_names": list(ARM_JOINTS), "points": []}}
        )
        await robot.wait_for(lambda _: len(robot.arm.received_trajectories) == 2, timeout=WAIT)
        assert robot.arm.run is not None  # still going
        here = [robot.arm.positions[name] for name in ARM_JOINTS]
        hold = {
            "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
            "joint_names": list(ARM_JOINTS),
            "points": [{"positions": here, "time_from_start": {"sec": 0, "nanosec": 0}}],
        }
        await client.send({"op": "publish", "topic": topic, "msg": hold})
        await robot.wait_for(lambda _: robot.arm.run is None, timeout=WAIT)
    assert robot.arm.positions["shoulder_pan_joint"] == pytest.approx(here[0])


async def test_the_gripper_closes_and_a_goal_beyond_its_travel_stalls() -> None:
    """Close to 0.01 m: SUCCEEDED, reached_goal; 0.1 m (beyond 0.04): stops at the limit, ABORTED, stalled."""
    async with SimulatedRobot(world="arm") as robot, await RawClient.open(robot.url) as client:
        gripper = "/gripper_controller/gripper_cmd"
        await send_goal(client, "close", {"command": {"position": 0.03, "max_effort": 20.0}}, gripper)
        closed = await result(client, "close")
        assert (closed["status"], closed["values"]["reached_goal"]) == (4, True)
        assert robot.arm.positions[FINGER] == pytest.approx(0.03)
        await send_goal(client, "wide", {"command": {"position": 0.1, "max_effort": 20.0}}, gripper)
        wide = await result(client, "wide")
        assert (wide["status"], wide["values"]["stalled"]) == (6, True)
        assert robot.arm.positions[FINGER] == pytest.approx(0.04)


async def call(client: RawClient, service: str, args: dict[str, Any]) -> dict[str, Any]:
    await client.send({"op": "call_service", "id": service, "service": service, "args": args})
    return dict((await client.reply(service))["values"])


async def test_switch_controller_deactivates_and_an_inactive_controller_refuses_goals() -> None:
    """Deactivated (strict): list_controllers says inactive with nothing claimed; a goal then aborts −1."""
    async with SimulatedRobot(world="arm") as robot, await RawClient.open(robot.url) as client:
        listed = await call(client, "/controller_manager/list_controllers", {})
        arm = next(c for c in listed["controller"] if c["name"] == "arm_controller")
        assert arm["state"] == "active"
        assert arm["claimed_interfaces"] == [f"{j}/position" for j in ARM_JOINTS]
        switch = "/controller_manager/switch_controller"
        assert (await call(client, switch, {"deactivate_controllers": ["arm_controller"], "strictness": 2}))[
            "ok"
        ]
        assert not (
            await call(client, switch, {"deactivate_controllers": ["arm_controller"], "strictness": 2})
        )["ok"]
        listed = await call(client, "/controller_manager/list_controllers", {})
        arm = next(c for c in listed["controller"] if c["name"] == "arm_controller")
        assert (arm["state"], arm["claimed_interfaces"]) == ("inactive", [])
        await send_goal(client, "g", goal([0.1, -0.3, 1.2, 0.0, 0.8, 0.0]))
        done = await result(client, "g")
        assert (done["status"], done["values"]["error_code"]) == (6, -1)
        assert robot.arm.positions == pytest.approx(HOME)


async def test_hardware_interfaces_are_claimed_while_their_controller_is_active() -> None:
    """list_hardware_interfaces (served by the lab's controller manager too): the arm's position commands are
    claimed, and free once arm_controller is deactivated; every joint's position is a state interface."""
    async with SimulatedRobot(world="arm") as robot, await RawClient.open(robot.url) as client:
        listing = "/controller_manager/list_hardware_interfaces"

        def claimed(listed: dict[str, Any]) -> set[str]:
            return {i["name"] for i in listed["command_interfaces"] if i["is_claimed"]}

        positions = {f"{j}/position" for j in ARM_JOINTS}
        listed = await call(client, listing, {})
        assert positions | {f"{FINGER}/position"} <= claimed(listed)
        assert positions <= {i["name"] for i in listed["state_interfaces"]}
        switch = {"deactivate_controllers": ["arm_controller"], "strictness": 2}
        assert (await call(client, "/controller_manager/switch_controller", switch))["ok"]
        assert claimed(await call(client, listing, {})) == {f"{FINGER}/position"}
        assert robot.arm.positions == pytest.approx(HOME)


async def test_the_arm_controller_fault_keeps_it_inactive() -> None:
    """arm-controller-inactive: inactive at start, and switch_controller cannot activate it."""
    async with (
        SimulatedRobot(world="arm", faults=["arm-controller-inactive"]) as robot,
        await RawClient.open(robot.url) as client,
    ):
        switch = "/controller_manager/switch_controller"
        assert not (
            await call(client, switch, {"activate_controllers": ["arm_controller"], "strictness": 2})
        )["ok"]
        assert not robot.arm.controllers.is_active("arm_controller")


async def test_joint_states_stale_stops_joint_states() -> None:
    """joint-states-stale: the broadcaster is in the graph, yet no /joint_states comes while the turtle's /tf
    ticks on (the barrier: several /tf messages, each a pass of the world's loops)."""
    async with (
        SimulatedRobot(world="arm", faults=["joint-states-stale"]) as robot,
        await RawClient.open(robot.url) as client,
    ):
        await client.send({"op": "subscribe", "topic": "/joint_states"})
        await client.send({"op": "subscribe", "topic": "/tf"})
        for _ in range(5):
            await message(client, "/tf")
        assert not [f for f in client.backlog if f.get("topic") == "/joint_states"]
        assert robot.arm.joint_state_count == 0
        assert "/joint_state_broadcaster" in robot.graph.publishers_of("/joint_states")
