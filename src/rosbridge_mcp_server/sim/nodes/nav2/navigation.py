"""The Nav2 world's navigator: a goal (or several poses in a row) planned on the map with
:class:`~.planner.Planner`, the plan published on ``/plan``, and the robot driven along it by a simple
controller (turn towards the next point, drive, turn to the goal's heading at the end) at a realistic speed,
with feedback a few times a second. A cancel stops the robot at once; a goal in an obstacle, off the map or
out of reach is aborted with Nav2's error code.

``speed`` scales every speed (1.0: 0.4 m/s and 1.2 rad/s at most, as a small indoor robot); tests set it
higher to keep their run time short.
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from rosbridge_mcp_server.sim.nodes.kit import NodeKit
from rosbridge_mcp_server.sim.nodes.nav2.planner import PlanFailure, Planner
from rosbridge_mcp_server.sim.nodes.nav2.robot import Nav2Robot, pose
from rosbridge_mcp_server.sim.world import TURTLE_HOME

__all__ = ["MAX_ANGULAR", "MAX_LINEAR", "Navigator", "Outcome", "Target", "targets_of"]

MAX_LINEAR = 0.4
MAX_ANGULAR = 1.2
#: How near (m) the goal's position and how near (rad) its heading count as there.
XY_TOLERANCE = 0.04
YAW_TOLERANCE = 0.03
LOOKAHEAD = 0.3
TICK = 0.05
FEEDBACK_EVERY = 4
#: Ticks between republishing the rest of the plan on /plan (Nav2 replans about once a second).
PLAN_EVERY = 20
#: nav2_msgs NavigateToPose error: TF_ERROR (a frame we cannot place).
TF_ERROR = 902

#: A pose to reach: x, y (m) and yaw (rad) in the map frame.
Target = tuple[float, float, float]


@dataclass(frozen=True)
class Outcome:
    """How a navigation ended: ``succeeded``, ``canceled`` or ``aborted``, with Nav2's error code and text."""

    state: str
    error_code: int = 0
    error_msg: str = ""


def _yaw_of(orientation: Any) -> float:
    if not isinstance(orientation, dict):
        return 0.0
    x, y = float(orientation.get("x", 0.0)), float(orientation.get("y", 0.0))
    z, w = float(orientation.get("z", 0.0)), float(orientation.get("w", 1.0))
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def targets_of(goal: dict[str, Any]) -> list[Target] | str:
    """The poses a navigation goal asks for, in the map frame, or why they cannot be placed.

    NavigateToPose ``pose``, NavigateThroughPoses ``poses`` (Kilted: ``poses.goals``), move_base
    ``target_pose``; ``odom`` is placed through the world's fixed map → odom transform, any other frame but
    ``map`` (or none) is a TF error."""
    stamped: list[Any] = []
    for key in ("pose", "target_pose"):
        if isinstance(goal.get(key), dict):
            stamped.append(goal[key])
    if not stamped:
        poses = goal.get("poses")
        if isinstance(poses, dict):  # Kilted: nav_msgs/Goals, the poses under "goals"
            poses = poses.get("goals")
        stamped = list(poses) if isinstance(poses, list) else []
    if not stamped:
        return "the goal holds no pose"
    out: list[Target] = []
    for item in stamped:
        if not isinstance(item, dict):
            return "a pose of the goal is not a PoseStamped"
        header = item.get("header")
        frame = str(header.get("frame_id", "")).lstrip("/") if isinstance(header, dict) else ""
        body = item.get("pose")
        body = body if isinstance(body, dict) else {}
        position = body.get("position")
        position = position if isinstance(position, dict) else {}
        x, y = float(position.get("x", 0.0)), float(position.get("y", 0.0))
        yaw = _yaw_of(body.get("orientation"))
        if frame == "odom":
            x, y = x + TURTLE_HOME, y + TURTLE_HOME
        elif frame not in ("", "map"):
            return f'Could not transform the goal from frame "{frame}" to "map"'
        out.append((x, y, yaw))
    return out


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


def _duration(seconds: float) -> dict[str, int]:
    sec = int(seconds)
    return {"sec": sec, "nanosec": int((seconds - sec) * 1e9)}


