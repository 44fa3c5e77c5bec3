"""The arm judge (``safety/arm.py``) on acts built as the acting layer builds them, with the arm given: URDF
limits, the speed scale, the workspace and keep-out boxes, the gripper, every carrier and spelling the same.
The attacks through an MCP session on the simulated arm are in ``tests/mcp/test_mcp_arm.py``."""

from __future__ import annotations

import math
import re
from typing import Any

import pytest

from arm_fixture import ARM_JOINTS, HOME, ROBOT, arm_urdf, scene
from rosbridge_mcp_server.errors import PolicyRefusal
from rosbridge_mcp_server.robot.approval import Act, nobody_to_ask
from rosbridge_mcp_server.robot.arm.kinematics import Chain, translation
from rosbridge_mcp_server.robot.arm.urdf import parse_urdf
from rosbridge_mcp_server.robot.arm_goals import carried_arm
from rosbridge_mcp_server.robot.arm_scene import ArmScene
from rosbridge_mcp_server.safety import PolicyGuard, parse_policy
from rosbridge_mcp_server.safety.arm import arm_goal_text, arm_refusal

NONE = parse_policy({}, where="t.toml").arm
BOXES = parse_policy(
    {
        "arm": {
            "workspace": {"table": [[-1.0, -1.0, 0.3], [1.0, 1.0, 1.2]]},
            "keep_out": {"person": [[-1.0, 0.2, 0.0], [1.0, 1.0, 2.0]]},
        }
    },
    where="t.toml",
).arm


def trajectory(
    target: dict[str, float], seconds: float, joints: tuple[str, ...] = ARM_JOINTS
) -> dict[str, Any]:
    """One point at *seconds*: HOME with *target* (radians) set."""
    positions = [target.get(name, HOME.get(name, 0.0)) for name in joints]
    return {
        "joint_names": list(joints),
        "points": [
            {
                "positions": positions,
                "time_from_start": {"sec": int(seconds), "nanosec": int(seconds % 1 * 1e9)},
            }
        ],
    }


def carriers(traj: dict[str, Any]) -> list[tuple[str, str, str, Any]]:
    """The same trajectory by every carrier and type spelling: (kind, name, type, payload)."""
    goal = {"trajectory": traj}
    return [
        (
            "action",
            "/arm_controller/follow_joint_trajectory",
            "control_msgs/action/FollowJointTrajectory",
            goal,
        ),
        (
            "action",
            "/arm_controller/follow_joint_trajectory",
            "control_msgs/FollowJointTrajectoryAction",
            goal,
        ),
        ("action", "/arm_controller/follow_joint_trajectory", "", goal),
        (
            "service",
            "/arm_controller/follow_joint_trajectory/_action/send_goal",
            "control_msgs/action/FollowJointTrajectory_SendGoal",
            {"goal_id": {}, "goal": goal},
        ),
        (
            "service",
            "/arm_controller/follow_joint_trajectory/_action/send_goal",
            "control_msgs/FollowJointTrajectory",
            {"goal": goal},
        ),
        (
            "topic",
            "/arm_controller/follow_joint_trajectory/goal",
            "control_msgs/FollowJointTrajectoryActionGoal",
            {"goal_id": {}, "goal": goal},
        ),
        ("topic", "/arm_controller/joint_trajectory", "trajectory_msgs/msg/JointTrajectory", traj),
        ("topic", "/arm_controller/joint_trajectory", "trajectory_msgs/JointTrajectory", traj),
    ]


def acts(traj: dict[str, Any], arm: ArmScene | None = None) -> list[Act]:
    arm = scene() if arm is None else arm
    return [
        Act("publish_x", kind, name, type_name, payload, scene=arm)  # type: ignore[arg-type]
        for kind, name, type_name, payload in carriers(traj)
    ]


def test_every_carrier_and_spelling_is_read_as_the_same_trajectory() -> None:
    traj = trajectory({"elbow_joint": 1.0}, 2.0)
    read = [carried_arm(a.kind, a.name, a.type, a.payload) for a in acts(traj)]
    assert all(r is not None and r.kind == "trajectory" for r in read)
    bodies = {r.body for r in read if r is not None}
    assert len(bodies) == 1


def test_a_slow_goal_within_the_limits_is_allowed_by_every_carrier() -> None:
    """0.2 rad in 2 s is 0.1 rad/s, under a quarter of 3 rad/s."""
    for act in acts(trajectory({"elbow_joint": 1.0}, 2.0)):
        assert arm_refusal(act, NONE) is None, act


