"""The guard's judgement of arm motion: one rule for every trajectory and gripper goal, whichever tool and
carrier sends it and however its type is spelt (``robot/arm_goals.py``: ``move_arm`` and ``move_gripper``;
``publish_action`` on a ``FollowJointTrajectory`` / ``GripperCommand`` server; ROS 2's
``<action>/_action/send_goal`` through ``publish_service``; ROS 1 actionlib's ``<action>/goal`` and a
``JointTrajectory`` on ``…/joint_trajectory`` through ``publish_topic``).

The act carries the arm it is judged against (``Act.scene``: an :class:`~rosbridge_mcp_server.robot.arm_scene.
ArmScene`, the URDF and the joint positions now, learnt by ``robot/acting/`` just before). In order:

1. the act must be readable (joint names, finite positions, times that increase); a multi-DOF trajectory is
   refused;
2. with no robot description, nothing can be judged: refused while ``[arm]`` has boxes (fail closed), else
   allowed unjudged;
3. every joint named is a movable joint of the URDF (not a mimic); every position within its URDF limits;
4. speed: from where the arm is now through every point, no joint faster than ``speed_scale`` × its URDF
   velocity (the controller interpolates linearly between points, by a cubic where both ends carry
   velocities: that curve is sampled); a first point at 0 s away from where the arm is (a jump) is refused;
5. ``[arm]`` boxes: along the interpolated path (sampled every :data:`STEP_RADIANS` of joint travel), every
   end effector inside one workspace box and every moving link's segment (joint to joint) outside every
   keep-out box, both by ``margin``, in the ``frame`` link (default the URDF's root);
6. a gripper goal's position(s) within the gripper joint's limits, its effort within the URDF's and
   ``max_gripper_effort``.

A ``switch_controller`` call is not judged here: the guard asks the person for it (``safety/guard.py``).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rosbridge_mcp_server.robot.arm_goals import ArmAct, GripperGoal, Trajectory, carried_arm

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.approval import Act
    from rosbridge_mcp_server.robot.arm.kinematics import Chain
    from rosbridge_mcp_server.robot.arm.urdf import Joint, Robot
    from rosbridge_mcp_server.robot.arm_path import Point
    from rosbridge_mcp_server.robot.arm_scene import ArmScene
    from rosbridge_mcp_server.safety.arm_rules import ArmRules

__all__ = ["ARM_SOURCES", "ArmRefusal", "act_arm", "arm_goal_text", "arm_refusal", "source_refusal"]

#: A first point at 0 s farther than this from where the joint is, is a jump.
JUMP_TOLERANCE = 1e-3
#: Slack on a speed (relative), for the rounding of times to nanoseconds.
SPEED_SLACK = 1e-6


@dataclass(frozen=True)
class ArmRefusal:
    """The rule (for the audit) and the sentence for the model."""

    rule: str
    text: str


def _refusal(rule: str, why: str, advice: str = "") -> ArmRefusal:
    return ArmRefusal(rule, f"Refused: {why}; nothing was sent. {advice}".strip())


def act_arm(act: Act) -> ArmAct | None:
    """What *act* does to an arm (a trajectory, a gripper goal, a controller switch), or ``None``."""
    return carried_arm(act.kind, act.name, act.type, act.payload)


def _shown(joint: Joint, value: float) -> str:
    return f"{value:.3f} m" if joint.linear else f"{math.degrees(value):.1f}°"


def _speed(joint: Joint, value: float) -> str:
    return f"{value:.3f} m/s" if joint.linear else f"{math.degrees(value):.1f}°/s"


def arm_refusal(act: Act, rules: ArmRules) -> ArmRefusal | None:
    """Why the arm motion *act* carries may not be sent, or ``None`` (also for an act that moves no arm)."""
    arm = act_arm(act)
    if arm is None or arm.kind == "switch":
        return None
    if isinstance(arm.body, str):
        return _refusal(
            f"arm: unreadable {arm.what}",
            f"the {arm.what} sent to {arm.target} cannot be read: {arm.body}",
            "Send joint names, finite positions and increasing times.",
        )
    from rosbridge_mcp_server.robot.arm_scene import ArmScene  # noqa: PLC0415 - arm acts only

    scene = act.scene if isinstance(act.scene, ArmScene) else None
    if scene is None or scene.robot is None:
        if not rules.configured:
            return None
        why = "; ".join(scene.problems) if scene is not None and scene.problems else "it was not read"
        return _refusal(
            "[arm] no robot description",
            f"the safety policy's [arm] boxes need the arm's robot description (URDF), and {why}",
            "Make sure /robot_description is published, or ask the robot's operator.",
        )
    if isinstance(arm.body, GripperGoal):
        return _gripper_refusal(arm, arm.body, scene, rules)
    assert isinstance(arm.body, Trajectory)
    return _trajectory_refusal(arm.body, scene, rules)


def _joints(trajectory: Trajectory, robot: Robot) -> list[Joint] | ArmRefusal:
    out = []
    for name in trajectory.joints:
        joint = robot.joint(name)
        if joint is None or not joint.movable or joint.mimic is not None:
            movable = ", ".join(j.name for j in robot.movable_joints[:12])
            return _refusal(
                f"arm: unknown joint {name}",
                f"{name!r} is not a movable joint of the robot description (its joints: {movable})",
            )
        out.append(joint)
    return out


def _trajectory_refusal(trajectory: Trajectory, scene: ArmScene, rules: ArmRules) -> ArmRefusal | None:
    assert scene.robot is not None
    joints = _joints(trajectory, scene.robot)
    if isinstance(joints, ArmRefusal):
        return joints
    for index, point in enumerate(trajectory.points):
        for joint, value in zip(joints, point.positions, strict=True):
            low, high = joint.limits.lower, joint.limits.upper
            if joint.bounded and low is not None and high is not None and not low <= value <= high:
                return _refusal(
                    f"URDF limit of {joint.name}",
                    f"point {index} puts {joint.name} at {_shown(joint, value)}, outside its URDF limits "
                    f"{_shown(joint, low)} … {_shown(joint, high)}",
                    "Choose positions within the limits (view the arm for them).",
                )
    start = [scene.positions.get(joint.name) for joint in joints]
    if any(value is None for value in start):
        unknown = ", ".join(j.name for j, v in zip(joints, start, strict=True) if v is None)
        return _refusal(
            "arm: joint state unknown",
            f"where {unknown} is now was not read from /joint_states, so the trajectory's speed cannot be "
            "checked",
            "Make sure /joint_states is published.",
        )
    begin = tuple(float(v) for v in start if v is not None)
    return (
        _overshoot_refusal(trajectory, joints, begin)
        or _speed_refusal(trajectory, joints, begin, rules)
        or _box_refusal(trajectory, joints, begin, (scene, rules))
    )


def _overshoot_refusal(
    trajectory: Trajectory, joints: list[Joint], begin: tuple[float, ...]
) -> ArmRefusal | None:
    """A cubic segment (velocities at both ends) can swing past its ends: sampled against the URDF limits."""
    from rosbridge_mcp_server.robot.arm_path import CUBIC_SAMPLES, hermite  # noqa: PLC0415 - arm acts only

    previous, previous_time = begin, 0.0
    previous_speeds: tuple[float, ...] | None = tuple(0.0 for _ in joints)  # the arm starts at rest
    for index, point in enumerate(trajectory.points):
        span = point.time - previous_time
        if point.velocities is not None and previous_speeds is not None and span > 0:
            for j, joint in enumerate(joints):
                low, high = joint.limits.lower, joint.limits.upper
                if not joint.bounded or low is None or high is None:
                    continue
                ends = (previous[j], point.positions[j], previous_speeds[j], point.velocities[j])
                for k in range(1, CUBIC_SAMPLES):
                    value = hermite(ends, span, k / CUBIC_SAMPLES)[0]
                    if not low <= value <= high:
                        return _refusal(
                            f"URDF limit of {joint.name}",
                            f"the cubic segment to point {index} swings {joint.name} to "
                            f"{_shown(joint, value)}, outside its URDF limits {_shown(joint, low)} … "
                            f"{_shown(joint, high)}",
                            "Give smaller velocities at the points, or none.",
                        )
        previous, previous_time, previous_speeds = point.positions, point.time, point.velocities
    return None


def _speed_refusal(
    trajectory: Trajectory, joints: list[Joint], begin: tuple[float, ...], rules: ArmRules
) -> ArmRefusal | None:
    from rosbridge_mcp_server.robot.arm_path import peak_speeds  # noqa: PLC0415 - arm acts only

    first = trajectory.points[0]
    if first.time == 0.0:
        for joint, now, there in zip(joints, begin, first.positions, strict=True):
            if abs(there - now) > JUMP_TOLERANCE:
                return _refusal(
                    f"arm: jump of {joint.name}",
                    f"the first point is at 0 s but puts {joint.name} at {_shown(joint, there)} while it is "
                    f"at {_shown(joint, now)}: the controller would jump there",
                    "Give the first point a time that keeps within the speed limit.",
                )
    caps = [_cap(joint, rules) for joint in joints]
    for index, point in enumerate(trajectory.points):
        for joint, cap, speed in zip(joints, caps, point.velocities or (), strict=False):
            if cap is not None and abs(speed) > cap * (1 + SPEED_SLACK):
                return _over(joint, cap, abs(speed), f"point {index}'s velocity", rules)
    previous_time, previous = 0.0, begin
    previous_speeds: tuple[float, ...] | None = tuple(0.0 for _ in joints)
    for index, point in enumerate(trajectory.points):
        span = point.time - previous_time
        if span > 0:
            peaks = peak_speeds(previous, point.positions, previous_speeds, point.velocities, span)
            for joint, cap, peak in zip(joints, caps, peaks, strict=True):
                if cap is not None and peak > cap * (1 + SPEED_SLACK) + 1e-9:
                    return _over(joint, cap, peak, f"the segment to point {index}", rules)
        previous_time, previous, previous_speeds = point.time, point.positions, point.velocities
    return None


def _cap(joint: Joint, rules: ArmRules) -> float | None:
    velocity = joint.limits.velocity
    return None if velocity is None or velocity <= 0 else velocity * rules.speed_scale


def _over(joint: Joint, cap: float, speed: float, where: str, rules: ArmRules) -> ArmRefusal:
    return _refusal(
        f"[arm] speed_scale of {joint.name}",
        f"{where} moves {joint.name} at {_speed(joint, speed)}, faster than {_speed(joint, cap)} "
        f"({rules.speed_scale:g} of its URDF velocity {_speed(joint, joint.limits.velocity or 0.0)}, safety "
        "policy)",
        "Give the points more time (move_arm times a goal itself).",
    )


def _box_refusal(
    trajectory: Trajectory, joints: list[Joint], begin: tuple[float, ...], judged: tuple[ArmScene, ArmRules]
) -> ArmRefusal | None:
    from rosbridge_mcp_server.robot.arm.kinematics import Chain  # noqa: PLC0415 - arm acts only
    from rosbridge_mcp_server.robot.arm.urdf import UrdfError  # noqa: PLC0415 - arm acts only
    from rosbridge_mcp_server.robot.arm_path import MAX_SAMPLES, STEP_RADIANS, path_samples  # noqa: PLC0415 - arm acts only

    scene, rules = judged
    if not rules.configured:
        return None
    robot = scene.robot
    assert robot is not None
    frame = rules.frame or robot.root
    if frame not in robot.links:
        return _refusal(
            "[arm] frame", f"the safety policy's [arm] frame {frame!r} is not a link of the robot"
        )
    samples = path_samples(trajectory, joints, begin)
    if samples is None:
        return _refusal(
            "[arm] path too long to check",
            f"the trajectory's path is longer than {MAX_SAMPLES} samples of {math.degrees(STEP_RADIANS):g}°",
            "Send a shorter motion.",
        )
    moving = {joint.child for joint in _moving_joints(robot, joints)}
    try:
        # One chain from the root to each end effector: its links' origins are the arm's skeleton.
        chains = [Chain(robot, robot.root, tool) for tool in robot.end_effectors()]
        to_frame = None if frame == robot.root else Chain(robot, robot.root, frame)
    except UrdfError as exc:
        return _refusal("[arm] kinematics", f"the arm's kinematics cannot be set up: {exc}")
    held = dict(scene.positions)
    names = [joint.name for joint in joints]
    for sample in samples:
        held.update(zip(names, sample, strict=True))
        try:
            problem = _sample_problem(chains, to_frame, held, moving, rules)
        except UrdfError as exc:
            return _refusal("[arm] kinematics", f"the arm's kinematics failed: {exc}")
        if problem is not None:
            return _refusal(
                f"[arm] {problem}",
                f"{problem} (safety policy, in {frame})",
                "Choose a goal that keeps the arm inside the workspace and out of the keep-out boxes.",
            )
    return None


def _sample_problem(
    chains: list[Chain], to_frame: Chain | None, held: Mapping[str, float], moving: set[str], rules: ArmRules
) -> str | None:
    from rosbridge_mcp_server.robot.arm.kinematics import inverse, transform_point, translation  # noqa: PLC0415 - arm acts only

    base = inverse(to_frame.tip_pose(held)) if to_frame is not None else None
    for chain in chains:
        points: list[tuple[str, Point]] = [(chain.base, (0.0, 0.0, 0.0))]
        points += [(link, translation(pose)) for link, pose in chain.poses(held)]
        if base is not None:
            points = [(link, transform_point(base, point)) for link, point in points]
        problem = _workspace_problem(chain.tip, points[-1][1], rules) or _keep_out_problem(
            points, moving, rules, chain.robot.radii
        )
        if problem is not None:
            return problem
    return None


def _moving_joints(robot: Robot, joints: list[Joint]) -> list[Joint]:
    """Every joint (fixed ones too) whose child link a joint of *joints* moves: the segments to check."""
    moved = {joint.child for joint in joints}
    todo = list(moved)
    while todo:
        for child in robot.child_joints(todo.pop()):
            if child.child not in moved:
                moved.add(child.child)
                todo.append(child.child)
    return [joint for joint in robot.joints if joint.child in moved]


def _workspace_problem(tool: str, point: Point, rules: ArmRules) -> str | None:
    from rosbridge_mcp_server.robot.arm_path import inside_box  # noqa: PLC0415 - arm acts only

    if not rules.workspace or any(inside_box(point, box[1], box[2], rules.margin) for box in rules.workspace):
        return None
    x, y, z = point
    names = ", ".join(name for name, _, _ in rules.workspace)
    return f"the path takes {tool} to ({x:.3f}, {y:.3f}, {z:.3f}) m, outside the workspace ({names})"


def _keep_out_problem(
    points: list[tuple[str, Point]], moving: set[str], rules: ArmRules, radii: Mapping[str, float]
) -> str | None:
    """Each moving link's segment from the link before it on the chain, as a capsule as thick as the thicker
    of its two links (``robot/arm/geometry.py``; ``[arm] link_radius`` where the URDF gives no size), against
    every keep-out box."""
    from rosbridge_mcp_server.robot.arm_path import segment_hits  # noqa: PLC0415 - arm acts only

    for box in rules.keep_out:
        for (before, a), (link, b) in itertools.pairwise(points):
            if link not in moving:
                continue
            radius = max(radii.get(before, rules.link_radius), radii.get(link, rules.link_radius))
            if segment_hits(a, b, box[1], box[2], rules.margin + radius):
                return f"the path takes {link} into the keep-out box {box[0]}"
    return None


def _gripper_refusal(arm: ArmAct, goal: GripperGoal, scene: ArmScene, rules: ArmRules) -> ArmRefusal | None:
    from rosbridge_mcp_server.robot.arm_scene import gripper_joint  # noqa: PLC0415 - arm acts only

    robot = scene.robot
    assert robot is not None
    if goal.joints:
        named = [robot.joint(name) for name in goal.joints]
    else:
        named = [gripper_joint(robot, scene, arm.controller)]
    if any(joint is None for joint in named):
        if not rules.configured and rules.max_gripper_effort is None:
            return None
        return _refusal(
            "[arm] gripper joint unknown",
            f"which joint {arm.target} moves is not known from the robot description",
            "Ask the robot's operator.",
        )
    for joint, value in zip(named, goal.positions, strict=False):
        assert joint is not None
        low, high = joint.limits.lower, joint.limits.upper
        if joint.bounded and low is not None and high is not None and not low <= value <= high:
            return _refusal(
                f"URDF limit of {joint.name}",
                f"the gripper goal puts {joint.name} at {_shown(joint, value)}, outside its URDF limits "
                f"{_shown(joint, low)} … {_shown(joint, high)}",
                "Choose a position within the limits.",
            )
    caps = [j.limits.effort for j in named if j is not None and j.limits.effort]
    if rules.max_gripper_effort is not None:
        caps.append(rules.max_gripper_effort)
    if caps and goal.max_effort is not None:
        cap = min(caps)
        if goal.max_effort > cap or (rules.max_gripper_effort is not None and goal.max_effort <= 0):
            return _refusal(
                "[arm] gripper effort",
                f"the gripper goal asks max_effort {goal.max_effort:g}, beyond {cap:g} (the URDF's effort "
                "limit and the safety policy's max_gripper_effort; 0 would mean no limit)",
                f"Give max_effort between 0 and {cap:g}.",
            )
    return None


#: What the arm judge reads, by the name's last part: writing it would move the limits under the judge.
ARM_SOURCES = {
    "robot_description": "the robot description, whose joint limits the arm's judge reads",
    "robot_description_semantic": "the SRDF, whose named poses move_arm reads",
    "joint_states": "the joint states, from which the arm's judge times the first segment",
}


def source_refusal(act: Act) -> ArmRefusal | None:
    """A write to what the arm judge reads (the URDF on ``…/robot_description``, the parameter of that name,
    ``…/joint_states``), by any tool: refused always, since the URDF's limits always hold."""
    written: list[str] = []
    if act.kind in ("topic", "parameter"):
        written.append(act.name)
    written += [effect.name for effect in act.effects if effect.kind == "parameter" and effect.what == "set"]
    for name in written:
        leaf = name.replace(":", "/").rsplit("/", 1)[-1]
        why = ARM_SOURCES.get(leaf)
        if why is not None:
            return _refusal(
                f"arm source write: {name}",
                f"{act.tool} on {act.name} writes {why}; the URDF's limits always hold, so it may not be "
                "written from here",
                "Tell the user; do not try to reach the same effect another way.",
            )
    return None


