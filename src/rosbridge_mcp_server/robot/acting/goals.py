"""Action goals (:func:`send_goal`: checked, approved, run until they end; :func:`require_action_server`) and
their cancels (:func:`stop_goals`: a cancel only stops what the robot does, so the guard is not asked)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import Advice, NotSentError
from rosbridge_mcp_server.robot.acting.context import Acting, as_read, given_name, motion_scene
from rosbridge_mcp_server.robot.approval import Act, approved, carry_out
from rosbridge_mcp_server.robot.goals import CancelReport, Goal, GoalFeedback, cancel_goals, run_goal
from rosbridge_mcp_server.robot.messages import require_fit
from rosbridge_mcp_server.robot.names import absolute_name, check_name_for_ros

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.arm_scene import ArmScene
    from rosbridge_mcp_server.robot.graph import RosGraph
    from rosbridge_mcp_server.robot.navigation import Scene

__all__ = ["require_action_server", "send_goal", "stop_goals"]


async def send_goal(
    ctx: Acting,
    *,
    tool: str,
    action: str,
    action_type: str,
    goal: dict[str, Any],
    timeout: float,
    on_feedback: GoalFeedback | None = None,
    scene: Scene | ArmScene | None = None,
) -> Goal:
    """Check the goal against the action server's type, run it until it ends, and return how it ended.

    *on_feedback* gets the running goal (``goal_id``, ``feedback_count``) and each feedback, so that a caller
    can name the goal (to cancel it) while it runs. The goal is tracked (seen by stop_robot and the E-STOP)
    from before anything of it is sent; right before the goal itself is sent, the send gate is asked, and a
    goal whose cancel or timeout came first is not sent at all. A motion goal (``robot/motion_goals.py``) is
    judged with the robot's map and pose: *scene* when the caller learnt them, else they are learnt here (as
    for a goal carried by a topic or a service), so that the guard judges a goal the same whichever tool and
    carrier sends it.
    """
    ticket = ctx.gate.ticket()  # a stop from now on voids this goal
    name = absolute_name(action, "action")
    dialect = await ctx.graph.dialect()
    check_name_for_ros(name, "action", dialect.version)
    wire_type = dialect.action_type(action_type)
    await require_action_server(ctx.graph, name, action_type)
    typedefs = await ctx.graph.action_goal_typedefs(action_type)
    if typedefs:
        require_fit(
            as_read(dialect, goal),
            typedefs,
            ros_version=dialect.version,
            nothing_sent="No goal was sent",
            looks_like="A goal",
        )

    if scene is None:
        scene = await motion_scene(ctx, "action", name, wire_type, goal)
    act = await approved(
        ctx, Act(tool, "action", name, wire_type, goal, given=given_name(action, name), scene=scene)
    )
    outcome: Goal = await carry_out(
        ctx,
        act,
        lambda: run_goal(
            ctx.goals,
            act.name,
            action_type,
            act.payload,
            timeout=timeout,
            on_feedback=on_feedback,
            before_send=lambda: ctx.gate.check(ticket, act),
        ),
    )
    return outcome


async def require_action_server(graph: RosGraph, name: str, action_type: str | None = None) -> None:
    """Fail fast on an action nobody serves, or (given *action_type*) on a type that is not the server's."""
    hint = await graph.missing_action(name)
    if hint is not None:
        raise NotSentError(f"No action server {name} is running on the robot.{hint}").advise(Advice.ACTIONS)
    if action_type is None:
        return
    found = await graph.action_type(name)
    if found is None:
        return
    if not Dialect.same_action(found, action_type):
        raise NotSentError(
            f"Action {name} has type {found}, not {action_type}. Send a goal of type {found} instead."
        )


async def stop_goals(ctx: Acting, *, action: str, goal_id: str | None = None) -> CancelReport:
    """Cancel one goal of *action* (by id) or all of them, after checking that the action is served.

    A cancel only stops what the robot does, so it does not ask the guard.
    """
    name = absolute_name(action, "action")
    hint = await ctx.graph.missing_action(name)
    if hint is not None:
        raise NotSentError(
            f"No action server {name} is running on the robot, so there is nothing to cancel.{hint}"
        ).advise(Advice.ACTIONS)
    return await cancel_goals(ctx.goals, name, goal_id)
