"""The arm moving: trajectories checked as ros2_control's JointTrajectoryController checks them, then followed
by ideal position tracking (no dynamics, no collisions), as the ROS 2 lab's arm is.

A trajectory starts from where the arm is and runs linearly between its points (a point at 0 s is jumped
to); ``header.stamp`` 0 starts it now, a future stamp later. One runs at a time: a newer goal or a trajectory
on the topic preempts it (ABORTED, −1), a cancel stops the arm where it is.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from rosbridge_mcp_server.sim.nodes.arm.model import ARM_JOINTS, JOINTS

__all__ = [
    "INVALID_GOAL",
    "INVALID_JOINTS",
    "LIMITS",
    "OLD_HEADER_TIMESTAMP",
    "Invalid",
    "Run",
    "Trajectory",
    "check_trajectory",
]

#: FollowJointTrajectory result codes.
SUCCESSFUL, INVALID_GOAL, INVALID_JOINTS, OLD_HEADER_TIMESTAMP = 0, -1, -2, -3
#: (lower, upper) of every joint with limits.
LIMITS: dict[str, tuple[float, float]] = {j.name: (j.lower, j.upper) for j in JOINTS if j.kind != "fixed"}


class Invalid(Exception):
    """A goal the controller refuses: its ``error_code`` and ``error_string``."""

    def __init__(self, code: int, text: str) -> None:
        super().__init__(text)
        self.code = code
        self.text = text


def _seconds(duration: Any) -> float:
    """A ``Duration`` or ``Time`` in either dialect's spelling (ROS 2 ``sec``/``nanosec``, ROS 1
    ``secs``/``nsecs``)."""
    if not isinstance(duration, dict):
        return 0.0
    sec = duration.get("sec", duration.get("secs", 0)) or 0
    nano = duration.get("nanosec", duration.get("nsecs", 0)) or 0
    return float(sec) + float(nano) / 1e9


@dataclass
class Trajectory:
    """Where each named joint should be at each time (``times`` relative to ``begin``, monotonic clock)."""

    joints: tuple[str, ...]
    times: list[float]
    positions: list[list[float]]
    begin: float
    start: list[float] = field(default_factory=list)  #: where the joints were when it began

    @property
    def end(self) -> float:
        return self.begin + self.times[-1]

    def sample(self, now: float) -> tuple[list[float], list[float]]:
        """Positions and velocities at *now*: held at the start before ``begin``, at the last point after."""
        t = now - self.begin
        if t <= 0:
            return list(self.start), [0.0] * len(self.joints)
        before_t, before = 0.0, self.start
        for at, point in zip(self.times, self.positions, strict=True):
            if t <= at:
                span = at - before_t
                if span <= 0:
                    return list(point), [0.0] * len(point)
                share = (t - before_t) / span
                positions = [a + (b - a) * share for a, b in zip(before, point, strict=True)]
                return positions, [(b - a) / span for a, b in zip(before, point, strict=True)]
            before_t, before = at, point
        return list(self.positions[-1]), [0.0] * len(self.joints)


def check_trajectory(
    trajectory: Any, *, allow_partial: bool, multi_dof: Any = None
) -> tuple[tuple[str, ...], Any]:
    """The joint names and points of a JointTrajectory, checked; :class:`Invalid` with ros2_control's code."""
    if not isinstance(trajectory, dict):
        raise Invalid(INVALID_GOAL, "the goal has no trajectory")
    names = trajectory.get("joint_names") or []
    unknown = [n for n in names if n not in ARM_JOINTS]
    if unknown:
        raise Invalid(INVALID_JOINTS, f"joints {', '.join(map(str, unknown[:6]))} are not the controller's")
    if len(set(names)) != len(names):
        raise Invalid(INVALID_JOINTS, "a joint is named twice in the trajectory")
    if not allow_partial and set(names) != set(ARM_JOINTS):
        missing = [n for n in ARM_JOINTS if n not in names]
        raise Invalid(
            INVALID_JOINTS, f"joints {', '.join(missing)} are missing (allow_partial_joints_goal false)"
        )
    if isinstance(multi_dof, dict) and (multi_dof.get("joint_names") or multi_dof.get("points")):
        raise Invalid(INVALID_GOAL, "multi-DOF trajectories are not supported by this controller")
    points = trajectory.get("points") or []
    if not points:
        raise Invalid(INVALID_GOAL, "the trajectory has no points")
    last = -1.0
    for index, point in enumerate(points):
        _check_point(index, point, names, last)
        last = _seconds(point.get("time_from_start"))
    return tuple(names), points


def _check_point(index: int, point: Any, names: Sequence[str], last: float) -> None:
    positions = point.get("positions") if isinstance(point, dict) else None
    if not isinstance(positions, list) or len(positions) != len(names):
        raise Invalid(
            INVALID_GOAL, f"point {index} has {len(positions or [])} positions for {len(names)} joints"
        )
    velocities = point.get("velocities") or []
    if velocities and len(velocities) != len(names):
        raise Invalid(INVALID_GOAL, f"point {index} has {len(velocities)} velocities for {len(names)} joints")
    at = _seconds(point.get("time_from_start"))
    if at <= last:
        raise Invalid(INVALID_GOAL, f"point {index}'s time_from_start is not after the previous point's")
    for name, value in zip(names, positions, strict=True):
        lower, upper = LIMITS[name]
        if not isinstance(value, int | float) or not lower <= value <= upper:
            raise Invalid(
                INVALID_GOAL,
                f"point {index}: joint {name} position {value} is outside its limits [{lower}, {upper}]",
            )


def make_trajectory(
    names: tuple[str, ...], points: Any, header: Any, where: Mapping[str, float], *, now: float | None = None
) -> Trajectory:
    """A checked trajectory placed in time: ``header.stamp`` 0 starts now; :class:`Invalid` (−3) when it is
    over before now."""
    wall, mono = time.time(), time.monotonic() if now is None else now
    stamp = _seconds(header.get("stamp")) if isinstance(header, dict) else 0.0
    begin = mono if stamp == 0 else mono + (stamp - wall)
    times = [_seconds(point.get("time_from_start")) for point in points]
    if begin + times[-1] < mono:
        raise Invalid(OLD_HEADER_TIMESTAMP, "the trajectory ends before now (header.stamp is too old)")
    positions = [[float(v) for v in point["positions"]] for point in points]
    return Trajectory(names, times, positions, begin, [where[name] for name in names])


@dataclass
class Run:
    """A trajectory being followed and how it ended (``succeeded``/``aborted``/``canceled``, result)."""

    trajectory: Trajectory
    source: str  #: "goal" or "topic"
    done: asyncio.Future[tuple[str, dict[str, Any]]] = field(
        default_factory=lambda: asyncio.get_running_loop().create_future()
    )

    def finish(self, state: str, code: int, text: str) -> None:
        if not self.done.done():
            self.done.set_result((state, {"error_code": code, "error_string": text}))