def arm_goal_text(act: Act) -> str:
    """Where an arm act sends the arm, for the person asked to confirm it: the last point's positions and
    when it is reached (not where the arm is now, which moves a little between two rounds of a question)."""
    arm = act_arm(act)
    if arm is None or isinstance(arm.body, str):
        return ""
    from rosbridge_mcp_server.robot.arm_scene import ArmScene  # noqa: PLC0415 - arm acts only

    scene = act.scene if isinstance(act.scene, ArmScene) else None
    robot = scene.robot if scene is not None else None
    if isinstance(arm.body, Trajectory):
        last = arm.body.points[-1]
        parts = []
        for name, value in zip(arm.body.joints, last.positions, strict=True):
            joint = robot.joint(name) if robot is not None else None
            parts.append(f"{name} {_shown(joint, value) if joint is not None else f'{value:g}'}")
        return f"Moves the arm to {', '.join(parts)} in {last.time:.1f} s."
    if isinstance(arm.body, GripperGoal):
        effort = f", max effort {arm.body.max_effort:g}" if arm.body.max_effort is not None else ""
        return f"Moves the gripper to {', '.join(f'{p:g}' for p in arm.body.positions)}{effort}."
    switch = arm.body
    return (
        f"Switches the robot's controllers: activates {', '.join(switch.activate) or 'none'}; deactivates "
        f"{', '.join(switch.deactivate) or 'none'}."
    )