@pytest.mark.parametrize("policy", [NONE, BOXES])
def test_a_position_beyond_the_urdf_limit_is_refused_naming_the_joint_and_the_limit(policy: Any) -> None:
    for act in acts(trajectory({"elbow_joint": math.radians(170)}, 60.0)):
        refusal = arm_refusal(act, policy)
        assert refusal is not None, act
        assert "elbow_joint at 170.0°, outside its URDF limits -160.0° … 160.0°" in refusal.text
        assert "nothing was sent" in refusal.text


def test_a_goal_faster_than_the_speed_scale_is_refused_by_every_carrier() -> None:
    """1 rad in 1 s is 57°/s: under the URDF's 3 rad/s, over its quarter (43°/s)."""
    for act in acts(trajectory({"elbow_joint": 0.2}, 1.0)):
        refusal = arm_refusal(act, NONE)
        assert refusal is not None, act
        assert "moves elbow_joint at 57.3°/s, faster than 43.0°/s" in refusal.text
    # At the full URDF speed (speed_scale = 1) the same goal is allowed.
    full = parse_policy({"arm": {"speed_scale": 1.0}}, where="t.toml").arm
    assert all(arm_refusal(act, full) is None for act in acts(trajectory({"elbow_joint": 0.2}, 1.0)))


def test_a_first_point_at_zero_seconds_away_from_the_arm_is_a_jump() -> None:
    traj = trajectory({"elbow_joint": 0.5}, 0.0)
    refusal = arm_refusal(acts(traj)[0], NONE)
    assert refusal is not None
    assert "the controller would jump there" in refusal.text


def test_velocities_given_by_the_model_are_judged_too() -> None:
    traj = trajectory({"elbow_joint": 1.0}, 10.0)
    traj["points"][0]["velocities"] = [0.0, 0.0, 2.5, 0.0, 0.0, 0.0]
    refusal = arm_refusal(acts(traj)[0], NONE)
    assert refusal is not None
    assert "point 0's velocity moves elbow_joint" in refusal.text


def test_a_cubic_segment_swinging_past_a_limit_is_refused_though_every_point_is_within() -> None:
    """Elbow 2.7 rad at 0.7 rad/s → 2.75 rad at rest in 1 s swings to ~2.81, past the limit 2.7925."""
    traj = trajectory({"elbow_joint": 2.7}, 20.0)
    traj["points"].append({"positions": list(traj["points"][0]["positions"]), "time_from_start": {"sec": 21}})
    traj["points"][1]["positions"][2] = 2.75
    traj["points"][0]["velocities"] = [0.0, 0.0, 0.7, 0.0, 0.0, 0.0]
    traj["points"][1]["velocities"] = [0.0] * 6
    refusal = arm_refusal(acts(traj)[0], NONE)
    assert refusal is not None
    assert "the cubic segment to point 1 swings elbow_joint to" in refusal.text
    traj["points"][0]["velocities"] = [0.0] * 6  # at rest at both ends: no swing past 2.75
    assert arm_refusal(acts(traj)[0], NONE) is None


def test_an_unknown_or_mimic_joint_is_refused() -> None:
    traj = trajectory({}, 5.0, joints=("shoulder_pan_joint", "gripper_right_finger_joint"))
    traj["points"][0]["positions"] = [0.0, 0.01]
    refusal = arm_refusal(acts(traj)[0], NONE)
    assert refusal is not None
    assert "'gripper_right_finger_joint' is not a movable joint" in refusal.text


def test_a_path_leaving_the_workspace_is_refused_where_both_ends_are_inside() -> None:
    """Tool from above (0.28, 0.02, 0.86) through the pan: the tool stays up; lifting the shoulder flat drops
    the tool below z = 0.3 on the way."""
    inside = trajectory({"shoulder_pan_joint": -0.5}, 10.0)
    assert all(arm_refusal(act, BOXES) is None for act in acts(inside))
    low = trajectory({"shoulder_lift_joint": 1.9, "elbow_joint": 0.2}, 20.0)
    for act in acts(low):
        refusal = arm_refusal(act, BOXES)
        assert refusal is not None, act
        assert "outside the workspace (table)" in refusal.text
    assert arm_refusal(acts(low)[0], NONE) is None  # no boxes: only the limits and speed


