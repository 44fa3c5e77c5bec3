"""A joint goal turned into the trajectory ``move_arm`` sends: which controller, which joints, and how long.

The timing is computed here from the URDF's joint speeds and the policy's speed share, never taken from the
model: the goal is one point, reached when the slowest joint (at ``speed_scale`` × its URDF velocity) gets
there; the controller interpolates linearly to it (positions only), so no joint goes faster than that. The
guard judges the result like any other trajectory (``safety/arm.py``). Pure; no MCP.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from rosbridge_mcp_server.robot.arm.controllers import Controller
from rosbridge_mcp_server.robot.arm.urdf import Joint, Robot
from rosbridge_mcp_server.robot.arm_goals import duration_message

__all__ = [
    "DEFAULT_ACTION",
    "FALLBACK_SPEED",
    "MIN_DURATION",
    "ArmPlan",
    "PlanError",
    "plan_motion",
    "shown",
    "to_si",
]

#: ros2_control's usual arm controller action, when the controller manager cannot be asked.
DEFAULT_ACTION = "/arm_controller/follow_joint_trajectory"
#: The shortest motion (s): a tiny move still gets a sane time.
MIN_DURATION = 0.2
#: Speed (rad/s, m/s) before the share for a joint whose URDF gives none.
FALLBACK_SPEED = {"revolute": 1.0, "prismatic": 0.1}


class PlanError(ValueError):
    """A joint goal that cannot be planned; ``str()`` says why, for the model."""


@dataclass(frozen=True)
class ArmPlan:
    """What ``move_arm`` sends: the action, the goal, the joints' targets and the motion's duration."""

    action: str
    controller: str
    joints: tuple[str, ...]
    start: tuple[float, ...]
    target: tuple[float, ...]
    duration: float
    goal: dict[str, object]


def to_si(joint: Joint, value: float) -> float:
    """A user's value (degrees for a revolute or continuous joint, metres for a prismatic one) in SI units."""
    return value if joint.linear else math.radians(value)


def shown(joint: Joint, value: float) -> float:
    """*value* (SI) as the user gives it: degrees, or metres."""
    return round(value, 4) if joint.linear else round(math.degrees(value), 2)


def _controller_for(
    controllers: tuple[Controller, ...], joints: set[str], given: str | None
) -> Controller | None:
    if given:
        leaf = given.strip("/").split("/")[0]
        return next((c for c in controllers if c.name == leaf), None)
    fitting = [c for c in controllers if joints <= set(c.joints) and "gripper" not in c.type.lower()]
    active = [c for c in fitting if c.active]
    return (active or fitting)[0] if fitting else None


def plan_motion(
    robot: Robot,
    positions: Mapping[str, float],
    targets: Mapping[str, float],
    *,
    controllers: tuple[Controller, ...],
    controller: str | None,
    speed_scale: float,
    ros_version: int,
) -> ArmPlan:
    """The trajectory to *targets* (SI units) from *positions*: every joint of the controller, those not named
    held where they are, timed at *speed_scale* of the URDF speeds."""
    chosen = _controller_for(controllers, set(targets), controller)
    if chosen is not None:
        names = tuple(chosen.joints)
        action = f"/{chosen.name}/follow_joint_trajectory"
        if not set(targets) <= set(names):
            other = ", ".join(sorted(set(targets) - set(names)))
            raise PlanError(f"controller {chosen.name} does not move {other}; it moves {', '.join(names)}")
    elif controllers and not controller:
        moved = ", ".join(sorted(targets))
        raise PlanError(
            f"no trajectory controller of the controller manager moves {moved} (a gripper's joints "
            "move by the gripper's own action)"
        )
    elif controller:
        action = controller if controller.startswith("/") else f"/{controller}"
        if not action.endswith("/follow_joint_trajectory"):
            action = f"{action.rstrip('/')}/follow_joint_trajectory"
        names = tuple(targets)
    else:
        action, names = DEFAULT_ACTION, tuple(targets)
    unknown = [name for name in names if name not in positions]
    if unknown:
        raise PlanError(f"where {', '.join(unknown)} is now was not read from /joint_states")
    start = tuple(positions[name] for name in names)
    target = tuple(targets.get(name, positions[name]) for name in names)
    duration = MIN_DURATION
    for name, a, b in zip(names, start, target, strict=True):
        joint = robot.joint(name)
        linear = joint is not None and joint.linear
        limit = joint.limits.velocity if joint is not None else None
        speed = (limit if limit else FALLBACK_SPEED["prismatic" if linear else "revolute"]) * speed_scale
        duration = max(duration, abs(b - a) / speed)
    # Whole milliseconds, rounded up: the time sent is never shorter than the speed allows.
    duration = math.ceil(duration * 1000) / 1000
    goal: dict[str, object] = {
        "trajectory": {
            "joint_names": list(names),
            "points": [
                {"positions": list(target), "time_from_start": duration_message(duration, ros_version)}
            ],
        }
    }
    return ArmPlan(action, action.rsplit("/", 1)[0].lstrip("/"), names, start, target, duration, goal)