class Navigator:
    """Drives one world's robots to their goals; one navigation per robot at a time (a new one preempts)."""

    def __init__(self, kit: NodeKit, grid: Callable[[], Any]) -> None:
        self.kit = kit
        self._grid = grid
        #: Scales the top speeds (tests drive faster than a real robot).
        self.speed = 1.0
        self._current: dict[str, asyncio.Event] = {}

    def planner(self) -> Planner:
        return Planner(self._grid())

    def _stop(self, robot: Nav2Robot) -> None:
        robot.linear = robot.angular = 0.0
        robot.command_time = time.monotonic()
        self.kit.world.notify()

    def plan_message(self, points: list[tuple[float, float]], yaw: float) -> dict[str, Any]:
        header = self.kit.header("map")
        return {
            "header": header,
            "poses": [{"header": header, "pose": pose(x, y, yaw)} for x, y in points],
        }

    async def navigate(
        self,
        robot: Nav2Robot,
        goal: dict[str, Any],
        cancel: asyncio.Event,
        feedback: Callable[[dict[str, Any]], None],
        *,
        ros1: bool = False,
    ) -> Outcome:
        """Plan and drive to every pose of *goal* in turn, until done, aborted or *cancel* is set."""
        targets = targets_of(goal)
        if isinstance(targets, str):
            return Outcome("aborted", TF_ERROR, targets)
        previous = self._current.get(robot.namespace)
        if previous is not None:
            previous.set()  # a newer goal preempts the running one
        mine = asyncio.Event()
        self._current[robot.namespace] = mine
        stop = _Either(cancel, mine)
        started = time.monotonic()
        planner = self.planner()
        try:
            for index, target in enumerate(targets):
                path = planner.plan((robot.x, robot.y), target[:2])
                if isinstance(path, PlanFailure):
                    return Outcome("aborted", path.code, path.message)
                self.kit.publish(f"{robot.namespace}/plan", self.plan_message(path, target[2]))
                remaining_poses = len(targets) - index - 1
                ended = await self._drive(
                    robot,
                    path,
                    target[2],
                    stop=stop,
                    started=started,
                    feedback=feedback,
                    poses_remaining=remaining_poses,
                    ros1=ros1,
                )
                if not ended:
                    return Outcome("canceled")
            return Outcome("succeeded")
        finally:
            self._stop(robot)
            if self._current.get(robot.namespace) is mine:
                del self._current[robot.namespace]

    async def _drive(
        self,
        robot: Nav2Robot,
        path: list[tuple[float, float]],
        yaw: float,
        *,
        stop: _Either,
        started: float,
        feedback: Callable[[dict[str, Any]], None],
        poses_remaining: int,
        ros1: bool,
    ) -> bool:
        """Follow *path*, then turn to *yaw*; ``False`` when stopped on the way."""
        index = 1
        tick = 0
        goal_x, goal_y = path[-1]
        while True:
            if stop.is_set():
                return False
            vmax, wmax = MAX_LINEAR * self.speed, MAX_ANGULAR * self.speed
            while index < len(path) - 1 and math.dist((robot.x, robot.y), path[index]) < LOOKAHEAD:
                index += 1
            left = math.dist((robot.x, robot.y), (goal_x, goal_y))
            remaining = (
                left
                if index >= len(path) - 1
                else (
                    math.dist((robot.x, robot.y), path[index])
                    + sum(math.dist(path[i], path[i + 1]) for i in range(index, len(path) - 1))
                )
            )
            if left <= XY_TOLERANCE:
                error = _wrap(yaw - robot.yaw)
                if abs(error) <= YAW_TOLERANCE:
                    self._stop(robot)
                    return True
                linear, angular = 0.0, max(-wmax, min(wmax, 4.0 * error + math.copysign(0.05, error)))
            else:
                tx, ty = path[index]
                error = _wrap(math.atan2(ty - robot.y, tx - robot.x) - robot.yaw)
                linear = 0.0 if abs(error) > 0.6 else min(vmax, 3.0 * left + 0.05) * math.cos(error)
                angular = max(-wmax, min(wmax, 3.0 * error))
            robot.linear, robot.angular = linear, angular
            robot.command_time = time.monotonic()
            if tick % FEEDBACK_EVERY == 0:
                feedback(self._feedback(robot, remaining, started, poses_remaining, ros1))
            if tick and tick % PLAN_EVERY == 0:
                rest = [(robot.x, robot.y), *path[index:]]
                self.kit.publish(f"{robot.namespace}/plan", self.plan_message(rest, yaw))
            tick += 1
            await stop.wait(TICK)

    def _feedback(
        self, robot: Nav2Robot, remaining: float, started: float, poses_remaining: int, ros1: bool
    ) -> dict[str, Any]:
        current = {"header": self.kit.header("map"), "pose": pose(robot.x, robot.y, robot.yaw)}
        if ros1:
            return {"base_position": current}
        elapsed = time.monotonic() - started
        speed = MAX_LINEAR * self.speed
        return {
            "current_pose": current,
            "navigation_time": _duration(elapsed),
            "estimated_time_remaining": _duration(remaining / speed),
            "number_of_recoveries": 0,
            "distance_remaining": round(remaining, 3),
            "number_of_poses_remaining": poses_remaining,
        }


class _Either:
    """Set when either event is: the goal's cancel or a newer goal."""

    def __init__(self, first: asyncio.Event, second: asyncio.Event) -> None:
        self.events = (first, second)

    def is_set(self) -> bool:
        return any(event.is_set() for event in self.events)

    async def wait(self, timeout: float) -> None:
        """Up to *timeout* seconds, less when either is set."""
        waits = [asyncio.ensure_future(event.wait()) for event in self.events]
        try:
            await asyncio.wait(waits, timeout=timeout, return_when=asyncio.FIRST_COMPLETED)
        finally:
            for task in waits:
                task.cancel()