def test_a_path_into_a_keep_out_box_is_refused() -> None:
    """Panning the arm 90° left swings the tool to y ≈ 0.28: into the person's box (y ≥ 0.2)."""
    swing = trajectory({"shoulder_pan_joint": math.radians(90)}, 20.0)
    for act in acts(swing):
        refusal = arm_refusal(act, BOXES)
        assert refusal is not None, act
        assert "into the keep-out box person" in refusal.text


def _highest_point(start: dict[str, float], end: dict[str, float]) -> float:
    """The highest any link origin of the arm gets on the straight joint path from *start* to *end*, sampled
    finer (0.1 % of the travel) than the judge samples it."""
    chain = Chain(ROBOT, ROBOT.root, "tool0")
    top = 0.0
    for k in range(1001):
        held = {name: a + (end[name] - a) * k / 1000 for name, a in start.items()}
        top = max([top] + [translation(pose)[2] for _, pose in chain.poses(held)])
    return top


def test_a_link_whose_centre_line_misses_a_keep_out_box_by_1_cm_but_whose_body_enters_it_is_refused() -> None:
    """Raising the forearm lifts the tool to its highest point; a ceiling 1 cm above that point's centre line
    is entered by the link's body (the default link radius, 5 cm: this URDF gives no size)."""
    target = {"elbow_joint": 0.2}
    top = _highest_point(HOME, HOME | target)
    ceiling = {"keep_out": {"ceiling": [[-2.0, -2.0, top + 0.01], [2.0, 2.0, 3.0]]}}
    raise_forearm = trajectory(target, 20.0)
    for act in acts(raise_forearm):
        refusal = arm_refusal(act, parse_policy({"arm": ceiling}, where="t").arm)
        assert refusal is not None, act
        assert "into the keep-out box ceiling" in refusal.text
    # Links as thin as their centre lines (link_radius 0): the same goal passes 1 cm under the ceiling.
    thin = parse_policy({"arm": {**ceiling, "link_radius": 0.0}}, where="t").arm
    assert arm_refusal(acts(raise_forearm)[0], thin) is None
    # Sizes the URDF gives are used: a 5 mm-thin arm passes too, whatever link_radius says.
    thin_links = parse_urdf(_with_radius(arm_urdf(), 0.005))
    act = acts(raise_forearm, ArmScene(thin_links, dict(HOME)))[0]
    assert arm_refusal(act, parse_policy({"arm": ceiling}, where="t").arm) is None


def _with_radius(urdf: str, radius: float) -> str:
    """*urdf* with every bare link given a sphere of *radius*."""
    shape = f'<collision><geometry><sphere radius="{radius}"/></geometry></collision>'
    return re.sub(r'<link name="([^"]+)"/>', lambda m: f'<link name="{m.group(1)}">{shape}</link>', urdf)


def test_without_a_description_nothing_is_judged_unless_boxes_are_set() -> None:
    blind = ArmScene(None, {}, problems=("/robot_description is not in the robot's graph",))
    act = acts(trajectory({"elbow_joint": 3.0}, 0.1), blind)[0]
    assert arm_refusal(act, NONE) is None
    refusal = arm_refusal(act, BOXES)
    assert refusal is not None
    assert "/robot_description is not in the robot's graph" in refusal.text


def test_without_joint_states_the_speed_cannot_be_checked_so_the_goal_is_refused() -> None:
    act = acts(trajectory({"elbow_joint": 1.0}, 5.0), ArmScene(ROBOT, {}))[0]
    refusal = arm_refusal(act, NONE)
    assert refusal is not None
    assert "was not read from /joint_states" in refusal.text


@pytest.mark.parametrize(
    ("traj", "fragment"),
    [
        ({"joint_names": ["elbow_joint"], "points": []}, "holds no points"),
        (
            # ROS 1's bridge reads only secs (0 here: a jump) where the judge would read sec.
            {
                "joint_names": ["elbow_joint"],
                "points": [{"positions": [2.0], "time_from_start": {"sec": 60, "secs": 0}}],
            },
            "one spelling only",
        ),
        ({"joint_names": ["elbow_joint"], "points": [{"positions": ["x"]}]}, "not a finite number"),
        (
            {"joint_names": ["elbow_joint", "elbow_joint"], "points": [{"positions": [1, 1]}]},
            "each joint once",
        ),
        (
            {
                "joint_names": ["elbow_joint"],
                "points": [
                    {"positions": [1.2], "time_from_start": {"sec": 2}},
                    {"positions": [1.2], "time_from_start": {"sec": 1}},
                ],
            },
            "later than the point before it",
        ),
    ],
)
def test_an_unreadable_trajectory_is_refused(traj: dict[str, Any], fragment: str) -> None:
    refusal = arm_refusal(acts(traj)[0], NONE)
    assert refusal is not None
    assert fragment in refusal.text


