"""Motion goals: which goals move the robot, however spelt and carried, and what the fence reads of them.

A goal that moves the robot reaches it by several carriers: an action goal (``publish_action``,
``navigate_to``), ROS 2's hidden ``<action>/_action/send_goal`` service, ROS 1 actionlib's ``<action>/goal``
topic (a ``…ActionGoal`` message), or a goal pose topic (``/goal_pose``, ``/move_base_simple/goal``).
:func:`carried_goal` finds the goal in any of them, by type (every spelling:
``nav2_msgs/action/NavigateToPose``, ``nav2_msgs/NavigateToPose``, ``…Action``, ``…ActionGoal``,
``…_SendGoal``, ``…_Goal``) and, when the type says nothing, by the usual action names. :func:`read_motion`
reads what the fence judges (:class:`Motion`):

* poses to place on the map: NavigateToPose ``pose``, move_base ``target_pose``, NavigateThroughPoses
  ``poses`` (Jazzy: a list of PoseStamped; Kilted: ``nav_msgs/Goals``, the list under ``goals``),
  FollowWaypoints ``poses``, DockRobot ``dock_pose`` (with ``use_dock_id`` false), ComputeAndTrackRoute's
  ``goal`` (with ``use_poses``), a goal pose topic's message;
* a path whose straight pieces are driven as given: FollowPath ``path.poses``;
* a distance along the robot's heading: DriveOnHeading ``target.x``, BackUp ``-|target.x|``; a Spin turns in
  place (distance 0); their ``speed`` is what ``[velocity]`` caps;
* what cannot be placed at all, with the reason: AssistedTeleop (teleoperation for a time), DockRobot by dock
  id, UndockRobot, ComputeAndTrackRoute by node ids, FollowGPSWaypoints, a goal of an unknown type sent to a
  motion action's usual name.

Pure; no MCP. ``robot/navigation.py`` places a :class:`Motion` on the map (``survey``), ``safety/`` judges it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.robot.occupancy import yaw_of

__all__ = [
    "GOAL_POSE_TOPICS",
    "MOTION_ACTIONS",
    "CarriedGoal",
    "GoalPose",
    "Motion",
    "carried_goal",
    "motion_action",
    "read_motion",
    "with_speed",
]

#: Motion actions by type (``pkg/Name``) → how the fence reads their goals (see :func:`read_motion`).
MOTION_ACTIONS: dict[str, str] = {
    "nav2_msgs/NavigateToPose": "pose",
    "move_base_msgs/MoveBase": "target_pose",
    "nav2_msgs/NavigateThroughPoses": "poses",
    "nav2_msgs/FollowWaypoints": "poses",
    "nav2_msgs/FollowPath": "path",
    "nav2_msgs/DriveOnHeading": "heading",
    "nav2_msgs/BackUp": "backup",
    "nav2_msgs/Spin": "spin",
    "nav2_msgs/AssistedTeleop": "teleop",
    "nav2_msgs/DockRobot": "dock",
    "nav2_msgs/UndockRobot": "undock",
    "nav2_msgs/ComputeAndTrackRoute": "route",
    "nav2_msgs/FollowGPSWaypoints": "gps",
}
#: The usual names (last part) of the motion actions: a goal to one of them whose type is not known is a
#: motion goal the fence cannot read.
MOTION_ACTION_NAMES = frozenset(
    {
        "navigate_to_pose",
        "navigate_through_poses",
        "follow_waypoints",
        "follow_gps_waypoints",
        "follow_path",
        "drive_on_heading",
        "backup",
        "back_up",
        "spin",
        "assisted_teleop",
        "dock_robot",
        "undock_robot",
        "compute_and_track_route",
        "move_base",
    }
)
#: Topics a navigation stack takes a goal pose on (ROS 1 move_base, ROS 2 Nav2's bt_navigator), also under a
#: namespace.
GOAL_POSE_TOPICS = ("/move_base_simple/goal", "/goal_pose")

#: Suffixes of the types that name an action or the goal of one, longest first.
_SUFFIXES = ("_SendGoal_Request", "_SendGoal", "ActionGoal", "_Goal", "Action", "Goal")


def motion_action(type_name: str) -> str | None:
    """The motion action (``pkg/Name``) *type_name* names in any spelling, or ``None``.

    ``nav2_msgs/action/NavigateToPose``, ``nav2_msgs/NavigateToPose``, ``nav2_msgs/NavigateToPoseAction``,
    ``nav2_msgs/NavigateToPoseActionGoal``, ``nav2_msgs/action/NavigateToPose_SendGoal`` and ROS 1's
    ``move_base_msgs/MoveBaseActionGoal`` all name one."""
    short = Dialect.short_type(type_name.strip().strip("/"))
    if short in MOTION_ACTIONS:
        return short
    for suffix in _SUFFIXES:
        if short.endswith(suffix) and short[: -len(suffix)] in MOTION_ACTIONS:
            return short[: -len(suffix)]
    return None


@dataclass(frozen=True)
class CarriedGoal:
    """A motion goal found in an act: its action type (``pkg/Name``; ``""`` for a goal pose topic, ``None``
    when the type is not a known one) and the goal itself as it will reach the robot."""

    action: str | None
    goal: Any
    target: str  #: what it is sent to: the action, or the goal pose topic

    @property
    def namespace(self) -> str:
        """The robot's namespace the goal is sent in (``""`` at the root): where its map is."""
        for topic in GOAL_POSE_TOPICS:
            if self.target.endswith(topic):
                return self.target[: -len(topic)]
        return self.target.rsplit("/", 1)[0]


