"""view_arm through an MCP session on the simulated arm: the description, the joint state, the tool by forward
kinematics (checked against tf), the controllers, the named poses; and its size for a 7-joint arm."""

from __future__ import annotations

import math
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import pytest
from mcp_harness import Session, open_session, text_of

from rosbridge_mcp_server.robot.arm.controllers import parse_controllers, parse_srdf
from rosbridge_mcp_server.robot.arm.reading import ArmReading, JointStateNow
from rosbridge_mcp_server.robot.arm.urdf import parse_urdf
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.nodes.arm import ARM_JOINTS, FINGER, HOME
from rosbridge_mcp_server.tools.view_arm import build_answer, render

MakeSim = Callable[..., Awaitable[SimulatedRobot]]
#: Where the lab's NOTES.md says tool0 is at home, in base_link (the arm's mount is 0.1 m above it).
TOOL0_AT_HOME_IN_BASE_LINK = (0.281, 0.020, 0.858)


@pytest.fixture
async def arm(make_sim: MakeSim) -> SimulatedRobot:
    return await make_sim(dialect="ros2", world="arm")


@pytest.fixture
async def session(arm: SimulatedRobot) -> AsyncIterator[Session]:
    async with open_session(arm.url) as opened:
        yield opened


async def test_view_arm_shows_joints_limits_state_tool_controllers_and_poses(session: Session) -> None:
    """Every movable joint with limits in degrees, positions at home, tool0 where the lab says, controllers
    active with their joints, the SRDF's named poses."""
    result = await session.ok("view_arm", {"frame": "base_link"})
    data: dict[str, Any] = result.structured_content or {}
    joints = {j["name"]: j for j in data["joints"]}
    assert set(joints) == {*ARM_JOINTS, FINGER, "gripper_right_finger_joint"}
    elbow = joints["elbow_joint"]
    assert (elbow["lower"], elbow["upper"], elbow["unit"]) == (-160.0, 160.0, "deg")
    assert elbow["position"] == pytest.approx(math.degrees(HOME["elbow_joint"]), abs=0.01)
    assert elbow["max_speed"] == pytest.approx(math.degrees(3.0), abs=0.01)
    assert joints[FINGER]["at_limit"] == "upper"  # the gripper starts open, at 0.04 m
    assert joints["gripper_right_finger_joint"]["mimics"] == FINGER
    (tool,) = data["tools"]
    assert (tool["link"], tool["frame"]) == ("tool0", "base_link")
    assert tool["xyz"] == pytest.approx(TOOL0_AT_HOME_IN_BASE_LINK, abs=1e-3)
    assert tool["chain"] == list(ARM_JOINTS)
    controllers = {c["name"]: c for c in data["controllers"]}
    assert controllers["arm_controller"]["state"] == "active"
    assert controllers["arm_controller"]["joints"] == list(ARM_JOINTS)
    assert {p["name"] for p in data["named_poses"]} >= {"home", "ready", "open", "closed"}
    text = text_of(result)
    assert "- tool0 in base_link: x=0.2807 y=0.02 z=0.858 m" in text
    assert "gripper_finger_joint: prismatic at 0.04m" in text
    assert "AT ITS UPPER LIMIT" in text
    assert data["notes"] == []


async def test_the_default_frame_is_the_chain_base_and_a_tf_frame_is_looked_up(
    session: Session, arm: SimulatedRobot
) -> None:
    """Without a frame: arm_base_link (0.1 m lower than in base_link); with odom: through /tf."""
    result = await session.ok("view_arm", {})
    (tool,) = (result.structured_content or {})["tools"]
    assert tool["frame"] == "arm_base_link"
    x, y, z = TOOL0_AT_HOME_IN_BASE_LINK
    assert tool["xyz"] == pytest.approx((x, y, z - 0.1), abs=1e-3)
    result = await session.ok("view_arm", {"frame": "odom"})
    (tool,) = (result.structured_content or {})["tools"]
    turtle = arm.world.turtle
    assert tool["frame"] == "odom"
    assert tool["xyz"][2] == pytest.approx(z, abs=1e-3)  # the turtle is flat on the floor
    assert math.hypot(tool["xyz"][0], tool["xyz"][1]) == pytest.approx(
        math.hypot(x, y), abs=0.05 + abs(turtle.linear)
    )


async def test_an_inactive_controller_is_seen(session: Session) -> None:
    """After switch_controller deactivates arm_controller, view_arm says INACTIVE with no claimed joints."""
    await session.ok(
        "publish_service",
        {
            "service": "/controller_manager/switch_controller",
            "service_type": "controller_manager_msgs/srv/SwitchController",
            "request": {"deactivate_controllers": ["arm_controller"], "strictness": 2},
        },
    )
    text = text_of(await session.ok("view_arm", {}))
    assert (
        "- arm_controller: INACTIVE (joint_trajectory_controller/JointTrajectoryController), joints" in text
    )


