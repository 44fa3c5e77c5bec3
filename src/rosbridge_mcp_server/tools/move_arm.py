"""``move_arm``: move a manipulator's joints to a goal (by joint, absolute or relative, or a named SRDF pose),
sent as a ``FollowJointTrajectory`` goal to the controller that moves those joints, timed from the URDF speeds
and the policy's ``[arm] speed_scale`` (never by the model), and judged by the guard like every arm motion."""

from __future__ import annotations

import asyncio
import math
from typing import TYPE_CHECKING, Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.errors import PolicyRefusal
from rosbridge_mcp_server.robot.goals import UNCONFIRMED_STATUS, Goal
from rosbridge_mcp_server.robot.messages import compact_json
from rosbridge_mcp_server.tools.arguments import FROM_JSON_TEXT
from rosbridge_mcp_server.tools.base import (
    ACTS_ON_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolImage,
    ToolSpec,
)

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.arm_plan import ArmPlan
    from rosbridge_mcp_server.robot.arm_scene import ArmScene

__all__ = ["SPEC", "ArmAnswer", "run"]

_READY_WAIT = 3.0
_MAX_TIMEOUT = 600.0
#: How long after the motion's own duration the goal may take before it is cancelled.
_SLACK = 10.0
#: The controller's action type: ROS 2's, and ROS 1's.
_TRAJECTORY_ACTION = "control_msgs/action/FollowJointTrajectory"
_TRAJECTORY_ACTION_ROS1 = "control_msgs/FollowJointTrajectoryAction"
_EXAMPLE = '{"joints": {"elbow_joint": 45}}'

_CANCELLED_BY = {
    "timeout": "cancelled: it did not finish within the timeout",
    "request_cancelled": "cancelled because the tool call was cancelled",
    "cancel_action": "cancelled by cancel_action",
    "stop_robot": "cancelled by stop_robot",
    "estop": "cancelled by E-STOP on the operator console",
}


class ArmAnswer(BaseModel):
    """How the motion ended (degrees; m)."""

    goal_id: str
    status: str
    succeeded: bool
    target: dict[str, float]
    final: dict[str, float] | None
    largest_error: float | None
    canceled_by: str | None


SPEC = ToolSpec(
    name="move_arm",
    title="Move the arm",
    description=(
        f"Move arm joints (DEGREES; prismatic m) or to an SRDF pose, within URDF limits. Example: {_EXAMPLE}"
    ),
    hints=ACTS_ON_ROBOT,
    acts_on="action",
    output=ArmAnswer,
)


def _targets(scene: ArmScene, joints: dict[str, Any], relative: bool) -> dict[str, float]:
    from rosbridge_mcp_server.robot.arm_plan import to_si  # noqa: PLC0415 - on first use

    robot = scene.robot
    assert robot is not None
    out: dict[str, float] = {}
    for name, value in joints.items():
        joint = robot.joint(name)
        if joint is None or not joint.movable or joint.mimic is not None:
            movable = ", ".join(j.name for j in robot.movable_joints)
            raise ToolFailure(
                f"{name!r} is not a movable joint of the arm. Its joints: {movable}. Nothing was sent."
            )
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise ToolFailure(f"joints.{name} must be a finite number (degrees or metres), not {value!r}.")
        target = to_si(joint, float(value))
        if relative:
            now = scene.positions.get(name)
            if now is None:
                raise ToolFailure(
                    f"where {name} is now was not read from /joint_states, so a relative move "
                    "cannot be placed. Nothing was sent."
                )
            target += now
        out[name] = target
    return out


def _named_pose(scene: ArmScene, pose: str) -> dict[str, float]:
    if scene.semantic is None:
        raise ToolFailure(
            f"No named pose {pose!r}: the robot has no SRDF (no /robot_description_semantic, no move_group). "
            "Give joints instead. Nothing was sent."
        )
    found = scene.semantic.pose(pose)
    if found is None:
        known = ", ".join(sorted({p.name for p in scene.semantic.poses})) or "none"
        raise ToolFailure(f"No named pose {pose!r} in the SRDF. Known poses: {known}. Nothing was sent.")
    return dict(found.positions)


