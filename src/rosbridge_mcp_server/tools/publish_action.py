"""``publish_action``: send an action goal, stream its feedback as progress, wait for its result."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.goals import UNCONFIRMED_STATUS, Goal
from rosbridge_mcp_server.robot.messages import compact_json
from rosbridge_mcp_server.tools.arguments import NO_FIELDS, JsonObject
from rosbridge_mcp_server.tools.base import (
    ACTS_ON_ROBOT,
    LongWork,
    ToolAnswer,
    ToolContext,
    ToolSpec,
)

__all__ = ["MAX_GOAL_TIMEOUT", "SPEC", "GoalAnswer", "run"]

MAX_GOAL_TIMEOUT = 3600.0
_EXAMPLE = '{"order": 5}'

_CANCELLED_BY = {
    "timeout": "it was cancelled because it did not finish within the timeout",
    "request_cancelled": "it was cancelled because the tool call was cancelled",
    "cancel_action": "it was cancelled by cancel_action",
    "stop_robot": "it was cancelled by stop_robot",
    "estop": "it was cancelled by E-STOP on the operator console",
}


class GoalAnswer(BaseModel):
    """How a goal ended."""

    goal_id: str = Field(description="The goal's id; pass it to cancel_action to cancel this goal")
    action: str
    action_type: str
    status: str = Field(
        description=(
            'Final status in words: succeeded, canceled, aborted, ...; "timed out" when the goal outlived '
            "the timeout and the robot never confirmed its end after the cancel"
        )
    )
    status_code: int = Field(description="Final status number in the bridge's own numbering")
    succeeded: bool
    result: dict[str, Any] | None = Field(description="The action's result message (null when none came)")
    feedback_count: int = Field(description="How many feedback messages arrived")
    last_feedback: list[dict[str, Any]] = Field(description="The last few feedback messages, oldest first")
    canceled_by: str | None = Field(
        description='"timeout", "request_cancelled", "cancel_action", "stop_robot", "estop" or null'
    )


SPEC = ToolSpec(
    name="publish_action",
    title="Run an action goal",
    description=(
        "Send a goal to an action server and wait for its result; can move the robot. Example: action_name "
        f"/fibonacci, action_type example_interfaces/action/Fibonacci, goal {_EXAMPLE}. Feedback comes as "
        "progress; on timeout the goal is cancelled."
    ),
    hints=ACTS_ON_ROBOT,
    acts_on="action",
    output=GoalAnswer,
    long_work=LongWork(cancelled="its goal was cancelled on the robot"),
)


async def run(
    ctx: ToolContext,
    action_name: Annotated[str, Field(description="e.g. /fibonacci")],
    action_type: Annotated[
        str,
        Field(description=("e.g. example_interfaces/action/Fibonacci (ROS 1: pkg/NameAction)")),
    ],
    goal: Annotated[
        JsonObject,
        Field(description=f"Goal fields as a JSON object, e.g. {_EXAMPLE}; {{}} for an empty goal"),
    ] = NO_FIELDS,
    timeout: Annotated[
        float,
        Field(
            gt=0,
            le=MAX_GOAL_TIMEOUT,
            description=("Seconds to wait before cancelling, e.g. 30"),
        ),
    ] = 30.0,
) -> ToolAnswer:
    """Check the goal, run it (feedback → progress), and describe how it ended."""
    from rosbridge_mcp_server.robot.acting import send_goal  # noqa: PLC0415 - on the first act

    body = goal

    # Every progress message names the goal: a client can cancel it by id while this call still waits.
    async def on_feedback(running: Goal, feedback: dict[str, Any]) -> None:
        index = running.feedback_count
        message = f"goal {running.goal_id} feedback {index}: {compact_json(feedback, 300)}"
        await ctx.report_progress(float(index), None, message)

    outcome = await send_goal(
        ctx,
        tool=SPEC.name,
        action=action_name,
        action_type=action_type,
        goal=body,
        timeout=timeout,
        on_feedback=on_feedback,
    )
    return _answer(outcome)


def _answer(outcome: Goal) -> ToolAnswer:
    wire_type = outcome.action_type
    last = list(outcome.last_feedback)
    data = GoalAnswer(
        goal_id=outcome.goal_id,
        action=outcome.action,
        action_type=wire_type,
        status=outcome.status,
        status_code=outcome.status_code,
        succeeded=outcome.succeeded,
        result=outcome.result,
        feedback_count=outcome.feedback_count,
        last_feedback=last,
        canceled_by=outcome.canceled_by,
    )
    lines = [f"Goal {outcome.goal_id} on {outcome.action} ({wire_type}): {outcome.status}."]
    if outcome.status == UNCONFIRMED_STATUS:
        # The cancel went out but no final status came back (a frozen action server or bridge): "it was
        # cancelled" would be a guess. A real 0.11.17 bridge with its action server under SIGSTOP ended the
        # goal only after SIGCONT.
        lines[0] = lines[0][:-1] + (
            "; it did not finish within the timeout, so a cancel was sent, but the robot has not confirmed "
            "that the goal ended: it may still be running. Call cancel_action for it, or check the robot."
        )
    elif outcome.canceled_by is not None:
        lines[0] = lines[0][:-1] + f"; {_CANCELLED_BY.get(outcome.canceled_by, outcome.canceled_by)}."
    lines.append(f"Result: {compact_json(outcome.result)}")
    if outcome.feedback_count:
        lines.append(
            f"Feedback: {outcome.feedback_count} messages; last {len(last)}: {compact_json(last, 400)}"
        )
    else:
        lines.append("Feedback: none.")
    return ToolAnswer(text="\n".join(lines), data=data)
