"""``view_arm``: the robot's arm as a model needs it — joints and limits, where each joint is now, where the
tool is, the controllers and the named poses. Read-only."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.frames import look_up_transform
from rosbridge_mcp_server.robot.nodes import node_names
from rosbridge_mcp_server.robot.transforms import frame_name
from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolFailure, ToolSpec

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.arm.kinematics import Transform
    from rosbridge_mcp_server.robot.arm.reading import ArmReading
    from rosbridge_mcp_server.robot.arm.urdf import Joint, Robot

__all__ = ["SPEC", "ArmAnswer", "render", "run"]

#: The most end effectors and named poses shown.
MAX_TOOLS = 4
MAX_POSES = 24


class JointView(BaseModel):
    """One joint: its kind, limits and (when heard) its state now; angles in degrees, lengths in metres."""

    name: str
    type: str
    unit: str
    lower: float | None = None
    upper: float | None = None
    max_speed: float | None = None
    position: float | None = None
    velocity: float | None = None
    effort: float | None = None
    at_limit: str | None = None
    mimics: str | None = None


class ToolPose(BaseModel):
    """Where an end effector is (forward kinematics of the joint state), in ``frame``."""

    link: str
    frame: str
    chain: list[str]
    xyz: list[float] | None = None
    rpy_deg: list[float] | None = None
    unknown: str | None = None


class ControllerView(BaseModel):
    name: str
    type: str
    state: str
    joints: list[str]


class NamedPoseView(BaseModel):
    name: str
    group: str
    joints: dict[str, float]


class ArmAnswer(BaseModel):
    """The arm: description, state now, tool poses, controllers, named poses, and what could not be read."""

    robot: str = Field(description="Its name, root link and where the URDF came from")
    joints: list[JointView]
    tools: list[ToolPose]
    controllers: list[ControllerView] | None
    manager: str | None
    named_poses: list[NamedPoseView]
    notes: list[str]


SPEC = ToolSpec(
    name="view_arm",
    title="Arm",
    description=(
        "The arm: joints (limits in deg/m, speeds), positions now, the tool's pose in a frame you name, "
        'controllers, SRDF poses. Read-only. Example: {"frame": "base_link"}.'
    ),
    hints=READS_ROBOT,
    output=ArmAnswer,
)


async def run(
    ctx: ToolContext,
    frame: Annotated[
        str | None,
        Field(
            description="A link (e.g. base_link) or tf frame (e.g. odom); default the arm's base",
            max_length=200,
        ),
    ] = None,
    timeout: Annotated[float, Field(gt=0, le=30, description="Seconds per topic, e.g. 3")] = 3.0,
) -> ToolAnswer:
    """Read the description, joint state, controllers and SRDF, then work out the tool poses."""
    from rosbridge_mcp_server.robot.arm.reading import read_arm  # noqa: PLC0415 - on first use

    reading = await read_arm(ctx.client, ctx.graph, timeout=timeout)
    outside: Transform | None = None
    if frame is not None and frame_name(frame) not in reading.robot.links:
        outside = await _frame_to_root(ctx, frame, reading.robot.root, timeout)
    answer = build_answer(reading, frame_name(frame) if frame is not None else None, outside)
    text = render(answer)
    if MOVE_GROUP in await node_names(ctx.graph):
        text += f"\n{MOVEIT_LINE}"
    return ToolAnswer(text=text, data=answer)


MOVE_GROUP = "/move_group"
#: Said when MoveIt's move_group runs: what move_arm does with it (docs/safety.md, "Arm motion").
MOVEIT_LINE = (
    "MoveIt: /move_group runs. move_arm sends joint goals and named poses, judged here against the URDF "
    "limits and the policy; Cartesian targets are not planned through this server yet."
)


async def _frame_to_root(ctx: ToolContext, frame: str, root: str, timeout: float) -> Transform:
    """*frame* ← the arm's root link, from tf (a frame the description does not have)."""
    from rosbridge_mcp_server.robot.arm.kinematics import from_quaternion  # noqa: PLC0415 - on first use

    name = frame_name(frame)
    if not name:
        raise ToolFailure("frame is empty; give a link of the arm (e.g. base_link) or a tf frame (e.g. odom)")
    found = await look_up_transform(ctx.client, ctx.graph, name, root, timeout=timeout)
    t = found.lookup.transform
    return from_quaternion(t.translation, t.rotation)