async def run(
    ctx: ToolContext,
    *,
    joints: Annotated[
        dict[str, float] | None,
        Field(description='e.g. {"elbow_joint": 45}'),
        FROM_JSON_TEXT,
    ] = None,
    pose: Annotated[str, Field(description='SRDF pose, e.g. "home"')] = "",
    relative: Annotated[bool, Field(description="e.g. true: add to now")] = False,
    controller: Annotated[str, Field(description="e.g. arm_controller")] = "",
    timeout: Annotated[float, Field(gt=0, le=_MAX_TIMEOUT, description="Seconds, e.g. 60")] = 60.0,
) -> ToolAnswer:
    """Resolve the goal, plan its timing, send it, report progress, say where the arm ended."""
    from rosbridge_mcp_server.robot.acting import send_goal  # noqa: PLC0415 - on the first act

    if bool(joints) == bool(pose.strip()):
        raise ToolFailure(
            f"Give joints or a named pose, not both or neither, e.g. {_EXAMPLE}. Nothing was sent."
        )
    if pose.strip() and relative:
        raise ToolFailure("relative applies to joints, not to a named pose. Nothing was sent.")
    scene = await _learnt_arm(ctx)
    targets = _named_pose(scene, pose.strip()) if pose.strip() else _targets(scene, joints or {}, relative)
    dialect = await ctx.client.dialect()
    plan = _planned(ctx, scene, targets, controller=controller, timeout=timeout, ros_version=dialect.version)
    action_type = _TRAJECTORY_ACTION_ROS1 if dialect.version == 1 else _TRAJECTORY_ACTION

    async def on_feedback(running: Goal, feedback: dict[str, Any]) -> None:
        actual = feedback.get("actual") if isinstance(feedback, dict) else None
        where = actual.get("positions") if isinstance(actual, dict) else None
        text = f"goal {running.goal_id}: moving ({plan.duration:.1f} s planned)"
        if isinstance(where, list) and len(where) == len(plan.joints):
            text += ": " + ", ".join(
                f"{name} {value:.3g}"
                for name, value in zip(plan.joints, _in_units(scene, plan, where), strict=True)
            )
        await ctx.report_progress(float(running.feedback_count), None, text)

    try:
        outcome = await send_goal(
            ctx,
            tool=SPEC.name,
            action=plan.action,
            action_type=action_type,
            goal=plan.goal,
            timeout=min(timeout, plan.duration + _SLACK),
            on_feedback=on_feedback,
            scene=scene,
        )
    except PolicyRefusal as exc:
        picture = await _picture(ctx, scene, plan)
        raise _Refused(
            f"{exc} The picture shows the arm now (grey) and at the goal (magenta).", picture
        ) from None
    answer = await _answer(ctx, scene, plan, outcome)
    return ToolAnswer(text=answer.text, data=answer.data, images=_images(await _picture(ctx, scene, plan)))


async def _learnt_arm(ctx: ToolContext) -> ArmScene:
    """The arm as the robot describes it now, or a worded failure when it has none that moves."""
    from rosbridge_mcp_server.robot.arm_scene import learn_arm  # noqa: PLC0415 - on first use

    scene = await learn_arm(ctx.client, ctx.graph, timeout=_READY_WAIT)
    if scene.robot is None:
        raise ToolFailure(f"The arm cannot be moved: {'; '.join(scene.problems)}. Nothing was sent.")
    if not scene.robot.movable_joints:
        raise ToolFailure(
            f"The robot description ({scene.robot.name}) has no movable joint: this robot has no arm. "
            "Nothing was sent."
        )
    return scene


def _planned(
    ctx: ToolContext,
    scene: ArmScene,
    targets: dict[str, float],
    *,
    controller: str,
    timeout: float,
    ros_version: int,
) -> ArmPlan:
    """The motion to *targets* planned at the policy's speed scale, refused when it cannot finish in time."""
    from rosbridge_mcp_server.robot.arm_plan import PlanError, plan_motion  # noqa: PLC0415 - on first use

    assert scene.robot is not None  # _learnt_arm's
    try:
        plan = plan_motion(
            scene.robot,
            scene.positions,
            targets,
            controllers=scene.controllers,
            controller=controller.strip() or None,
            speed_scale=ctx.config.policy.arm.speed_scale,
            ros_version=ros_version,
        )
    except PlanError as exc:
        raise ToolFailure(f"The arm cannot be moved: {exc}. Nothing was sent.") from None
    if plan.duration + 1.0 > timeout:
        raise ToolFailure(
            f"The motion takes {plan.duration:.1f} s at the allowed speed, longer than the timeout "
            f"{timeout:g} s. Give a longer timeout. Nothing was sent."
        )
    return plan


