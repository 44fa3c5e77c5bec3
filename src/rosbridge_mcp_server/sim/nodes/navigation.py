"""What a navigating robot publishes: the room's ``/map`` (latched), ``/odom`` and a planned ``/plan``.

``/map`` is the room as an occupancy grid in frame ``map`` (the same place as turtlesim's ``world``: a
static ``map → world`` link joins the trees, so ``map → odom → base_link`` resolves). ``/plan`` is a
straight path from the turtle to :data:`PLAN_GOAL`, latched and sent again each second as the turtle moves.
"""

from __future__ import annotations

import asyncio
import math
from typing import Any

from rosbridge_mcp_server.sim.maps import GridMap
from rosbridge_mcp_server.sim.nodes.kit import NodeKit, quaternion_from_yaw
from rosbridge_mcp_server.sim.nodes.room import ROOM_MAP_CELLS, turtle_room_map
from rosbridge_mcp_server.sim.world import TURTLE_HOME

__all__ = ["MAP_SERVER", "PLANNER", "PLAN_GOAL", "MapServer", "Planner", "odometry"]

MAP_SERVER = "/map_server"
PLANNER = "/planner"
#: Where the simulated planner's path leads, in the map frame (metres).
PLAN_GOAL = (9.5, 3.0)
PLAN_PERIOD = 1.0
PLAN_STEP = 0.1


class MapServer:
    """``/map``: the room, published once and latched (map_server's ``transient_local`` on ROS 2)."""

    def __init__(self, kit: NodeKit, cells: int = ROOM_MAP_CELLS) -> None:
        self.kit = kit
        self.cells = cells
        self.map: GridMap | None = None

    def build(self) -> None:
        if self.kit.publisher(
            MAP_SERVER, "/map", self.kit.msg_type("nav_msgs", "OccupancyGrid"), latched=True
        ):
            self.kit.loops.append(self._publish_once)

    async def _publish_once(self) -> None:
        if self.map is None:
            # A large map takes a moment to build: off the loop, once per robot.
            self.map = await asyncio.to_thread(turtle_room_map, self.cells)
        header = self.kit.header(self.map.frame_id)
        self.kit.publish("/map", self.map.message(header, header["stamp"]), complete=True)


class Planner:
    """``/plan``: ``nav_msgs/Path`` from the turtle's pose to :data:`PLAN_GOAL`, every second, latched."""

    def __init__(self, kit: NodeKit) -> None:
        self.kit = kit

    def build(self) -> None:
        if self.kit.publisher(PLANNER, "/plan", self.kit.msg_type("nav_msgs", "Path"), latched=True):
            self.kit.loops.append(self._loop)

    def path(self) -> dict[str, Any]:
        """Poses every :data:`PLAN_STEP` metres along the straight line, each facing the goal."""
        turtle = self.kit.world.turtle
        gx, gy = PLAN_GOAL
        length = math.hypot(gx - turtle.x, gy - turtle.y)
        heading = math.atan2(gy - turtle.y, gx - turtle.x)
        steps = max(1, math.ceil(length / PLAN_STEP))
        header = self.kit.header("map")
        poses = [
            {
                "header": header,
                "pose": {
                    "position": {
                        "x": turtle.x + (gx - turtle.x) * i / steps,
                        "y": turtle.y + (gy - turtle.y) * i / steps,
                        "z": 0.0,
                    },
                    "orientation": quaternion_from_yaw(heading),
                },
            }
            for i in range(steps + 1)
        ]
        return {"header": header, "poses": poses}

    async def _loop(self) -> None:
        while True:
            self.kit.publish("/plan", self.path())
            await asyncio.sleep(PLAN_PERIOD)


def odometry(kit: NodeKit) -> dict[str, Any]:
    """``nav_msgs/Odometry`` of the turtle in ``odom`` (which sits where the turtle started)."""
    turtle = kit.world.turtle
    return {
        "header": kit.header("odom"),
        "child_frame_id": "base_link",
        "pose": {
            "pose": {
                "position": {"x": turtle.x - TURTLE_HOME, "y": turtle.y - TURTLE_HOME, "z": 0.0},
                "orientation": quaternion_from_yaw(turtle.theta),
            }
        },
        "twist": {"twist": {"linear": {"x": turtle.linear}, "angular": {"z": turtle.angular}}},
    }