async def test_joint_states_stale_is_said_not_guessed(make_sim: MakeSim) -> None:
    """Without /joint_states: positions unknown, the tool pose unknown with the reason, a note."""
    arm = await make_sim(dialect="ros2", world="arm", faults=["joint-states-stale"])
    async with open_session(arm.url) as session:
        result = await session.ok("view_arm", {"timeout": 0.5})
    data: dict[str, Any] = result.structured_content or {}
    assert data["notes"] == ["no /joint_states within 0.5 s"]
    assert all(j["position"] is None for j in data["joints"])
    assert "no position for joint(s) shoulder_pan_joint" in data["tools"][0]["unknown"]


async def test_a_robot_without_an_arm_is_said_to_have_none(make_sim: MakeSim) -> None:
    """The Nav2 robot's description has two wheels: joints listed, no end effector, "no arm" said."""
    nav2 = await make_sim(dialect="ros2", world="nav2")
    async with open_session(nav2.url) as session:
        result = await session.ok("view_arm", {"timeout": 1.0})
    assert (result.structured_content or {})["tools"] == []
    assert "this robot has no arm" in text_of(result)


async def test_a_robot_without_a_description_is_a_tool_error_that_says_so(make_sim: MakeSim) -> None:
    """No /robot_description publisher and no robot_state_publisher parameter: an error naming both."""
    turtle = await make_sim(dialect="ros2")
    turtle.graph.remove_publisher("/robot_state_publisher", "/robot_description")
    del turtle.world.params["/robot_state_publisher:robot_description"]
    async with open_session(turtle.url) as session:
        message = await session.error("view_arm", {"timeout": 0.3})
    assert "No robot description: /robot_description is not published" in message
    assert "robot_state_publisher" in message


def seven_joint_arm() -> str:
    """A Franka-like arm: 7 revolute joints, a hand and two mimic fingers, long names."""
    links = ["panda_link0", *[f"panda_link{i}" for i in range(1, 8)], "panda_link8", "panda_hand"]
    links += ["panda_leftfinger", "panda_rightfinger", "panda_hand_tcp"]
    joints = []
    for i in range(1, 8):
        roll = "-1.5708" if i % 2 else "1.5708"
        joints.append(
            f'<joint name="panda_joint{i}" type="revolute"><parent link="panda_link{i - 1}"/>'
            f'<child link="panda_link{i}"/><origin xyz="0 0 0.1" rpy="{roll} 0 0"/><axis xyz="0 0 1"/>'
            '<limit lower="-2.8973" upper="2.8973" velocity="2.175" effort="87"/></joint>'
        )
    fixed = [
        ("panda_joint8", "panda_link7", "panda_link8"),
        ("panda_hand_joint", "panda_link8", "panda_hand"),
    ]
    fixed.append(("panda_hand_tcp_joint", "panda_hand", "panda_hand_tcp"))
    joints += [
        f'<joint name="{n}" type="fixed"><parent link="{p}"/><child link="{c}"/>'
        '<origin xyz="0 0 0.1"/></joint>'
        for n, p, c in fixed
    ]
    for side, mimic in (("left", ""), ("right", '<mimic joint="panda_finger_joint1"/>')):
        joints.append(
            f'<joint name="panda_finger_joint{1 if side == "left" else 2}" type="prismatic">'
            f'<parent link="panda_hand"/><child link="panda_{side}finger"/><axis xyz="0 1 0"/>'
            f'<limit lower="0" upper="0.04" velocity="0.2" effort="100"/>{mimic}</joint>'
        )
    body = "".join(f'<link name="{link}"/>' for link in links) + "".join(joints)
    return f'<robot name="panda">{body}</robot>'


