"""The arm world on ROS 1: the same arm as ros_control lays it out, seen on a raw socket: actionlib's
FollowJointTrajectory and GripperCommand over their five topics, ``/arm_controller/command`` (an empty
trajectory holds the arm), the URDF and SRDF as parameters, ``controller_manager`` in ROS 1 form."""

from __future__ import annotations

import json
from typing import Any

import pytest
from rawclient import RawClient

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.nodes.arm import ARM_JOINTS, FINGER, HOME

WAIT = 30.0
FOLLOW = "/arm_controller/follow_joint_trajectory"


def trajectory(pan: float, seconds: int) -> dict[str, Any]:
    positions = [pan if name == "shoulder_pan_joint" else HOME[name] for name in ARM_JOINTS]
    return {
        "joint_names": list(ARM_JOINTS),
        "points": [{"positions": positions, "time_from_start": {"secs": seconds, "nsecs": 0}}],
    }


async def result(client: RawClient, action: str, goal_id: str) -> dict[str, Any]:
    frame = await client.recv_until(
        lambda f: f.get("topic") == f"{action}/result" and f["msg"]["status"]["goal_id"]["id"] == goal_id,
        WAIT,
    )
    return dict(frame["msg"])


async def goal(client: RawClient, action: str, kind: str, goal_id: str, body: dict[str, Any]) -> None:
    await client.send(
        {"op": "subscribe", "topic": f"{action}/result", "type": f"control_msgs/{kind}ActionResult"}
    )
    await client.send(
        {"op": "advertise", "topic": f"{action}/goal", "type": f"control_msgs/{kind}ActionGoal"}
    )
    await client.send(
        {"op": "publish", "topic": f"{action}/goal", "msg": {"goal_id": {"id": goal_id}, "goal": body}}
    )


async def test_a_goal_through_actionlib_is_followed_and_a_cancel_stops_the_arm_where_it_is() -> None:
    async with (
        SimulatedRobot(dialect="ros1", world="arm") as robot,
        await RawClient.open(robot.url) as client,
    ):
        await goal(client, FOLLOW, "FollowJointTrajectory", "g1", {"trajectory": trajectory(0.3, 1)})
        done = await result(client, FOLLOW, "g1")
        assert done["status"]["status"] == 3  # SUCCEEDED
        assert done["result"]["error_code"] == 0
        assert robot.arm.positions["shoulder_pan_joint"] == pytest.approx(0.3)
        await goal(client, FOLLOW, "FollowJointTrajectory", "g2", {"trajectory": trajectory(1.5, 4)})
        await robot.wait_for(lambda _: robot.arm.positions["shoulder_pan_joint"] > 0.35, WAIT)
        await client.send({"op": "advertise", "topic": f"{FOLLOW}/cancel", "type": "actionlib_msgs/GoalID"})
        await client.send({"op": "publish", "topic": f"{FOLLOW}/cancel", "msg": {"id": "g2"}})
        assert (await result(client, FOLLOW, "g2"))["status"]["status"] == 2  # PREEMPTED
    assert 0.35 < robot.arm.positions["shoulder_pan_joint"] < 1.4
    assert robot.arm.run is None


async def test_an_empty_trajectory_on_the_command_topic_holds_the_arm() -> None:
    """ros_control's joint_trajectory_controller: an empty trajectory stops what runs and holds."""
    async with (
        SimulatedRobot(dialect="ros1", world="arm") as robot,
        await RawClient.open(robot.url) as client,
    ):
        await client.send(
            {"op": "advertise", "topic": "/arm_controller/command", "type": "trajectory_msgs/JointTrajectory"}
        )
        await client.send({"op": "publish", "topic": "/arm_controller/command", "msg": trajectory(1.5, 4)})
        await robot.wait_for(lambda _: robot.arm.positions["shoulder_pan_joint"] > 0.05, WAIT)
        await client.send({"op": "publish", "topic": "/arm_controller/command", "msg": {"points": []}})
        await robot.wait_for(lambda _: robot.arm.run is None, WAIT)
        here = robot.arm.positions["shoulder_pan_joint"]
    assert 0.05 < here < 1.4
    assert not any(robot.arm.velocities.values())


async def test_the_gripper_closes_through_actionlib() -> None:
    action = "/gripper_controller/gripper_cmd"
    async with (
        SimulatedRobot(dialect="ros1", world="arm") as robot,
        await RawClient.open(robot.url) as client,
    ):
        await goal(
            client, action, "GripperCommand", "c1", {"command": {"position": 0.01, "max_effort": 10.0}}
        )
        done = await result(client, action, "c1")
    assert done["status"]["status"] == 3
    assert done["result"]["reached_goal"] is True
    assert robot.arm.positions[FINGER] == pytest.approx(0.01)


async def test_the_description_srdf_and_controllers_in_ros1_form() -> None:
    async with (
        SimulatedRobot(dialect="ros1", world="arm") as robot,
        await RawClient.open(robot.url) as client,
    ):
        for index, name in enumerate(("/robot_description", "/robot_description_semantic")):
            await client.send(
                {
                    "op": "call_service",
                    "id": f"p{index}",
                    "service": "/rosapi/get_param",
                    "args": {"name": name},
                }
            )
            reply = await client.recv_until(lambda f, i=index: f.get("id") == f"p{i}", WAIT)
            text = json.loads(reply["values"]["value"])
            assert ('<joint name="elbow_joint"' if index == 0 else '<group_state name="home"') in text
        await client.send(
            {"op": "call_service", "id": "l", "service": "/controller_manager/list_controllers"}
        )
        listed = (await client.recv_until(lambda f: f.get("id") == "l", WAIT))["values"]["controller"]
        arm = next(c for c in listed if c["name"] == "arm_controller")
        assert arm["state"] == "running"
        assert arm["claimed_resources"][0]["resources"] == list(ARM_JOINTS)
        await client.send(
            {
                "op": "call_service",
                "id": "s",
                "service": "/controller_manager/switch_controller",
                "args": {"stop_controllers": ["arm_controller"], "strictness": 2},
            }
        )
        assert (await client.recv_until(lambda f: f.get("id") == "s", WAIT))["values"]["ok"] is True
    assert not robot.arm.controllers.is_active("arm_controller")
