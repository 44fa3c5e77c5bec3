"""What a stop cancels: every goal this server caused, and (the operator's E-STOP) every goal of the robot's
known motion action servers, whoever sent it.

* :func:`cancel_caused`: the goals the registry tracks (``run_goal``'s, by id) and the goals a publish or a
  service call started (:mod:`.caused`: by id when known, else every goal of the navigator's action);
* :func:`cancel_motion_servers`: every goal of each action server on the graph that moves the robot, known by
  its type (:data:`MOTION_ACTION_TYPES`) or, before its type is learnt, by its name's last part
  (:data:`MOTION_ACTION_LEAVES`): ROS 2 a ``CancelGoal`` with a zero goal id and zero stamp, ROS 1 an empty
  ``GoalID`` on ``<action>/cancel``.

Each cancel comes back as one :class:`Cancelled` saying what the robot answered, or why the cancel failed: a
stop never fails silently.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import RosbridgeError, ServiceError
from rosbridge_mcp_server.robot.goals import CanceledBy, CancelReport, cancel_goals
from rosbridge_mcp_server.robot.goals.registry import GoalRegistry
from rosbridge_mcp_server.robot.graph.rosapi import bounded_map

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = [
    "MOTION_ACTION_LEAVES",
    "MOTION_ACTION_TYPES",
    "Cancelled",
    "cancel_caused",
    "cancel_motion_servers",
    "motion_action_type",
    "summary",
]

#: Action types whose goals move the robot or a part of it, ``pkg/Name`` (either dialect's spelling is
#: read down to this). Nav2's planners, smoother and Wait move nothing and are left alone.
MOTION_ACTION_TYPES: Final = frozenset(
    {
        *(
            f"nav2_msgs/{name}"
            for name in (
                "NavigateToPose",
                "NavigateThroughPoses",
                "FollowWaypoints",
                "FollowGPSWaypoints",
                "FollowPath",
                "ComputeAndTrackRoute",
                "Spin",
                "BackUp",
                "DriveOnHeading",
                "AssistedTeleop",
                "DockRobot",
                "UndockRobot",
            )
        ),
        "opennav_docking_msgs/DockRobot",
        "opennav_docking_msgs/UndockRobot",
        "move_base_msgs/MoveBase",
        "mbf_msgs/MoveBase",
        "mbf_msgs/ExePath",
        "mbf_msgs/Recovery",
        "control_msgs/FollowJointTrajectory",
        "control_msgs/JointTrajectory",
        "control_msgs/GripperCommand",
        "control_msgs/ParallelGripperCommand",
        "control_msgs/SingleJointPosition",
        "control_msgs/PointHead",
        "moveit_msgs/MoveGroup",
        "moveit_msgs/ExecuteTrajectory",
        "turtlesim/RotateAbsolute",
    }
)
#: The usual names (last part) of those servers: a server so named is cancelled without learning its type.
MOTION_ACTION_LEAVES: Final = frozenset(
    {
        "navigate_to_pose",
        "navigate_through_poses",
        "follow_waypoints",
        "follow_gps_waypoints",
        "follow_path",
        "compute_and_track_route",
        "spin",
        "backup",
        "drive_on_heading",
        "assisted_teleop",
        "dock_robot",
        "undock_robot",
        "move_base",
        "follow_joint_trajectory",
        "gripper_cmd",
        "gripper_action",
        "execute_trajectory",
        "move_action",
        "rotate_absolute",
    }
)
#: How long the E-STOP spends learning which action servers are on the graph and their types.
SURVEY_SECONDS: Final = 3.0


@dataclass(frozen=True)
class Cancelled:
    """One cancel a stop sent, or tried to: a goal by id, or every goal of an action (``goal_id`` None)."""

    action: str
    goal_id: str | None
    #: Why it was cancelled: "sent by this server", "sent on /goal_pose by this server", "a motion server".
    why: str
    #: What the robot answered ("cancelling", "not running", "2 goal(s) cancelling", "cancel sent"), or the
    #: failure.
    outcome: str
    failed: bool = False

    def describe(self) -> str:
        if not self.action:
            return self.outcome
        which = f"goal {self.goal_id}" if self.goal_id is not None else "every goal"
        return f"{which} on {self.action} ({self.why}): {self.outcome}"


#: Why a server reached by its name was cancelled (such cancels are grouped in a summary).
BY_NAME: Final = "a motion server, by its name"


def summary(cancels: Iterable[Cancelled]) -> list[str]:
    """One line per cancel sent, those of servers reached by name grouped by what they answered (an idle
    Nav2 robot has ten motion servers)."""
    lines: list[str] = []
    grouped: dict[str, list[str]] = {}
    for cancel in cancels:
        if cancel.failed:
            continue
        if cancel.goal_id is None and cancel.why == BY_NAME:
            grouped.setdefault(cancel.outcome, []).append(cancel.action)
        else:
            lines.append(cancel.describe())
    lines += [
        f"every goal on {', '.join(names)} ({BY_NAME}): {outcome}" for outcome, names in grouped.items()
    ]
    return lines


def motion_action_type(action_type: str) -> bool:
    """Whether *action_type* (any spelling) is one whose goals move the robot."""
    try:
        names = Dialect.action_names(action_type)
    except RosbridgeError:
        return False
    return f"{names.package}/{names.name}" in MOTION_ACTION_TYPES


async def cancel_caused(goals: GoalRegistry, by: CanceledBy) -> list[Cancelled]:
    """Cancel every goal this server caused: those it runs, then those a publish or a call started."""
    done: list[Cancelled] = []
    for goal in goals.running():
        done.append(await _cancel(goals, goal.action, goal.goal_id, "sent by this server", by))
    try:
        version: int | None = (await goals.client.ros_info()).version if goals.caused_goals() else None
    except RosbridgeError:
        version = None  # not connected: each cancel below fails and says so
    for caused in goals.caused_goals():
        if version is not None and caused.dialect != version:
            goals.forget_caused(caused)  # sent to a bridge of the other ROS version: that goal is gone
            continue
        cancel = await _cancel(
            goals, caused.action, caused.goal_id, f"sent on {caused.carrier} by this server", by
        )
        done.append(cancel)
        if not cancel.failed:
            goals.forget_caused(caused)
    return done


async def cancel_motion_servers(
    goals: GoalRegistry, graph: RosGraph, by: CanceledBy, *, done: Iterable[str] = ()
) -> list[Cancelled]:
    """Cancel every goal of every motion action server on the graph but those in *done* (whose goals were all
    cancelled already); a server whose type could not be learnt in time is said, not skipped silently."""
    try:
        async with asyncio.timeout(SURVEY_SECONDS):
            names = await graph.action_names()
    except (RosbridgeError, TimeoutError) as exc:
        why = f"within {SURVEY_SECONDS:g} s" if isinstance(exc, TimeoutError) else str(exc)
        failed = f"Could not list the robot's action servers, so no motion server was cancelled: {why}"
        return [Cancelled("", None, "the robot's motion servers", failed, failed=True)]
    skip = set(done)
    names = [name for name in names if name not in skip]
    by_name = [name for name in names if name.rsplit("/", 1)[-1] in MOTION_ACTION_LEAVES]
    types = await _types(graph, [name for name in names if name not in by_name])
    out: list[Cancelled] = []
    chosen = [(name, BY_NAME) for name in by_name]
    for name in names:
        if name in by_name:
            continue
        found = types.get(name, "")
        if found is None:
            continue  # the bridge cannot tell its type: not one we know
        if not found:
            late = f"its type was not learnt (within {SURVEY_SECONDS:g} s), so it was not cancelled"
            out.append(Cancelled(name, None, "an action server of unknown type", late, failed=True))
        elif motion_action_type(found):
            chosen.append((name, f"a motion server, {found}"))
    cancels = await asyncio.gather(*(_cancel(goals, name, None, why, by) for name, why in chosen))
    return [*cancels, *out]


async def _types(graph: RosGraph, names: list[str]) -> dict[str, str | None]:
    """The type of each action (None: the bridge cannot tell); those not learnt (in time, or at all: the
    connection went) are left out, and said by the caller."""
    found: dict[str, str | None] = {}

    async def one(name: str) -> None:
        known = graph.known_action_type(name)
        try:
            found[name] = known or await graph.action_type(name)
        except ServiceError:
            found[name] = None  # rosapi cannot tell it
        except RosbridgeError:
            pass

    with contextlib.suppress(TimeoutError):
        async with asyncio.timeout(SURVEY_SECONDS):
            await bounded_map(one, names)
    return found


async def _cancel(
    goals: GoalRegistry, action: str, goal_id: str | None, why: str, by: CanceledBy
) -> Cancelled:
    # ROS 1: the client sends a cancel on a new publisher once more a moment later (its first message is
    # often lost).
    try:
        report = await cancel_goals(goals, action, goal_id, by=by)
    except RosbridgeError as exc:
        return Cancelled(action, goal_id, why, f"the cancel failed: {exc}", failed=True)
    return Cancelled(action, goal_id, why, *_outcome(report))


def _outcome(report: CancelReport) -> tuple[str, bool]:
    """What the robot answered a cancel, and whether it failed."""
    if report.dialect == 1:
        return ("cancel sent" if report.goal_id is not None else "cancel of every goal sent"), False
    if report.failed:
        return report.note or "the cancel failed", True
    if report.no_server:
        return "no such action server on the graph, so no goal of it runs", False
    if report.return_code in (2, 3):  # unknown goal id (never started, or gone), goal already ended
        return "not running", False
    if report.return_code == 1:
        # rcl answers a cancel of every goal that matches none with "rejected" too.
        if report.goal_id is None and not report.goals_canceling:
            return "no goal was running", False
        return "the action server rejected the cancel", True
    if report.goals_canceling is not None:
        count = len(report.goals_canceling)
        if report.goal_id is None:
            return (f"{count} goal(s) cancelling" if count else "no goal was running"), False
        return ("cancelling" if count else "not running"), False
    return "cancel sent", False