def test_a_seven_joint_arm_with_a_gripper_fits_in_8000_characters() -> None:
    """The text of a 7-joint arm with a gripper, every part present, stays under 8,000 characters."""
    robot = parse_urdf(seven_joint_arm())
    names = [j.name for j in robot.movable_joints]
    state = JointStateNow(
        dict.fromkeys(names, 0.3), dict.fromkeys(names, 0.1), dict.fromkeys(names, 1.5), 0.01
    )
    claimed = [f"panda_joint{i}/position" for i in range(1, 8)]
    controllers = parse_controllers(
        {
            "controller": [
                {"name": "fr3_arm_controller", "state": "active", "claimed_interfaces": claimed,
                 "type": "joint_trajectory_controller/JointTrajectoryController"},
                {"name": "franka_gripper", "type": "franka_gripper/GripperController", "state": "active",
                 "claimed_interfaces": ["panda_finger_joint1/position"]},
                {"name": "joint_state_broadcaster", "type": "joint_state_broadcaster/JointStateBroadcaster",
                 "state": "active"},
            ]
        }
    )  # fmt: skip
    poses = "".join(
        f'<group_state name="pose_{k}" group="panda_arm">'
        + "".join(f'<joint name="panda_joint{i}" value="0.{k}"/>' for i in range(1, 8))
        + "</group_state>"
        for k in range(8)
    )
    semantic = parse_srdf(f'<robot name="panda">{poses}</robot>')
    reading = ArmReading(
        robot, "topic /robot_description", state, controllers, "/controller_manager", semantic, "topic", ()
    )
    text = render(build_answer(reading, None, None))
    assert "panda_hand_tcp in panda_link0" in text
    assert len(text) <= 8_000, len(text)


BOMB = (
    '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa">'
    + "".join(f'<!ENTITY a{i} "{"&a;" * 10 if i == 0 else f"&a{i - 1};" * 10}">' for i in range(9))
    + ']><robot name="&a8;"><link name="l"/></robot>'
)
CYCLE = (
    '<robot name="r"><link name="a"/><link name="b"/>'
    '<joint name="j1" type="fixed"><parent link="a"/><child link="b"/></joint>'
    '<joint name="j2" type="fixed"><parent link="b"/><child link="a"/></joint></robot>'
)
NAN_LIMIT = (
    '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="revolute"><parent link="a"/>'
    '<child link="b"/><limit lower="nan" upper="1" velocity="1"/></joint></robot>'
)


@pytest.mark.parametrize(
    ("description", "words"),
    [
        (BOMB, "has a DTD (<!DOCTYPE>); a URDF needs none, and it is not read"),
        ("<robot>" + "x" * 2_100_000 + "</robot>", "at most 2,000,000 are read"),
        ("<robot name='r'>" + "<a>" * 3000 + "</a>" * 3000 + "</robot>", "nests elements deeper than 24"),
        (CYCLE, "joints form a cycle"),
        (NAN_LIMIT, "not a finite number"),
    ],
    ids=["entity-bomb", "huge", "deep", "cycle", "nan-limit"],
)
async def test_a_hostile_description_is_refused_in_words(
    make_sim: MakeSim, description: str, words: str
) -> None:
    """The description (here robot_state_publisher's parameter) is robot text: an entity bomb, 2 MB+, deep
    nesting, a cycle, a NaN limit are each a tool error saying what is wrong, and the server goes on."""
    robot = await make_sim(dialect="ros2")
    robot.graph.remove_publisher("/robot_state_publisher", "/robot_description")
    robot.world.params["/robot_state_publisher:robot_description"] = description
    async with open_session(robot.url, request_timeout=15.0) as session:
        message = await session.error("view_arm", {"timeout": 0.3})
        assert (
            "The robot description (parameter /robot_state_publisher:robot_description) cannot be read"
            in message
        )
        assert words in message
        assert not (await session.call("list_topics")).is_error


async def test_view_arm_on_ros1_reads_ros_controls_controllers_and_the_srdf_parameter(
    make_sim: MakeSim,
) -> None:
    """ROS 1: list_controllers' running/stopped and claimed_resources read as ros2_control's words; the SRDF
    from the /robot_description_semantic parameter (MoveIt's ROS 1 layout)."""
    robot = await make_sim(dialect="ros1", world="arm")
    robot.arm.controllers.controllers["gripper_controller"].active = False
    async with open_session(robot.url) as session:
        result = await session.ok("view_arm")
    data: dict[str, Any] = result.structured_content or {}
    controllers = {c["name"]: c for c in data["controllers"]}
    assert controllers["arm_controller"]["state"] == "active"
    assert controllers["arm_controller"]["joints"] == list(ARM_JOINTS)
    assert controllers["gripper_controller"]["state"] == "inactive"
    assert "ready" in {pose["name"] for pose in data["named_poses"]}


async def test_on_the_plain_demo_view_arm_says_there_is_no_arm_and_where_one_is(make_sim: MakeSim) -> None:
    """The turtle's description has no movable joint: one sentence, not "0 movable joints" and empty lists."""
    turtle = await make_sim(dialect="ros2")
    async with open_session(turtle.url) as session:
        text = text_of(await session.ok("view_arm", {"timeout": 1.0}))
    assert text.startswith("No arm on robot sim_turtle (")
    assert "its robot description has no movable joint, so this robot publishes no arm" in text
    assert "--demo --demo-world arm" in text
    assert "0 movable joints" not in text
    assert "Joints (" not in text