def _is_goal_pose_topic(name: str) -> bool:
    return name in GOAL_POSE_TOPICS or name.endswith(GOAL_POSE_TOPICS)


def carried_goal(kind: str, name: str, type_name: str, payload: Any) -> CarriedGoal | None:
    """The motion goal an act of *kind* on *name* carries, or ``None`` when it carries none."""
    action = motion_action(type_name) if type_name else None
    body = payload if isinstance(payload, Mapping) else {}
    if kind == "action":
        if action is not None or name.rsplit("/", 1)[-1] in MOTION_ACTION_NAMES:
            return CarriedGoal(action, payload, name)
        return None
    if kind == "topic":
        parent, _, leaf = name.rpartition("/")
        if type_name.endswith("ActionGoal") and (
            action is not None or (leaf == "goal" and parent.rsplit("/", 1)[-1] in MOTION_ACTION_NAMES)
        ):
            return CarriedGoal(action, body.get("goal"), parent or name)
        if _is_goal_pose_topic(name):
            pose = Dialect.short_type(type_name) == "geometry_msgs/PoseStamped"
            return CarriedGoal("" if pose else None, payload, name)
        return None
    if kind == "service":
        parent, _, leaf = name.rpartition("/")
        action_name, _, hidden = parent.rpartition("/")
        sends = hidden == "_action" and leaf == "send_goal"
        by_name = sends and action_name.rsplit("/", 1)[-1] in MOTION_ACTION_NAMES
        if (action is not None and ("_SendGoal" in type_name or sends)) or by_name:
            return CarriedGoal(action, body.get("goal"), action_name if sends else name)
    return None


@dataclass(frozen=True)
class GoalPose:
    """One pose a goal asks for, as written in it: frame (``""`` when the header names none), x, y, yaw."""

    frame: str
    x: float
    y: float
    yaw: float


@dataclass(frozen=True)
class Motion:
    """What the fence judges of a motion goal.

    ``poses`` are placed on the map (``path``: the robot drives the straight pieces between them as given);
    ``along`` is a drive along the robot's heading in metres (negative: backwards; 0: in place), placed from
    the robot's pose; ``unplaceable`` says why the goal cannot be placed at all; ``speed`` (m/s, as asked)
    is what a speed cap judges, at ``speed_field`` of the goal."""

    what: str  #: e.g. "NavigateToPose", "a goal pose on /goal_pose"
    poses: tuple[GoalPose, ...] = ()
    path: bool = False
    along: float | None = None
    unplaceable: str | None = None
    speed: float | None = None

    @property
    def placed_count(self) -> int:
        """How many poses a scene places for it: one per pose, or the end of a drive along the heading."""
        return 1 if self.along is not None else len(self.poses)


def _finite(value: object) -> float | None:
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return None


def _pose(item: Any, where: str, frame: str = "") -> GoalPose | str:
    if not isinstance(item, Mapping):
        return f"{where} is not a geometry_msgs/PoseStamped"
    header = item.get("header")
    written = str(header.get("frame_id", "")).lstrip("/") if isinstance(header, Mapping) else ""
    body = item.get("pose")
    body = body if isinstance(body, Mapping) else {}
    position = body.get("position")
    position = position if isinstance(position, Mapping) else {}
    x, y = _finite(position.get("x", 0.0)), _finite(position.get("y", 0.0))
    if x is None or y is None:
        return f"{where}.pose.position is not a finite point"
    orientation = body.get("orientation")
    if isinstance(orientation, Mapping) and any(
        _finite(orientation.get(k, 0.0)) is None for k in ("x", "y", "z", "w")
    ):
        return f"{where}.pose.orientation is not a finite quaternion"
    return GoalPose(written or frame, x, y, yaw_of(orientation))


def _poses(items: Any, where: str, frame: str = "") -> tuple[GoalPose, ...] | str:
    if not isinstance(items, list) or not items:
        return f"{where} holds no poses"
    out: list[GoalPose] = []
    for index, item in enumerate(items):
        pose = _pose(item, f"{where}[{index}]", frame)
        if isinstance(pose, str):
            return pose
        out.append(pose)
    return tuple(out)


