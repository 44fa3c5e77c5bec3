"""``move_gripper``: open or close a gripper, or move it to a position, with a most effort, as a
``GripperCommand`` (or ``ParallelGripperCommand``) goal, judged by the guard like every arm motion."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.goals import Goal
from rosbridge_mcp_server.robot.messages import compact_json
from rosbridge_mcp_server.tools.base import ACTS_ON_ROBOT, ToolAnswer, ToolContext, ToolFailure, ToolSpec

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.arm.urdf import Joint

__all__ = ["SPEC", "GripperAnswer", "run"]

_READY_WAIT = 3.0
_MAX_TIMEOUT = 120.0
DEFAULT_ACTION = "/gripper_controller/gripper_cmd"


class GripperAnswer(BaseModel):
    """How the gripper goal ended (m)."""

    goal_id: str
    status: str
    succeeded: bool
    position: float | None
    reached_goal: bool | None
    canceled_by: str | None


SPEC = ToolSpec(
    name="move_gripper",
    title="Move the gripper",
    description=('Open, close or set the gripper (m) within URDF limits. Example: {"command": "close"}'),
    hints=ACTS_ON_ROBOT,
    acts_on="action",
    output=GripperAnswer,
)


def _target(joint: Joint | None, command: str, position: float | None) -> float:
    if position is not None:
        if not math.isfinite(position):
            raise ToolFailure(f"position must be a finite number of metres, not {position!r}.")
        return position
    if joint is None or joint.limits.lower is None or joint.limits.upper is None:
        raise ToolFailure(
            f"The gripper's joint and its limits are not known from the robot description, so {command!r} "
            "cannot be placed; give position in metres. Nothing was sent."
        )
    return joint.limits.upper if command == "open" else joint.limits.lower


async def _action_type(ctx: ToolContext, action: str) -> str:
    found = await ctx.graph.action_type(action)
    if found and "ParallelGripperCommand" in found:
        return found
    dialect = await ctx.client.dialect()
    return (
        "control_msgs/GripperCommandAction" if dialect.version == 1 else "control_msgs/action/GripperCommand"
    )


async def run(
    ctx: ToolContext,
    *,
    command: Annotated[Literal["open", "close", ""], Field(description='e.g. "open"')] = "",
    position: Annotated[float | None, Field(description="Metres, e.g. 0.02")] = None,
    max_effort: Annotated[float | None, Field(ge=0, description="Newtons, e.g. 10")] = None,
    action: Annotated[str, Field(description=f"e.g. {DEFAULT_ACTION}")] = "",
    timeout: Annotated[float, Field(gt=0, le=_MAX_TIMEOUT, description="s, e.g. 20")] = 20.0,
) -> ToolAnswer:
    """Resolve the target from the URDF, send the goal, report how it ended."""
    from rosbridge_mcp_server.robot.acting import send_goal  # noqa: PLC0415 - on the first act
    from rosbridge_mcp_server.robot.arm_scene import gripper_joint, learn_arm  # noqa: PLC0415 - on first use

    if bool(command) == (position is not None):
        raise ToolFailure('Give command ("open" or "close") or position (metres), not both or neither.')
    name = action.strip() or DEFAULT_ACTION
    name = name if name.startswith("/") else f"/{name}"
    scene = await learn_arm(ctx.client, ctx.graph, timeout=_READY_WAIT)
    joint = gripper_joint(scene.robot, scene, name.rsplit("/", 1)[0]) if scene.robot is not None else None
    target = _target(joint, command, position)
    effort = max_effort
    if effort is None:
        effort = ctx.config.policy.arm.max_gripper_effort
    if effort is None and joint is not None and joint.limits.effort:
        effort = joint.limits.effort
    action_type = await _action_type(ctx, name)
    goal: dict[str, Any]
    if "ParallelGripperCommand" in action_type:
        goal = {
            "command": {
                "name": [joint.name] if joint is not None else [],
                "position": [target],
                "effort": [effort or 0.0],
            }
        }
    else:
        goal = {"command": {"position": target, "max_effort": effort or 0.0}}

    async def on_feedback(running: Goal, feedback: dict[str, Any]) -> None:
        where = feedback.get("position") if isinstance(feedback, dict) else None
        text = f"goal {running.goal_id}: gripper at {where:.4g}" if isinstance(where, int | float) else ""
        await ctx.report_progress(
            float(running.feedback_count), None, text or f"goal {running.goal_id}: moving"
        )

    outcome = await send_goal(
        ctx,
        tool=SPEC.name,
        action=name,
        action_type=action_type,
        goal=goal,
        timeout=timeout,
        on_feedback=on_feedback,
        scene=scene,
    )
    return _answer(outcome, joint, target)


def _answer(outcome: Goal, joint: Joint | None, target: float) -> ToolAnswer:
    result = outcome.result if isinstance(outcome.result, dict) else {}
    position = result.get("position")
    reached = result.get("reached_goal")
    data = GripperAnswer(
        goal_id=outcome.goal_id,
        status=outcome.status,
        succeeded=outcome.succeeded,
        position=float(position) if isinstance(position, int | float) else None,
        reached_goal=reached if isinstance(reached, bool) else None,
        canceled_by=outcome.canceled_by,
    )
    lines = [f"Gripper goal {outcome.goal_id} on {outcome.action}: {outcome.status} (target {target:g})."]
    if outcome.canceled_by is not None:
        lines[0] = lines[0][:-1] + f"; cancelled by {outcome.canceled_by}."
    lines.append(f"Result: {compact_json(result, 300)}")
    return ToolAnswer(text="\n".join(lines), data=data)
