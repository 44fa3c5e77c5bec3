"""The guard's judgement of navigation goals: one rule for every goal that sends the robot somewhere,
whichever tool sends it and however it is spelt (``navigate_to``; ``publish_action`` on Nav2's
``NavigateToPose``, ``NavigateThroughPoses``, ``FollowWaypoints`` or ROS 1's ``move_base``).

The act carries the scene it is judged against (``Act.scene``: the map, the robot's pose and the goal placed
on the map, learnt by ``robot/acting.py`` just before). In order:

1. the goal's poses must be readable and placeable in the map frame;
2. every goal is on the map, in known free space, at least ``robot_radius`` from anything occupied or unknown
   (checked whenever a map is known; with ``[navigation]`` zones or a distance limit a goal that cannot be
   checked against the map is refused);
3. ``[navigation]``: outside every keep-out zone, inside an allowed zone (when any is listed), at most
   ``max_goal_distance`` from the robot.

A navigation goal can also travel as something else: ROS 1 actionlib's ``<action>/goal`` topic, ROS 2's
``<action>/_action/send_goal`` service, or a goal pose topic (``/goal_pose``, ``/move_base_simple/goal``).
Those carry no scene, so while ``[navigation]`` has zones or limits they are refused: the rules would
otherwise not be checked at all.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rosbridge_mcp_server.robot.effects import MOTION_GOAL_TOPICS
from rosbridge_mcp_server.robot.navigation import (
    DEFAULT_ROBOT_RADIUS,
    Scene,
    distance_problem,
    goal_poses,
    map_problem,
    navigation_goal,
    zone_problem,
)

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.seam import Act
    from rosbridge_mcp_server.safety.policy import NavigationRules

__all__ = ["NavigationRefusal", "goal_text", "navigation_refusal"]


@dataclass(frozen=True)
class NavigationRefusal:
    """The rule (for the audit) and the sentence for the model."""

    rule: str
    text: str


def _refusal(rule: str, why: str, advice: str) -> NavigationRefusal:
    return NavigationRefusal(rule, f"Refused: {why}; nothing was sent. {advice}".strip())


_PICK = "Pick a goal in free space on the map (view_map shows it)."


#: The last part of the usual navigation actions' names: a goal to one of them by another carrier is a
#: navigation goal even when its type is not known.
_NAVIGATION_ACTIONS = frozenset(
    {"navigate_to_pose", "navigate_through_poses", "follow_waypoints", "move_base"}
)


def carries_navigation_goal(act: Act) -> bool:
    """Whether *act*, not itself an action goal, sends a navigation goal: an actionlib goal topic or an
    ``_action/send_goal`` call of a navigation action, or a goal pose topic."""
    if act.kind == "topic":
        if act.type.endswith("ActionGoal") and navigation_goal(act.type[: -len("Goal")]) is not None:
            return True
        if act.name in MOTION_GOAL_TOPICS or act.name.endswith(MOTION_GOAL_TOPICS):
            return True
    sends_goal = act.kind == "service" and act.type.endswith("_SendGoal")
    if sends_goal and navigation_goal(act.type[: -len("_SendGoal")]) is not None:
        return True
    return any(
        effect.kind == "action"
        and effect.what == "goal"
        and effect.name.rsplit("/", 1)[-1] in _NAVIGATION_ACTIONS
        for effect in act.effects
    )


def navigation_refusal(act: Act, rules: NavigationRules) -> NavigationRefusal | None:
    """Why the navigation goal *act* may not be sent, or ``None`` (also for any act that is no such goal)."""
    if act.kind != "action":
        if rules.configured and carries_navigation_goal(act):
            return _refusal(
                "[navigation] goal not sent as a goal",
                f"{act.name} carries a navigation goal, and the safety policy's [navigation] zones and "
                "limits are checked only where a goal is placed on the map",
                "Send it with navigate_to, or publish_action on the navigation action.",
            )
        return None
    if navigation_goal(act.type) is None:
        return None
    poses = goal_poses(act.type, act.payload if isinstance(act.payload, dict) else {})
    if isinstance(poses, str):
        return _refusal("navigation: unreadable goal", f"the navigation goal cannot be read: {poses}", "")
    scene = act.scene if isinstance(act.scene, Scene) else None
    strict = rules.configured
    if scene is None or len(scene.goals) != len(poses):
        if not strict:
            return None
        why = "; ".join(scene.problems) if scene is not None and scene.problems else "no map or /tf was read"
        return _refusal(
            "[navigation] goal not placed",
            f"the safety policy's [navigation] zones and limits need the goal placed on the map, and {why}",
            "Make sure the map and /tf are published, or give the goal in the map frame.",
        )
    radius = rules.robot_radius if rules.robot_radius is not None else DEFAULT_ROBOT_RADIUS
    if scene.grid is not None:
        for goal in scene.goals:
            problem = map_problem(scene.grid, goal, radius)
            if problem is not None:
                return _refusal(f"map: {problem}", problem, _PICK)
    elif strict:
        why = "; ".join(scene.problems) or "no map"
        return _refusal(
            "[navigation] no map",
            f"the goal cannot be checked against the map ({why})",
            "Start the map server, or ask the robot's operator.",
        )
    allowed = dict(rules.allowed_zones)
    keep_out = dict(rules.keep_out)
    for goal in scene.goals:
        problem = zone_problem(goal, allowed, keep_out)
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
    if rules.max_goal_distance is not None:
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
                return _refusal(
                    f"[navigation] {problem}", f"{problem} (safety policy)", "Choose a nearer goal."
                )
    return None


def goal_text(act: Act) -> str:
    """Where a navigation goal sends the robot, in the map frame, for the person asked to confirm it.

    Only the goal: the robot's own pose moves (localisation jitters), and the question must read the same when
    a client answers it in a second round (protocol 2026-07-28 matches the answer to the exact question)."""
    scene = act.scene if isinstance(act.scene, Scene) else None
    if act.kind != "action" or scene is None or not scene.goals:
        return ""
    parts = [f"x={goal.x:.2f} y={goal.y:.2f} m yaw={math.degrees(goal.yaw):.0f}°" for goal in scene.goals]
    return f"Goal in {scene.map_frame}: {'; then '.join(parts)}."