def _header_frame(value: Mapping[str, Any]) -> str:
    header = value.get("header")
    return str(header.get("frame_id", "")).lstrip("/") if isinstance(header, Mapping) else ""


def _many(what: str, goal: Mapping[str, Any], key: str, *, path: bool = False) -> Motion | str:
    """A list of PoseStamped, or (Kilted's nav_msgs/Goals, FollowPath's nav_msgs/Path) one under a header."""
    value = goal.get(key)
    inner = "poses" if path else "goals"
    if isinstance(value, Mapping):
        poses = _poses(value.get(inner), f"{key}.{inner}", _header_frame(value))
    else:
        poses = _poses(value, key)
    return poses if isinstance(poses, str) else Motion(what, poses, path=path)


def _drive(what: str, goal: Mapping[str, Any], backwards: bool) -> Motion | str:
    target = goal.get("target")
    target = target if isinstance(target, Mapping) else {}
    distance = _finite(target.get("x", 0.0))
    speed = _finite(goal.get("speed", 0.0))
    if distance is None or speed is None:
        return "target.x and speed must be finite numbers"
    return Motion(what, along=-abs(distance) if backwards else distance, speed=abs(speed))


_CANNOT = {
    "teleop": "AssistedTeleop hands the robot to teleoperation for its time_allowance, so where it goes "
    "cannot be placed",
    "undock": "UndockRobot drives the robot off its dock to a staging pose the docking server chooses, "
    "which cannot be placed",
    "gps": "FollowGPSWaypoints gives latitude and longitude, which cannot be placed on the map",
}


def read_motion(carried: CarriedGoal) -> Motion | str:
    """What the fence judges of *carried*, or a sentence saying why the goal cannot be read."""
    goal = carried.goal
    if carried.action is None:
        return Motion(
            f"a goal to {carried.target}",
            unplaceable=f"the goal to {carried.target} is of a type the fence does not know",
        )
    if carried.action == "":
        pose = _pose(goal, f"the message on {carried.target}")
        return pose if isinstance(pose, str) else Motion(f"a goal pose on {carried.target}", (pose,))
    if not isinstance(goal, Mapping):
        return "the goal is not an object"
    what = carried.action.rsplit("/", 1)[-1]
    shape = MOTION_ACTIONS[carried.action]
    if shape in ("pose", "target_pose"):
        pose = _pose(goal.get(shape), shape)
        return pose if isinstance(pose, str) else Motion(what, (pose,))
    if shape in ("poses", "path"):
        return _many(what, goal, shape, path=shape == "path")
    if shape in ("heading", "backup"):
        return _drive(what, goal, backwards=shape == "backup")
    if shape == "spin":
        yaw = _finite(goal.get("target_yaw", 0.0))
        return "target_yaw must be a finite number" if yaw is None else Motion(what, along=0.0)
    if shape == "dock":
        return _dock(what, goal)
    if shape == "route":
        return _route(what, goal)
    return Motion(what, unplaceable=_CANNOT[shape])


def _dock(what: str, goal: Mapping[str, Any]) -> Motion | str:
    if goal.get("use_dock_id", True) is not False:
        return Motion(
            what,
            unplaceable="DockRobot names its dock by dock_id, whose pose is in the docking server's "
            "database, which the fence cannot read (give dock_pose with use_dock_id false)",
        )
    pose = _pose(goal.get("dock_pose"), "dock_pose")
    return pose if isinstance(pose, str) else Motion(what, (pose,))


def _route(what: str, goal: Mapping[str, Any]) -> Motion | str:
    if goal.get("use_poses") is not True:
        return Motion(
            what,
            unplaceable="ComputeAndTrackRoute names route graph nodes (start_id, goal_id), which cannot be "
            "placed (give poses with use_poses true)",
        )
    poses = [_pose(goal.get("goal"), "goal")]
    if goal.get("use_start") is True:
        poses.insert(0, _pose(goal.get("start"), "start"))
    for pose in poses:
        if isinstance(pose, str):
            return pose
    return Motion(what, tuple(p for p in poses if isinstance(p, GoalPose)))


def with_speed(kind: str, payload: Any, speed: float) -> Any:
    """*payload* (an act of *kind* carrying a DriveOnHeading or BackUp goal) with the goal's ``speed`` set to
    *speed* in the sign it had."""
    if not isinstance(payload, Mapping):
        return payload
    if kind != "action":
        return {**payload, "goal": with_speed("action", payload.get("goal"), speed)}
    asked = _finite(payload.get("speed", 0.0)) or 0.0
    return {**payload, "speed": math.copysign(speed, asked)}
