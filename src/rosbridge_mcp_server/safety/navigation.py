"""The guard's judgement of motion goals: one rule for every goal that moves the robot, whichever tool and
carrier sends it and however its type is spelt (``robot/motion_goals.py``: ``navigate_to``;
``publish_action``; ROS 2's ``<action>/_action/send_goal`` through ``publish_service``; ROS 1 actionlib's
``<action>/goal`` and the goal pose topics through ``publish_topic``).

The act carries the scene it is judged against (``Act.scene``: the map, the robot's pose and the goal placed
on the map, learnt by ``robot/acting/`` just before). In order:

1. the goal must be readable; one the fence cannot place at all (AssistedTeleop, a dock by id, UndockRobot,
   route node ids, GPS waypoints, an unknown type sent to a motion action's name) is refused while
   ``[navigation]`` has zones or limits (fail closed), and otherwise allowed unjudged;
2. its poses (or the end of a drive along the robot's heading) must be placed in the map frame: while
   ``[navigation]`` has zones or limits, a goal that cannot be placed is refused;
3. every pose is on the map, in known free space, at least ``robot_radius`` from anything occupied or unknown
   (not for a turn in place), and a straight drive (DriveOnHeading, BackUp, FollowPath's pieces) crosses no
   obstacle and stays on the map (checked whenever a map is known; with zones or limits a goal that cannot be
   checked against the map is refused);
4. ``[navigation]``: the robot's footprint (a disc of ``robot_radius``) at every pose, and swept along every
   straight drive, outside every keep-out zone and inside one allowed zone (when any is listed); every pose at
   most ``max_goal_distance`` from the robot.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rosbridge_mcp_server.robot.motion_goals import Motion, carried_goal, read_motion
from rosbridge_mcp_server.robot.navigation import (
    DEFAULT_ROBOT_RADIUS,
    Scene,
    distance_problem,
    map_problem,
    path_map_problem,
    zone_problem,
)
from rosbridge_mcp_server.robot.occupancy import Pose2D

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.approval import Act
    from rosbridge_mcp_server.safety.policy import NavigationRules

__all__ = ["NavigationRefusal", "act_motion", "goal_text", "navigation_refusal"]


@dataclass(frozen=True)
class NavigationRefusal:
    """The rule (for the audit) and the sentence for the model."""

    rule: str
    text: str


def _refusal(rule: str, why: str, advice: str) -> NavigationRefusal:
    return NavigationRefusal(rule, f"Refused: {why}; nothing was sent. {advice}".strip())


_PICK = "Pick a goal in free space on the map (view_map shows it)."


def act_motion(act: Act) -> Motion | str | None:
    """What the fence judges of the motion goal *act* carries (a sentence when it cannot be read), or
    ``None`` when it carries none."""
    carried = carried_goal(act.kind, act.name, act.type, act.payload)
    return None if carried is None else read_motion(carried)


def navigation_refusal(act: Act, rules: NavigationRules) -> NavigationRefusal | None:
    """Why the motion goal *act* carries may not be sent, or ``None`` (also for any act that carries none)."""
    motion = act_motion(act)
    if motion is None:
        return None
    if isinstance(motion, str):
        return _refusal(
            "navigation: unreadable goal", f"the motion goal {act.name} carries cannot be read: {motion}", ""
        )
    strict = rules.configured
    if motion.unplaceable is not None:
        if not strict:
            return None
        return _refusal(
            "[navigation] goal cannot be placed",
            f"the goal ({motion.what}) cannot be placed on the map: {motion.unplaceable}; while the safety "
            "policy's [navigation] has zones or limits, such a goal is refused",
            "Send a goal with poses on the map (navigate_to), or ask the robot's operator.",
        )
    scene = act.scene if isinstance(act.scene, Scene) else None
    # A path is driven from wherever the robot is: with zones, where it is must be known too.
    if (scene is None or len(scene.goals) != motion.placed_count) and not strict:
        return None
    robot_needed = strict and motion.path and scene is not None and scene.robot is None
    if scene is None or len(scene.goals) != motion.placed_count or robot_needed:
        why = "; ".join(scene.problems) if scene is not None and scene.problems else "no map or /tf was read"
        return _refusal(
            "[navigation] goal not placed",
            f"the safety policy's [navigation] zones and limits need the goal ({motion.what}) placed on the "
            f"map, and {why}",
            "Make sure the map and /tf are published, or give the goal in the map frame.",
        )
    radius = rules.robot_radius if rules.robot_radius is not None else DEFAULT_ROBOT_RADIUS
    drives = _straight_drives(motion, scene)
    return (
        _map_refusal(motion, scene, drives, radius, strict)
        or _zone_refusal(scene, drives, rules, radius)
        or _distance_refusal(scene, rules)
    )


def _straight_drives(motion: Motion, scene: Scene) -> list[tuple[Pose2D, Pose2D]]:
    """The straight pieces the robot drives as given: along its heading, or between a path's poses (from
    the robot to the first when its pose is known)."""
    if motion.along is not None:
        return [(scene.robot, scene.goals[0])] if scene.robot is not None else []
    if not motion.path:
        return []
    points = ([scene.robot] if scene.robot is not None else []) + list(scene.goals)
    return list(itertools.pairwise(points))


#: Most map cells a goal's straight drives are checked at (a 100 m path on a 5 cm map is 4,000).
MAX_MAP_SAMPLES = 200_000


def _map_refusal(
    motion: Motion, scene: Scene, drives: list[tuple[Pose2D, Pose2D]], radius: float, strict: bool
) -> NavigationRefusal | None:
    if scene.grid is None:
        if not strict:
            return None
        why = "; ".join(scene.problems) or "no map"
        return _refusal(
            "[navigation] no map",
            f"the goal cannot be checked against the map ({why})",
            "Start the map server, or ask the robot's operator.",
        )
    in_place = motion.along == 0.0
    length = sum(math.hypot(end.x - start.x, end.y - start.y) for start, end in drives)
    if length / (scene.grid.resolution / 2) > MAX_MAP_SAMPLES:
        # Each straight piece is sampled every half cell: a bound keeps one goal from stalling the server.
        too_long = f"the straight drives of this goal are {length:.0f} m in all, too long to check on the map"
        return _refusal(f"map: {too_long}", too_long, "Send a shorter path.")
    for goal in () if in_place else scene.goals:
        problem = map_problem(scene.grid, goal, radius)
        if problem is not None:
            return _refusal(f"map: {problem}", problem, _PICK)
    for start, end in drives:
        problem = path_map_problem(scene.grid, start, end)
        if problem is not None:
            return _refusal(f"map: {problem}", problem, _PICK)
    return None


def _zone_refusal(
    scene: Scene, drives: list[tuple[Pose2D, Pose2D]], rules: NavigationRules, radius: float
) -> NavigationRefusal | None:
    allowed = dict(rules.allowed_zones)
    keep_out = dict(rules.keep_out)
    if not allowed and not keep_out:
        return None
    judged: list[tuple[Pose2D, Pose2D | None]] = [(goal, None) for goal in scene.goals]
    judged += [(end, start) for start, end in drives]
    for goal, start in judged:
        problem = zone_problem(goal, allowed, keep_out, radius, start)
        if problem is not None:
            return _refusal(
                f"[navigation] {problem}",
                f"{problem} (safety policy)",
                # Only the zones the policy has: with keep-out zones alone there is no allowed area.
                "Choose a goal "
                + " and ".join(
                    (["inside the allowed area"] if allowed else [])
                    + (["clear of the keep-out zones"] if keep_out else [])
                )
                + ".",
            )
    return None


def _distance_refusal(scene: Scene, rules: NavigationRules) -> NavigationRefusal | None:
    if rules.max_goal_distance is None:
        return None
    if scene.robot is None:
        return _refusal(
            "[navigation] max_goal_distance: robot pose unknown",
            f"the goal's distance cannot be checked against max_goal_distance "
            f"{rules.max_goal_distance:g} m: {'; '.join(scene.problems) or 'the robot pose is unknown'}",
            "",
        )
    for goal in scene.goals:
        problem = distance_problem(goal, scene.robot, rules.max_goal_distance)
        if problem is not None:
            return _refusal(f"[navigation] {problem}", f"{problem} (safety policy)", "Choose a nearer goal.")
    return None


def goal_text(act: Act) -> str:
    """Where a navigation goal sends the robot, in the map frame, for the person asked to confirm it.

    Only the goal: the robot's own pose moves (localisation jitters), and the question must read the same when
    a client answers it in a second round (protocol 2026-07-28 matches the answer to the exact question)."""
    motion = act_motion(act)
    if isinstance(motion, Motion) and motion.along is not None:
        # Relative to the robot, which the question must not name (its pose jitters between two rounds).
        if motion.along == 0.0:
            return "Turns the robot in place."
        way = "forward" if motion.along > 0 else "backward"
        return f"Drives the robot {abs(motion.along):.2f} m {way} along its heading."
    scene = act.scene if isinstance(act.scene, Scene) else None
    if scene is None or not scene.goals:
        return ""
    parts = [f"x={goal.x:.2f} y={goal.y:.2f} m yaw={math.degrees(goal.yaw):.0f}°" for goal in scene.goals]
    return f"Goal in {scene.map_frame}: {'; then '.join(parts)}."
