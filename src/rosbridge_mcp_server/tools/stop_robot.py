"""``stop_robot``: the e-stop for what this server started (streams, velocity commands, its goals)."""

from __future__ import annotations

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.approval import Act
from rosbridge_mcp_server.safety.estop import emergency_stop
from rosbridge_mcp_server.tools.base import ToolAnswer, ToolContext, ToolHints, ToolSpec

__all__ = ["SPEC", "StopAnswer", "run"]


class StopAnswer(BaseModel):
    """What stop_robot did."""

    streams_stopped: list[str] = Field(description="Topics whose streams ended")
    streams_still_running: list[str] = Field(description="Topics whose streams did not end in time")
    zeroed_topics: list[str] = Field(description="Topics that got one zero velocity command")
    held_topics: list[str] = Field(
        default_factory=list, description="Trajectory topics that got a trajectory holding the joints"
    )
    zeros_owed: list[str] = Field(
        default_factory=list,
        description="Velocity topics whose zero could not be sent (not connected): sent once it is back",
    )
    goals_cancelled: list[str] = Field(
        description="Each goal (or every goal of an action) cancelled, and what the robot answered"
    )
    failures: list[str]


SPEC = ToolSpec(
    name="stop_robot",
    title="Stop what this server started",
    description=(
        "Emergency stop for what this server started: ends streams, sends zero velocity, holds trajectories, "
        "cancels goals. "
        "Never asks; call it with {} whenever the robot must stop."
    ),
    # It acts on the robot, but only ever takes motion away; repeating it is harmless.
    hints=ToolHints(read_only=False, destructive=False, idempotent=True),
    acts_on="topic",
    stops=True,
    every_robot=True,
    output=StopAnswer,
)


async def run(ctx: ToolContext) -> ToolAnswer:
    """Stop the streams, zero the velocity topics, cancel the goals, and say what was done."""
    report = await emergency_stop(ctx.robot, by="stop_robot")
    # Stopping is never put to the policy; each stop that went out is still audited.
    for topic, type_name, message in report.zero_messages:
        ctx.guard.record(Act(SPEC.name, "topic", topic, type_name, message, caller=ctx.caller), "e-stop")
    for action, goal_id in report.goals:
        ctx.guard.record(
            Act(SPEC.name, "action", action, "", {"cancel": goal_id or "all"}, caller=ctx.caller), "e-stop"
        )
    if not report.did_anything:
        ctx.guard.record(Act(SPEC.name, "topic", "", "", None, caller=ctx.caller), "e-stop: nothing to stop")
    data = StopAnswer(
        streams_stopped=report.streams_stopped,
        streams_still_running=report.streams_still_running,
        zeroed_topics=report.zeroed_topics,
        held_topics=report.held_topics,
        zeros_owed=report.zeros_owed,
        goals_cancelled=report.cancel_lines(),
        failures=report.failures,
    )
    return ToolAnswer(text=_text(data), data=data)


def _text(data: StopAnswer) -> str:
    lines = []
    if data.streams_stopped:
        lines.append(
            f"Ended {len(data.streams_stopped)} publish stream(s) on {', '.join(data.streams_stopped)}."
        )
    if data.streams_still_running:
        lines.append(
            f"Stream(s) on {', '.join(data.streams_still_running)} did not end in time; call stop_robot "
            "again."
        )
    if data.zeroed_topics:
        lines.append(f"Published a zero velocity command on {', '.join(data.zeroed_topics)}.")
    if data.held_topics:
        lines.append(
            f"Stopped the trajectory on {', '.join(data.held_topics)}: the joints hold where they are."
        )
    lines.extend(f"Cancelled {cancel}." for cancel in data.goals_cancelled)
    if data.zeros_owed:
        lines.append(
            f"No zero velocity command could be sent on {', '.join(data.zeros_owed)} (not connected); each "
            "goes out once the connection is back."
        )
    if not lines:
        lines.append(
            "Nothing to stop: this server has no running stream, has started no goal it has not cancelled "
            "since, and has sent no velocity command in this session."
        )
    lines.extend(data.failures)
    return "\n".join(lines)