def test_a_multi_dof_trajectory_is_refused() -> None:
    goal = {"trajectory": trajectory({}, 5.0), "multi_dof_trajectory": {"points": [{"transforms": []}]}}
    act = Act(
        "publish_action",
        "action",
        "/arm_controller/follow_joint_trajectory",
        "control_msgs/action/FollowJointTrajectory",
        goal,
        scene=scene(),
    )
    refusal = arm_refusal(act, NONE)
    assert refusal is not None
    assert "multi_dof_trajectory" in refusal.text


@pytest.mark.parametrize(
    ("command", "policy", "fragment"),
    [
        (
            {"position": 0.06, "max_effort": 10},
            NONE,
            "gripper_finger_joint at 0.060 m, outside its URDF limits",
        ),
        ({"position": 0.02, "max_effort": 50}, NONE, "max_effort 50, beyond 40"),
        (
            {"position": 0.02, "max_effort": 15},
            parse_policy({"arm": {"max_gripper_effort": 10}}, where="t").arm,
            "max_effort 15, beyond 10",
        ),
        (
            {"position": 0.02, "max_effort": 0},
            parse_policy({"arm": {"max_gripper_effort": 10}}, where="t").arm,
            "0 would mean no limit",
        ),
    ],
)
def test_a_gripper_goal_beyond_its_limits_is_refused(
    command: dict[str, Any], policy: Any, fragment: str
) -> None:
    for kind, name, type_name, payload in [
        (
            "action",
            "/gripper_controller/gripper_cmd",
            "control_msgs/action/GripperCommand",
            {"command": command},
        ),
        (
            "service",
            "/gripper_controller/gripper_cmd/_action/send_goal",
            "control_msgs/action/GripperCommand_SendGoal",
            {"goal": {"command": command}},
        ),
    ]:
        refusal = arm_refusal(Act("t", kind, name, type_name, payload, scene=scene()), policy)  # type: ignore[arg-type]
        assert refusal is not None
        assert fragment in refusal.text
    ok = Act(
        "t",
        "action",
        "/gripper_controller/gripper_cmd",
        "control_msgs/action/GripperCommand",
        {"command": {"position": 0.0, "max_effort": 5}},
        scene=scene(),
    )
    assert arm_refusal(ok, policy) is None


async def test_a_controller_switch_needs_a_person_while_arm_boxes_are_set() -> None:
    switch = Act(
        "publish_service",
        "service",
        "/controller_manager/switch_controller",
        "controller_manager_msgs/srv/SwitchController",
        {"activate_controllers": ["other_controller"], "deactivate_controllers": ["arm_controller"]},
    )
    guard = PolicyGuard(parse_policy({"arm": {"keep_out": {"p": [[0, 0, 0], [1, 1, 1]]}}}, where="t"))
    with pytest.raises(PolicyRefusal) as refused:
        await guard.approve(switch, nobody_to_ask)
    assert "requires a person to confirm" in str(refused.value)
    assert await PolicyGuard(parse_policy({}, where="t")).approve(switch, nobody_to_ask) == switch
    assert arm_goal_text(switch) == (
        "Switches the robot's controllers: activates other_controller; deactivates arm_controller."
    )


async def test_arm_confirm_motion_asks_for_every_arm_carrier() -> None:
    guard = PolicyGuard(parse_policy({"arm": {"confirm": "motion"}}, where="t"))
    asked: list[str] = []

    async def ask(question: str) -> Any:
        asked.append(question)
        return "accept"

    from rosbridge_mcp_server.robot.approval import asking

    for act in acts(trajectory({"elbow_joint": 1.0}, 2.0)):
        await guard.approve(act, asking(ask))
    assert len(asked) == len(carriers(trajectory({}, 1.0)))
    assert all(
        "Moves the arm to shoulder_pan_joint 0.0°, shoulder_lift_joint -17.2°, elbow_joint 57.3°" in q
        for q in asked
    )
