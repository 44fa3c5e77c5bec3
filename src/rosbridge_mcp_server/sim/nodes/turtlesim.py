"""``/turtlesim``: the turtle, driven by ``/turtle1/cmd_vel``, and its services."""

from __future__ import annotations

import asyncio
import logging
import math
import time
from typing import Any

from rosbridge_mcp_server.sim.nodes.kit import NodeKit

__all__ = ["COMMAND_HOLD", "TURTLESIM", "TURTLE_PERIOD", "Turtlesim"]

log = logging.getLogger("rosbridge_mcp_server.sim")

TURTLESIM = "/turtlesim"
TURTLE_PERIOD = 1.0 / 25  # pose at 25 Hz
COMMAND_HOLD = 1.0  # a velocity command holds this long, then the turtle stops


class Turtlesim:
    """The turtle: subscribes its velocity command, publishes its pose and the colour under it."""

    def __init__(self, kit: NodeKit) -> None:
        self.kit = kit

    def build(self) -> None:
        kit = self.kit
        twist = kit.type("geometry_msgs/msg/Twist", "geometry_msgs/Twist", "msg")
        if twist is not None:
            kit.graph.add_subscriber(TURTLESIM, "/turtle1/cmd_vel", twist, self._on_cmd_vel)
        kit.publisher(TURTLESIM, "/turtle1/pose", kit.msg_type("turtlesim", "Pose"))
        kit.publisher(TURTLESIM, "/turtle1/color_sensor", kit.msg_type("turtlesim", "Color"))
        empty = kit.type("std_srvs/srv/Empty", "std_srvs/Empty", "srv")
        kit.service(TURTLESIM, "/reset", empty, self._reset)
        kit.service(TURTLESIM, "/clear", empty, self._clear)
        kit.service(
            TURTLESIM,
            "/turtle1/teleport_absolute",
            kit.type("turtlesim/srv/TeleportAbsolute", "turtlesim/TeleportAbsolute", "srv"),
            self._teleport_absolute,
        )
        kit.service(
            TURTLESIM,
            "/turtle1/teleport_relative",
            kit.type("turtlesim/srv/TeleportRelative", "turtlesim/TeleportRelative", "srv"),
            self._teleport_relative,
        )
        kit.loops.append(self._loop)

    def background(self) -> tuple[int, int, int]:
        """turtlesim's background colour from its parameters (the camera paints with it too)."""
        params = self.kit.world.params
        sep = ":" if self.kit.ros2 else "/"
        values = []
        for channel, default in (("r", 69), ("g", 86), ("b", 255)):
            value = params.get(f"{TURTLESIM}{sep}background_{channel}", default)
            values.append(
                int(value) % 256
                if isinstance(value, int | float) and not isinstance(value, bool)
                else default
            )
        return values[0], values[1], values[2]

    def _on_cmd_vel(self, msg: dict[str, Any], _source: int) -> None:
        world = self.kit.world
        if not world.enabled:
            log.info("cmd_vel ignored: the robot is disabled (/set_enabled)")
            return
        turtle = world.turtle
        turtle.linear = float(msg.get("linear", {}).get("x", 0.0))
        turtle.angular = float(msg.get("angular", {}).get("z", 0.0))
        turtle.command_time = time.monotonic()
        turtle.commands += 1
        world.notify()

    async def _loop(self) -> None:
        world = self.kit.world
        last = time.monotonic()
        while True:
            await asyncio.sleep(TURTLE_PERIOD)
            now = time.monotonic()
            turtle = world.turtle
            if (turtle.linear or turtle.angular) and now - turtle.command_time > COMMAND_HOLD:
                turtle.linear = turtle.angular = 0.0
            turtle.step(now - last)
            last = now
            self.kit.publish(
                "/turtle1/pose",
                {
                    "x": turtle.x,
                    "y": turtle.y,
                    "theta": turtle.theta,
                    "linear_velocity": turtle.linear,
                    "angular_velocity": turtle.angular,
                },
            )
            r, g, b = self.background()
            self.kit.publish("/turtle1/color_sensor", {"r": r, "g": g, "b": b})
            world.notify()

    async def _reset(self, request: dict[str, Any]) -> dict[str, Any]:
        self.kit.world.turtle.reset()
        self.kit.world.notify()
        return {}

    @staticmethod
    async def _clear(request: dict[str, Any]) -> dict[str, Any]:
        return {}

    async def _teleport_absolute(self, request: dict[str, Any]) -> dict[str, Any]:
        turtle = self.kit.world.turtle
        turtle.x, turtle.y, turtle.theta = float(request["x"]), float(request["y"]), float(request["theta"])
        self.kit.world.notify()
        return {}

    async def _teleport_relative(self, request: dict[str, Any]) -> dict[str, Any]:
        turtle = self.kit.world.turtle
        turtle.theta = math.remainder(turtle.theta + float(request["angular"]), math.tau)
        turtle.x += math.cos(turtle.theta) * float(request["linear"])
        turtle.y += math.sin(turtle.theta) * float(request["linear"])
        self.kit.world.notify()
        return {}