# --- the answer --------------------------------------------------------------------------------------------


def _shown(value: float | None, joint: Joint) -> float | None:
    if value is None:
        return None
    return round(value, 4) if joint.linear else round(math.degrees(value), 2)


def build_answer(reading: ArmReading, frame: str | None, outside: Transform | None) -> ArmAnswer:
    """The answer's data from what was read (*outside*: *frame* ← the root link for a tf frame)."""
    from rosbridge_mcp_server.robot.arm.reading import at_limit  # noqa: PLC0415 - on first use

    robot = reading.robot
    state = reading.joint_state
    positions = dict(state.positions) if state else {}
    limits = {name: side for name, side, _ in at_limit(robot, positions)}
    joints = [
        JointView(
            name=j.name,
            type=j.type,
            unit="m" if j.linear else "deg",
            lower=_shown(j.limits.lower, j) if j.bounded else None,
            upper=_shown(j.limits.upper, j) if j.bounded else None,
            max_speed=_shown(j.limits.velocity, j),
            position=_shown(positions.get(j.name), j) if j.mimic is None else None,
            velocity=_shown(state.velocities.get(j.name), j) if state and j.mimic is None else None,
            effort=round(state.efforts[j.name], 3) if state and j.name in state.efforts else None,
            at_limit=limits.get(j.name),
            mimics=j.mimic.joint if j.mimic else None,
        )
        for j in robot.joints
        if j.movable
    ]
    tools = [_tool_pose(robot, link, positions, frame, outside) for link in robot.end_effectors()[:MAX_TOOLS]]
    controllers = None
    if reading.controllers is not None:
        controllers = [
            ControllerView(name=c.name, type=c.type, state=c.state, joints=list(c.joints))
            for c in reading.controllers
        ]
    poses = []
    if reading.semantic is not None:
        for pose in reading.semantic.poses[:MAX_POSES]:
            shown: dict[str, float] = {}
            for name, value in pose.positions.items():
                joint = robot.joint(name)
                shown[name] = (
                    round(value, 4) if joint is None or joint.linear else round(math.degrees(value), 2)
                )
            poses.append(NamedPoseView(name=pose.name, group=pose.group, joints=shown))
    return ArmAnswer(
        robot=f"{robot.name} (root {robot.root}, from {reading.description_source})",
        joints=joints,
        tools=tools,
        controllers=controllers,
        manager=reading.controller_manager,
        named_poses=poses,
        notes=list(reading.notes),
    )


def _chain_base(robot: Robot, link: str) -> str:
    """The link above the first movable joint on the way from the root to *link* (the arm's base)."""
    path = robot.chain(robot.root, link)
    first = next((j for j in path if j.movable), None)
    return first.parent if first is not None else robot.root