class _Refused(ToolFailure):
    """A refused motion, with the side view that shows why."""

    def __init__(self, text: str, image: bytes | None) -> None:
        super().__init__(text)
        self.images = _images(image)


def _images(image: bytes | None) -> tuple[ToolImage, ...]:
    return (ToolImage(image, "image/png"),) if image is not None else ()


async def _picture(ctx: ToolContext, scene: ArmScene, plan: ArmPlan) -> bytes | None:
    """The arm at the start and at the goal, from the side, with the policy's boxes."""
    from rosbridge_mcp_server.pictures.arm import draw_arm  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.pictures.drawing import png_bytes  # noqa: PLC0415 - on first use

    robot = scene.robot
    if robot is None:
        return None
    rules = ctx.config.policy.arm
    goal = {**scene.positions, **dict(zip(plan.joints, plan.target, strict=True))}

    def draw() -> bytes:
        image = draw_arm(
            robot,
            scene.positions,
            goal,
            frame=rules.frame,
            workspace=rules.workspace,
            keep_out=rules.keep_out,
        )
        return png_bytes(image)

    return await asyncio.to_thread(draw)


def _in_units(scene: ArmScene, plan: ArmPlan, values: list[Any]) -> list[float]:
    from rosbridge_mcp_server.robot.arm_plan import shown  # noqa: PLC0415 - on first use

    robot = scene.robot
    assert robot is not None
    out = []
    for name, value in zip(plan.joints, values, strict=True):
        joint = robot.joint(name)
        number = float(value) if isinstance(value, int | float) else math.nan
        out.append(shown(joint, number) if joint is not None else number)
    return out


async def _answer(ctx: ToolContext, scene: ArmScene, plan: ArmPlan, outcome: Goal) -> ToolAnswer:
    from rosbridge_mcp_server.robot.arm_scene import positions_now  # noqa: PLC0415 - on first use

    now = await positions_now(ctx.client, ctx.graph, _READY_WAIT)
    target = dict(zip(plan.joints, _in_units(scene, plan, list(plan.target)), strict=True))
    final = None
    error = None
    if all(name in now for name in plan.joints):
        final = dict(zip(plan.joints, _in_units(scene, plan, [now[n] for n in plan.joints]), strict=True))
        error = round(max(abs(final[n] - target[n]) for n in plan.joints), 4)
    result = outcome.result if isinstance(outcome.result, dict) else {}
    data = ArmAnswer(
        goal_id=outcome.goal_id,
        status=outcome.status,
        succeeded=outcome.succeeded,
        target=target,
        final=final,
        largest_error=error,
        canceled_by=outcome.canceled_by,
    )
    lines = [f"Goal {outcome.goal_id} on {outcome.action}: {outcome.status} (timed {plan.duration:.1f} s)."]
    if outcome.status == UNCONFIRMED_STATUS:
        lines[0] = (
            lines[0][:-1] + "; the robot has not confirmed that it ended: call stop_robot, or check it."
        )
    elif outcome.canceled_by is not None:
        lines[0] = lines[0][:-1] + f"; {_CANCELLED_BY.get(outcome.canceled_by, outcome.canceled_by)}."
    if not outcome.succeeded and result:
        lines.append(f"Result: {compact_json(result, 300)}")
    lines.append(f"Target: {_listed(target)}")
    if final is not None:
        lines.append(f"Now: {_listed(final)} (largest error {error:g})")
    else:
        lines.append("Now: /joint_states did not say.")
    return ToolAnswer(text="\n".join(lines), data=data)


def _listed(values: dict[str, float]) -> str:
    return ", ".join(f"{name} {value:g}" for name, value in values.items())
