"""Arm acts: which acts move a manipulator, however spelt and carried, and what the arm's judge reads of them.

A trajectory reaches a ros2_control (or ROS 1 ros_control) arm by several carriers: a
``FollowJointTrajectory``
goal (``move_arm``, ``publish_action``), ROS 2's hidden ``<action>/_action/send_goal`` service, ROS 1
actionlib's ``<action>/goal`` topic (a ``…ActionGoal`` message), or a ``trajectory_msgs/JointTrajectory``
published on the controller's ``…/joint_trajectory`` topic. A gripper moves by a ``GripperCommand`` or
``ParallelGripperCommand`` goal by the same carriers; a ``controller_manager`` ``switch_controller`` call
changes which controller drives the joints. :func:`carried_arm` finds each of them in an act, by type in every
spelling (``control_msgs/action/FollowJointTrajectory``, ``control_msgs/FollowJointTrajectory``,
``…Action``, ``…ActionGoal``, ``…_SendGoal``, ``…_Goal``) and, when the type says nothing, by the usual
names (``follow_joint_trajectory``, ``gripper_cmd``, ``switch_controller``). What it finds is read into
plain data (:class:`Trajectory`, :class:`GripperGoal`, :class:`ControllerSwitch`), or a sentence saying why
it cannot be read. Pure; no MCP.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from rosbridge_mcp_server.client import Dialect

__all__ = [
    "MAX_JOINTS",
    "MAX_POINTS",
    "ArmAct",
    "ControllerSwitch",
    "GripperGoal",
    "Trajectory",
    "TrajectoryPoint",
    "arm_action",
    "carried_arm",
    "duration_message",
]

#: Arm actions by type (``pkg/Name``) → what they carry.
ARM_ACTIONS: dict[str, str] = {
    "control_msgs/FollowJointTrajectory": "trajectory",
    "control_msgs/GripperCommand": "gripper",
    "control_msgs/ParallelGripperCommand": "parallel_gripper",
}
#: The usual names (last part) of the arm actions, for a goal whose type says nothing.
ARM_ACTION_NAMES = {
    "follow_joint_trajectory": "trajectory",
    "gripper_cmd": "gripper",
    "gripper_action": "gripper",
}
TRAJECTORY_TOPIC_TYPE = "trajectory_msgs/JointTrajectory"
SWITCH_TYPE = "controller_manager_msgs/SwitchController"
#: Most joints and points a trajectory may hold to be judged (a bound on the judge's work).
MAX_JOINTS = 64
MAX_POINTS = 10_000

_SUFFIXES = ("_SendGoal_Request", "_SendGoal", "ActionGoal", "_Goal", "Action", "Goal")


def arm_action(type_name: str) -> str | None:
    """The arm action (``pkg/Name``) *type_name* names in any spelling, or ``None``."""
    short = Dialect.short_type(type_name.strip().strip("/")) if "/" in type_name else type_name
    if short in ARM_ACTIONS:
        return short
    for suffix in _SUFFIXES:
        if short.endswith(suffix) and short[: -len(suffix)] in ARM_ACTIONS:
            return short[: -len(suffix)]
    return None


@dataclass(frozen=True)
class TrajectoryPoint:
    """One point: when (seconds from the trajectory's start) and where (one position per joint)."""

    time: float
    positions: tuple[float, ...]
    velocities: tuple[float, ...] | None = None


@dataclass(frozen=True)
class Trajectory:
    """A joint trajectory as the controller will run it: from where the arm is, through every point."""

    joints: tuple[str, ...]
    points: tuple[TrajectoryPoint, ...]


@dataclass(frozen=True)
class GripperGoal:
    """A gripper goal: the joint position(s) asked for (metres or radians) and the most effort."""

    positions: tuple[float, ...]
    max_effort: float | None
    #: The joints a ParallelGripperCommand names (``()`` for GripperCommand: the controller's one joint).
    joints: tuple[str, ...] = ()


@dataclass(frozen=True)
class ControllerSwitch:
    """A ``switch_controller`` request: what it starts and stops."""

    activate: tuple[str, ...]
    deactivate: tuple[str, ...]


ArmKind = Literal["trajectory", "gripper", "switch"]


@dataclass(frozen=True)
class ArmAct:
    """What an act does to an arm: its kind, what it is sent to (the action, the topic, the service), and
    what it asks (or the sentence saying why that cannot be read)."""

    kind: ArmKind
    target: str
    body: Trajectory | GripperGoal | ControllerSwitch | str
    what: str  #: e.g. "FollowJointTrajectory", "a JointTrajectory on /arm_controller/joint_trajectory"

    @property
    def controller(self) -> str:
        """The controller's namespace: ``/arm_controller`` for its action or topic."""
        return self.target.rsplit("/", 1)[0] or "/"


def carried_arm(kind: str, name: str, type_name: str, payload: Any) -> ArmAct | None:
    """What an act of *kind* on *name* does to an arm, or ``None`` when it touches none."""
    action = arm_action(type_name) if type_name else None
    body = payload if isinstance(payload, Mapping) else {}
    parent, _, leaf = name.rpartition("/")
    if kind == "action":
        shape = ARM_ACTIONS.get(action or "") or ARM_ACTION_NAMES.get(leaf)
        return None if shape is None else _read(shape, name, payload)
    if kind == "topic":
        short = Dialect.short_type(type_name) if "/" in type_name else type_name
        if short == TRAJECTORY_TOPIC_TYPE:
            return ArmAct(
                "trajectory", name, _trajectory(payload, "the message"), f"a JointTrajectory on {name}"
            )
        by_name = ARM_ACTION_NAMES.get(parent.rsplit("/", 1)[-1]) if leaf == "goal" else None
        if type_name.endswith("ActionGoal") and (action is not None or by_name is not None):
            shape = ARM_ACTIONS.get(action or "") or by_name or ""
            return _read(shape, parent or name, body.get("goal"))
        return None
    if kind == "service":
        short = Dialect.short_type(type_name) if "/" in type_name else type_name
        if short == SWITCH_TYPE or leaf == "switch_controller":
            return ArmAct("switch", name, _switch(payload), "a controller switch")
        action_name, _, hidden = parent.rpartition("/")
        sends = hidden == "_action" and leaf == "send_goal"
        shape = ARM_ACTIONS.get(action or "") if action and ("_SendGoal" in type_name or sends) else None
        if shape is None and sends:
            shape = ARM_ACTION_NAMES.get(action_name.rsplit("/", 1)[-1])
        if shape is not None:
            return _read(shape, action_name if sends else name, body.get("goal"))
    return None


def _read(shape: str, target: str, goal: Any) -> ArmAct:
    if shape == "trajectory":
        if not isinstance(goal, Mapping):
            return ArmAct("trajectory", target, "the goal is not an object", "FollowJointTrajectory")
        multi = goal.get("multi_dof_trajectory")
        if isinstance(multi, Mapping) and multi.get("points"):
            why = "it holds a multi_dof_trajectory, which the arm's limits cannot judge"
            return ArmAct("trajectory", target, why, "FollowJointTrajectory")
        return ArmAct(
            "trajectory", target, _trajectory(goal.get("trajectory"), "trajectory"), "FollowJointTrajectory"
        )
    if shape == "parallel_gripper":
        return ArmAct("gripper", target, _parallel(goal), "ParallelGripperCommand")
    return ArmAct("gripper", target, _gripper(goal), "GripperCommand")


def _finite(value: object) -> float | None:
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return None


def _numbers(value: Any, count: int, where: str) -> tuple[float, ...] | str:
    if not isinstance(value, list) or len(value) != count:
        return f"{where} must hold {count} numbers, one per joint"
    out = []
    for item in value:
        number = _finite(item)
        if number is None:
            return f"{where} holds {item!r}, not a finite number"
        out.append(number)
    return tuple(out)


def _seconds(value: Any, where: str) -> float | str:
    """``time_from_start`` in either spelling (ROS 2 ``sec``/``nanosec``, ROS 1 ``secs``/``nsecs``)."""
    if value is None:
        return 0.0
    if not isinstance(value, Mapping):
        return f"{where} must be {{sec, nanosec}}"
    if not (set(value) <= {"sec", "nanosec"} or set(value) <= {"secs", "nsecs"}):
        # Mixed spellings ({"sec": 9, "secs": 0}) are read differently by the two lines of rosbridge (ROS 1
        # reads only secs/nsecs): what is judged must be what the controller gets.
        return f"{where} must be {{sec, nanosec}} (or ROS 1's {{secs, nsecs}}), one spelling only"
    sec = _finite(value.get("sec", value.get("secs", 0)))
    nano = _finite(value.get("nanosec", value.get("nsecs", 0)))
    if sec is None or nano is None:
        return f"{where} must be {{sec, nanosec}} in finite numbers"
    return sec + nano / 1e9


def _trajectory(value: Any, where: str) -> Trajectory | str:
    if not isinstance(value, Mapping):
        return f"{where} is not a trajectory_msgs/JointTrajectory"
    joints = value.get("joint_names")
    if not isinstance(joints, list) or not joints or not all(isinstance(j, str) and j for j in joints):
        return f"{where}.joint_names must be a list of joint names"
    if len(joints) > MAX_JOINTS or len(set(joints)) != len(joints):
        return f"{where}.joint_names must name each joint once (at most {MAX_JOINTS})"
    points = value.get("points")
    if not isinstance(points, list) or not points:
        return f"{where}.points holds no points"
    if len(points) > MAX_POINTS:
        return f"{where}.points holds {len(points)} points, more than {MAX_POINTS} the arm's judge reads"
    out: list[TrajectoryPoint] = []
    for index, point in enumerate(points):
        here = f"{where}.points[{index}]"
        if not isinstance(point, Mapping):
            return f"{here} is not a JointTrajectoryPoint"
        positions = _numbers(point.get("positions"), len(joints), f"{here}.positions")
        if isinstance(positions, str):
            return positions
        velocities: tuple[float, ...] | None = None
        if point.get("velocities"):
            speeds = _numbers(point.get("velocities"), len(joints), f"{here}.velocities")
            if isinstance(speeds, str):
                return speeds
            velocities = speeds
        time = _seconds(point.get("time_from_start"), f"{here}.time_from_start")
        if isinstance(time, str):
            return time
        if time < 0 or (out and time <= out[-1].time):
            return f"{here}.time_from_start must be later than the point before it (and not negative)"
        out.append(TrajectoryPoint(time, positions, velocities))
    return Trajectory(tuple(joints), tuple(out))


def _gripper(goal: Any) -> GripperGoal | str:
    command = goal.get("command") if isinstance(goal, Mapping) else None
    if not isinstance(command, Mapping):
        return "the goal has no command {position, max_effort}"
    position = _finite(command.get("position", 0.0))
    effort = _finite(command.get("max_effort", 0.0))
    if position is None or effort is None:
        return "command.position and command.max_effort must be finite numbers"
    return GripperGoal((position,), effort)


def _parallel(goal: Any) -> GripperGoal | str:
    command = goal.get("command") if isinstance(goal, Mapping) else None
    if not isinstance(command, Mapping):
        return "the goal has no command (a sensor_msgs/JointState)"
    names = command.get("name") or []
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names) or len(names) > MAX_JOINTS:
        return "command.name must be a list of joint names"
    positions = _numbers(command.get("position"), len(names) or 1, "command.position")
    if isinstance(positions, str):
        return positions
    efforts = command.get("effort") or []
    checked = _numbers(efforts, len(efforts), "command.effort") if isinstance(efforts, list) else "bad"
    if isinstance(checked, str):
        return "command.effort must be finite numbers"
    return GripperGoal(positions, max(checked) if checked else None, tuple(names))


def _names(value: Any) -> tuple[str, ...] | None:
    if value is None:
        return ()
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        return None
    return tuple(value)


def _switch(request: Any) -> ControllerSwitch | str:
    """ROS 2 ``activate_controllers`` / ``deactivate_controllers`` (also the older ``start_controllers`` /
    ``stop_controllers`` both lines know)."""
    body = request if isinstance(request, Mapping) else {}
    lists = [_names(body.get(key)) for key in ("activate_controllers", "start_controllers")]
    stops = [_names(body.get(key)) for key in ("deactivate_controllers", "stop_controllers")]
    if any(v is None for v in lists + stops):
        return "the controller lists must be lists of controller names"
    return ControllerSwitch(
        tuple(n for names in lists for n in names or ()), tuple(n for names in stops for n in names or ())
    )


def duration_message(seconds: float, ros_version: int) -> dict[str, int]:
    """``time_from_start`` for *seconds* in the dialect's spelling."""
    whole = int(seconds)
    nano = round((seconds - whole) * 1e9)
    if nano >= 1_000_000_000:
        whole, nano = whole + 1, nano - 1_000_000_000
    return {"secs": whole, "nsecs": nano} if ros_version == 1 else {"sec": whole, "nanosec": nano}
