"""Velocity commands: recognising a Twist / TwistStamped in either dialect, measuring it, scaling it down.

A velocity command is recognised by its type, never by its topic: a robot may take Twists on ``/cmd_vel``,
``/base/cmd_vel_unstamped`` or ``/turtle1/cmd_vel``, and a cap that looked at topic names would miss one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rosbridge_mcp_server.client import Dialect

__all__ = [
    "TWIST",
    "TWIST_STAMPED",
    "Velocity",
    "clamp_text",
    "is_velocity_type",
    "measure",
    "scaled",
    "stamped",
    "zero_command",
]

#: The velocity command types, named canonically (the dialect compares either line's spelling with them).
TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"


def is_velocity_type(type_name: str) -> bool:
    """Whether ``type_name`` is a Twist or TwistStamped, in either dialect's spelling."""
    return Dialect.same_type(type_name, TWIST) or stamped(type_name)


def stamped(type_name: str) -> bool:
    """Whether ``type_name`` is a TwistStamped, in either dialect's spelling."""
    return Dialect.same_type(type_name, TWIST_STAMPED)


@dataclass(frozen=True)
class Velocity:
    """The lengths of a command's linear and angular vectors (NaN when a component is not a finite number)."""

    linear: float
    angular: float

    @property
    def finite(self) -> bool:
        return math.isfinite(self.linear) and math.isfinite(self.angular)


def _twist(type_name: str, message: Any) -> Any:
    if not isinstance(message, dict):
        return None
    return message.get("twist") if stamped(type_name) else message


def _length(vector: Any) -> float:
    if vector is None:
        return 0.0
    if not isinstance(vector, dict):
        return math.nan
    total = 0.0
    for axis in ("x", "y", "z"):
        value = vector.get(axis, 0.0)
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            return math.nan
        total += float(value) ** 2
    return math.sqrt(total)


def measure(type_name: str, message: Any) -> Velocity:
    """The linear (m/s) and angular (rad/s) speed a Twist / TwistStamped message commands."""
    twist = _twist(type_name, message)
    if twist is None:
        return Velocity(0.0, 0.0)
    if not isinstance(twist, dict):
        return Velocity(math.nan, math.nan)
    return Velocity(_length(twist.get("linear")), _length(twist.get("angular")))


def _scale(vector: Any, factor: float) -> Any:
    if not isinstance(vector, dict):
        return vector
    return {key: (value * factor if key in ("x", "y", "z") else value) for key, value in vector.items()}


def scaled(type_name: str, message: dict[str, Any], linear: float, angular: float) -> dict[str, Any]:
    """A copy of ``message`` with its linear vector scaled by ``linear`` and its angular by ``angular``.

    Scaling keeps the direction: a command to drive diagonally stays diagonal, only slower.
    """
    twist = _twist(type_name, message)
    if not isinstance(twist, dict):
        return message
    new_twist = dict(twist)
    if "linear" in twist:
        new_twist["linear"] = _scale(twist["linear"], linear)
    if "angular" in twist:
        new_twist["angular"] = _scale(twist["angular"], angular)
    if stamped(type_name):
        return {**message, "twist": new_twist}
    return new_twist


def zero_command(type_name: str, now: float, frame_id: str = "") -> dict[str, Any]:
    """A complete "stand still" message of ``type_name``; a TwistStamped is stamped ``now`` (Unix seconds).

    A zero stamp could look stale to a controller that drops old commands, so the stop carries the time
    (spelled ``sec``/``nanosec``: the client respells it for ROS 1).
    """
    zeros = {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
    if not stamped(type_name):
        return zeros
    seconds = int(now)
    fraction = int((now - seconds) * 1e9)
    stamp = {"sec": seconds, "nanosec": fraction}
    return {"header": {"stamp": stamp, "frame_id": frame_id}, "twist": zeros}


def clamp_text(type_name: str, before: Any, after: Any) -> str:
    """How the velocity caps changed a command, e.g. ``scaled down to the caps: linear 2 → 0.5 m/s``."""
    old, new = measure(type_name, before), measure(type_name, after)
    parts = []
    if not math.isclose(old.linear, new.linear):
        parts.append(f"linear {old.linear:g} → {new.linear:g} m/s")
    if not math.isclose(old.angular, new.angular):
        parts.append(f"angular {old.angular:g} → {new.angular:g} rad/s")
    return "scaled down to the [velocity] caps: " + ", ".join(parts)