def _tool_pose(
    robot: Robot, link: str, positions: dict[str, float], frame: str | None, outside: Transform | None
) -> ToolPose:
    from rosbridge_mcp_server.robot.arm.kinematics import (  # noqa: PLC0415 - on first use
        Chain,
        MissingJointsError,
        compose,
        inverse,
        rpy,
        translation,
    )

    base = _chain_base(robot, link)
    chain = Chain(robot, base, link)
    movable = [j.name for j in chain.joints if j.movable and j.mimic is None]
    shown_frame = frame or base
    try:
        if frame is None:
            pose = chain.tip_pose(positions)
        else:
            in_root = Chain(robot, robot.root, link).tip_pose(positions)
            if outside is not None:
                pose = compose(outside, in_root)
            else:
                pose = compose(inverse(Chain(robot, robot.root, frame).tip_pose(positions)), in_root)
    except MissingJointsError as exc:
        return ToolPose(link=link, frame=shown_frame, chain=movable, unknown=str(exc))
    roll, pitch, yaw = rpy(pose)
    return ToolPose(
        link=link,
        frame=shown_frame,
        chain=movable,
        xyz=[round(v, 4) + 0.0 for v in translation(pose)],
        rpy_deg=[round(math.degrees(a), 1) + 0.0 for a in (roll, pitch, yaw)],
    )


# --- the text ----------------------------------------------------------------------------------------------


def _g(value: float | None) -> str:
    return "?" if value is None else f"{value:g}"


def _joint_line(joint: JointView) -> str:
    if joint.mimics:
        return f"- {joint.name}: {joint.type}, mimics {joint.mimics}"
    unit = joint.unit if joint.unit == "m" else "°"
    where = "position unknown" if joint.position is None else f"at {joint.position:g}{unit}"
    limits = f"[{_g(joint.lower)}, {_g(joint.upper)}]{unit}" if joint.lower is not None else "no limits"
    speed = f"max {_g(joint.max_speed)}{unit}/s" if joint.max_speed is not None else "no speed limit"
    moving = f", moving {joint.velocity:g}{unit}/s" if joint.velocity else ""
    flag = f"  ← AT ITS {joint.at_limit.upper()} LIMIT" if joint.at_limit else ""
    return f"- {joint.name}: {joint.type} {where}{moving}; {limits}, {speed}{flag}"


def _tool_line(tool: ToolPose) -> str:
    if tool.xyz is None or tool.rpy_deg is None:
        return f"- {tool.link} in {tool.frame}: unknown ({tool.unknown})"
    x, y, z = tool.xyz
    roll, pitch, yaw = tool.rpy_deg
    return (
        f"- {tool.link} in {tool.frame}: x={x:g} y={y:g} z={z:g} m, roll={roll:g}° pitch={pitch:g}° "
        f"yaw={yaw:g}°; chain {', '.join(tool.chain) or 'no movable joint'}"
    )


def render(answer: ArmAnswer) -> str:
    """The answer as text: one line per joint, per tool, per controller; the named poses on one line each."""
    moving = [j for j in answer.joints if not j.mimics]
    if not moving:
        lines = [
            f"No arm on robot {answer.robot}: its robot description has no movable joint, so this robot "
            "publishes no arm to show or move (the built-in simulated robot has one with --demo "
            "--demo-world arm)."
        ]
    else:
        lines = [
            f"Arm of robot {answer.robot}: {len(moving)} movable joints. Angles in degrees, lengths in "
            "metres.",
            "Joints (position now; [lower, upper]; max speed):",
            *(_joint_line(j) for j in answer.joints),
            "End effectors (forward kinematics of the joint state):",
            *(_tool_line(t) for t in answer.tools),
        ]
    if moving and not answer.tools:
        lines.append("- none: no link lies below two or more movable joints (this robot has no arm)")
    if answer.controllers is not None:
        lines.append(f"Controllers ({answer.manager}):")
        lines += [
            f"- {c.name}: {c.state.upper() if c.state != 'active' else 'active'} ({c.type})"
            + (f", joints {', '.join(c.joints)}" if c.joints else "")
            for c in answer.controllers
        ]
    if answer.named_poses:
        lines.append("Named poses (SRDF):")
        lines += [
            f"- {p.name} ({p.group}): " + ", ".join(f"{name} {value:g}" for name, value in p.joints.items())
            for p in answer.named_poses
        ]
    if answer.notes:
        lines.append("Not read: " + "; ".join(answer.notes) + ".")
    return "\n".join(lines)
