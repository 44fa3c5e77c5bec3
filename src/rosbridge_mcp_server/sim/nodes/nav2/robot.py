"""One Nav2 robot's state: its pose in the map frame and the velocity command it follows."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

from rosbridge_mcp_server.sim.nodes.kit import quaternion_from_yaw
from rosbridge_mcp_server.sim.world import TURTLE_ARENA, TURTLE_HOME

__all__ = ["Nav2Robot", "pose"]


@dataclass
class Nav2Robot:
    """One robot's state in the map frame: pose (m, rad), the command it follows (m/s, rad/s)."""

    namespace: str
    x: float = TURTLE_HOME
    y: float = TURTLE_HOME
    yaw: float = 0.0
    linear: float = 0.0
    angular: float = 0.0
    command_time: float = 0.0
    commands: int = 0
    #: Lifecycle state id of each lifecycle node (by name relative to the namespace).
    states: dict[str, int] = field(default_factory=dict)
    #: What a fault silenced (``health.py``): a topic (``"scan"``), a transform (``"odom->base_footprint"``).
    quiet: set[str] = field(default_factory=set)

    def step(self, dt: float) -> None:
        if time.monotonic() - self.command_time > 0.5:
            self.linear = self.angular = 0.0
        self.yaw = math.atan2(math.sin(self.yaw + self.angular * dt), math.cos(self.yaw + self.angular * dt))
        self.x = min(max(self.x + math.cos(self.yaw) * self.linear * dt, 0.2), TURTLE_ARENA - 0.2)
        self.y = min(max(self.y + math.sin(self.yaw) * self.linear * dt, 0.2), TURTLE_ARENA - 0.2)


def pose(x: float, y: float, yaw: float) -> dict[str, Any]:
    """A ``geometry_msgs/Pose`` at (x, y) turned *yaw* about z."""
    return {"position": {"x": x, "y": y, "z": 0.0}, "orientation": quaternion_from_yaw(yaw)}
