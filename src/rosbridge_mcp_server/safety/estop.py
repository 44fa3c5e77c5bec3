"""The e-stop: streams ended, velocity topics zeroed, joint trajectories held, goals cancelled.

Both stops cancel every goal this server caused, by any carrier (``robot/goals/stopping.py``); the operator's
E-STOP (the console) also cancels every goal of the robot's known motion action servers, whoever sent it.
``stop_robot``, the model's stop, reaches only what this server caused: see docs/safety.md for why.

It asks no one and consults no policy: stopping must always be possible, and each step only takes motion away.
Every step is tried even when an earlier one failed (a dropped connection must not keep the streams running).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Final, Literal, get_args

from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.arm_stop import stop_trajectories
from rosbridge_mcp_server.robot.goals import CanceledBy
from rosbridge_mcp_server.robot.goals.stopping import Cancelled, cancel_caused, cancel_motion_servers, summary
from rosbridge_mcp_server.robot.velocity import zero_command

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.session import RobotSession

__all__ = [
    "HANDLED_SECONDS",
    "PRESSER_NAMES",
    "STREAM_STOP_SECONDS",
    "SWEEPS_MOTION_SERVERS",
    "Cancelled",
    "Presser",
    "StopReport",
    "emergency_stop",
]

#: How long the streams get to end after their cancel before the zero messages go out anyway.
STREAM_STOP_SECONDS = 0.5
#: How long the stop waits for the bridge to show it handled everything sent before (one call's round trip).
HANDLED_SECONDS = 2.0

#: Who pressed the stop: the stop_robot tool, the E-STOP button of the operator console, or the server
#: shutting down (a signal, stdin closed, the HTTP server stopping). (The audit's tool column of each stop is
#: the presser's key.)
Presser = Literal["stop_robot", "console", "shutdown"]
#: How each presser is named in the answers of what its stop ended: voided calls' refusals, ended streams.
PRESSER_NAMES: Final[dict[Presser, str]] = {
    "stop_robot": "stop_robot",
    "console": "E-STOP on the operator console",
    "shutdown": "the server shutting down",
}
#: What each presser's cancelled goals say in ``canceled_by`` (a shutdown ends the calls that sent them).
_CANCELED_BY: Final[dict[Presser, CanceledBy]] = {
    "stop_robot": "stop_robot",
    "console": "estop",
    "shutdown": "request_cancelled",
}
_PRESSERS: Final[tuple[Presser, ...]] = get_args(Presser)
#: Whose stop also cancels every goal of the robot's known motion servers, whoever sent it.
SWEEPS_MOTION_SERVERS: Final[frozenset[Presser]] = frozenset({"console"})


@dataclass
class StopReport:
    """What :func:`emergency_stop` did, step by step."""

    streams_stopped: list[str] = field(default_factory=list)
    streams_still_running: list[str] = field(default_factory=list)
    zeroed_topics: list[str] = field(default_factory=list)
    #: Velocity topics whose zero could not be sent (not connected): owed, sent once the connection is back.
    zeros_owed: list[str] = field(default_factory=list)
    #: Controllers' trajectory topics that got a trajectory holding the joints (``robot/arm_stop.py``).
    held_topics: list[str] = field(default_factory=list)
    #: Ids of the goals a cancel was sent for (every goal of an action: ``cancels``).
    goals_cancelled: list[str] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)
    #: Every zero command (and trajectory hold) sent: (topic, type, message), for the audit.
    zero_messages: list[tuple[str, str, dict[str, Any]]] = field(default_factory=list)
    #: Every goal a cancel was sent for: (action, goal id, or "" for every goal of the action).
    goals: list[tuple[str, str]] = field(default_factory=list)
    #: Every cancel, one goal or every goal of an action, with what the robot answered.
    cancels: list[Cancelled] = field(default_factory=list)

    @property
    def did_anything(self) -> bool:
        return bool(
            self.streams_stopped
            or self.streams_still_running
            or self.zeroed_topics
            or self.held_topics
            or self.goals_cancelled
            or self.cancels
        )

    def cancel_lines(self) -> list[str]:
        """Each cancel sent, a line each (servers reached by name grouped by what they answered)."""
        return summary(self.cancels)

    def add(self, cancels: list[Cancelled]) -> None:
        """Take in cancels: each sent one for the audit, each failed one among the failures."""
        for cancel in cancels:
            self.cancels.append(cancel)
            if cancel.failed:
                self.failures.append(cancel.describe())
                continue
            self.goals.append((cancel.action, cancel.goal_id or ""))
            if cancel.goal_id is not None:
                self.goals_cancelled.append(cancel.goal_id)


async def emergency_stop(robot: RobotSession, *, by: Presser) -> StopReport:
    """On *robot*: end every stream, publish one zero command on every velocity topic used, cancel every goal
    this server caused (and, for the console's E-STOP, every goal of the robot's known motion servers).

    ``by`` is who pressed the stop (there is no default: every caller says it). Its name
    (:data:`PRESSER_NAMES`) is what each voided call's refusal and each ended stream's answer say; each
    cancelled goal's ``canceled_by`` is ``stop_robot`` or ``estop`` (the console).

    First, before anything awaits, the robot's send gate voids every call that began before this stop:
    whatever was approved (or being approved) then sends nothing more, whether or not it is registered yet.
    Last, one call on the main connection proves the bridge has handled everything sent before it (the
    streams' last messages, the zero commands, the cancels): what the robot gets after this returns is
    nothing of what ran before it.
    """
    if by not in _PRESSERS:  # a caller mypy does not see: refused before anything, so none is mislabelled
        raise ValueError(f"emergency_stop: unknown presser {by!r}; one of {', '.join(_PRESSERS)}")
    name, source = PRESSER_NAMES[by], _CANCELED_BY[by]
    client, activity = robot.client, robot.activity
    robot.gate.stop(name)
    report = StopReport()
    # Streams first: a stream still running after the zero message would set the robot moving again.
    ended, running = await activity.stop_streams(STREAM_STOP_SECONDS, by=name)
    report.streams_stopped = [entry.topic for entry in ended]
    report.streams_still_running = [entry.topic for entry in running]

    connected = False
    try:
        await client.ros_info()
        connected = True
    except RosbridgeError as exc:
        for target in activity.velocity_topics:  # sent once the connection is back (robot/owed_zeros.py)
            activity.owe_zero(target.topic, target.type, target.frame_id)
            report.zeros_owed.append(target.topic)
        report.failures.append(f"not connected, so no zero command was sent: {exc}")
    if connected:
        now = time.time()
        for target in activity.velocity_topics:
            message = zero_command(target.type, now, target.frame_id)
            try:
                await client.publish(target.topic, target.type, message)
            except RosbridgeError as exc:
                report.failures.append(f"zero command on {target.topic} failed: {exc}")
            else:
                report.zeroed_topics.append(target.topic)
                report.zero_messages.append((target.topic, target.type, message))
        await _hold_trajectories(robot, report)

    await _cancel_goals(robot, by, source, report)
    if connected and not await client.handled(HANDLED_SECONDS):
        report.failures.append(
            f"the bridge did not confirm within {HANDLED_SECONDS:g} s that it handled what was sent before "
            "the stop; check the robot"
        )
    return report


async def _hold_trajectories(robot: RobotSession, report: StopReport) -> None:
    """Hold every controller a trajectory this server published on its topic may still drive."""
    streamed = {*report.streams_stopped, *report.streams_still_running}
    held, failed = await stop_trajectories(robot.client, robot.graph, robot.activity.trajectories, streamed)
    for topic, type_name, message in held:
        robot.activity.forget_trajectory(topic)
        report.held_topics.append(topic)
        report.zero_messages.append((topic, type_name, message))
    report.failures.extend(failed)


async def _cancel_goals(robot: RobotSession, by: Presser, source: CanceledBy, report: StopReport) -> None:
    """Every goal this server caused; then, when *by* sweeps them, every known motion server's goals."""
    report.add(await cancel_caused(robot.goals, source))
    if by in SWEEPS_MOTION_SERVERS:
        done = {cancel.action for cancel in report.cancels if cancel.goal_id is None and not cancel.failed}
        report.add(await cancel_motion_servers(robot.goals, robot.graph, source, done=done))
