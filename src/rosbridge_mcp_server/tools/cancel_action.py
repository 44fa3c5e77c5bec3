"""``cancel_action``: cancel one goal, or every goal of an action, on ROS 1 and ROS 2."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.goals import CancelReport
from rosbridge_mcp_server.robot.wording import counted
from rosbridge_mcp_server.tools.base import ACTS_ON_ROBOT, ToolAnswer, ToolContext, ToolFailure, ToolSpec

__all__ = ["SPEC", "CancelAnswer", "run"]


class CancelAnswer(BaseModel):
    """What was cancelled."""

    action: str
    goal_id: str | None = Field(description="The goal asked for, or null for every goal of the action")
    canceled_goals: list[str] = Field(
        description="Ids of goals started by publish_action that were cancelled"
    )
    goals_canceling: list[str] | None = Field(
        description=(
            "ROS 2, cancel-all or a goal UUID: ids (hex UUIDs) the action server says it is canceling"
        )
    )
    unknown_goal_id: bool = Field(
        description="The goal id is not one of publish_action's running goals (a cancel was still sent)"
    )
    note: str | None = None


SPEC = ToolSpec(
    name="cancel_action",
    title="Cancel action goals",
    description=(
        'Cancel an action\'s running goals, or one by goal_id. Example: {"action_name": "/fibonacci"}. '
        "A waiting publish_action ends too."
    ),
    hints=ACTS_ON_ROBOT,
    acts_on="action",
    output=CancelAnswer,
)


async def run(
    ctx: ToolContext,
    action_name: Annotated[str, Field(description="e.g. /fibonacci")],
    goal_id: Annotated[
        str | None,
        Field(
            description=(
                "One goal: its id from publish_action (e.g. goal:/fibonacci:0d95c87b-5) or its UUID "
                "(32 hex digits); omit: all goals"
            )
        ),
    ] = None,
) -> ToolAnswer:
    """Send the cancel and report what it reached."""
    from rosbridge_mcp_server.robot.acting import stop_goals  # noqa: PLC0415 - on the first act

    wanted = goal_id.strip() if goal_id is not None and goal_id.strip() else None
    return _answer(await stop_goals(ctx, action=action_name, goal_id=wanted))


def _answer(report: CancelReport) -> ToolAnswer:
    data = CancelAnswer(
        action=report.action,
        goal_id=report.goal_id,
        canceled_goals=list(report.canceled_ours),
        goals_canceling=report.goals_canceling,
        unknown_goal_id=report.unknown_goal_id,
        note=report.note,
    )
    if report.refused is not None:
        raise ToolFailure(
            f"Goal {report.goal_id} on {report.action} was not cancelled: the bridge refused "
            f"({report.refused}). This bridge lets only the connection that started a goal cancel it by that "
            "id. Give the goal's UUID instead (32 hex digits: goal_info.goal_id.uuid in "
            f"{report.action}/_action/status), or omit goal_id to cancel every goal of the action through "
            "its action server."
        )
    if report.goal_id is not None and report.goals_canceling is not None:
        text = f"Asked the action server of {report.action} to cancel goal {report.goal_id}."
        count = len(report.goals_canceling)
        text += (
            " It is canceling that goal."
            if count
            else " It is canceling no goal (that UUID is not one of its running goals)."
        )
    elif report.goal_id is not None:
        text = f"Sent a cancel for goal {report.goal_id} on {report.action}."
        if report.unknown_goal_id:
            text += (
                " That id is not a goal publish_action is running now (it may have finished already, or "
                "belong to another client); the action server ignores a cancel for a goal it does not know."
            )
        else:
            text += " publish_action will report the goal's final status."
    else:
        text = f"Sent a cancel for every goal of {report.action}."
        if report.canceled_ours:
            text += f" Goals started by publish_action: {', '.join(report.canceled_ours)}."
        if report.goals_canceling is not None:
            count = len(report.goals_canceling)
            goals = counted(count, "goal")
            if report.canceled_ours:
                # Our goals' own cancels usually reach the server first, and a goal already being canceled
                # is not listed again: "0 goals" would read as if ours went on.
                text += (
                    f" The action server's answer to the cancel of every goal lists {goals} it began "
                    "canceling (a goal already being canceled, as ours may be, is not listed)."
                )
            else:
                text += f" The action server is canceling {goals}."
        elif not report.canceled_ours:
            text += " None of them was started by publish_action."
    if report.note:
        text += f" Note: {report.note}."
    return ToolAnswer(text=text, data=data)
