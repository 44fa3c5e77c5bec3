"""The room around the turtle, for the range sensors: turtlesim's square arena with a round pillar in it.

The laser scanner and the depth camera cast rays from the turtle's pose against the four walls and the
pillar (exactly, not against the grid: the same answer at any map resolution, and cheap at 5 Hz); ``/map``
is the same room as an occupancy grid (:func:`turtle_room_map`). The turtle itself drives through the
pillar (turtlesim knows nothing of it); from inside, the pillar is not seen.
"""

from __future__ import annotations

import math

from rosbridge_mcp_server.sim.maps import GridMap, room_map
from rosbridge_mcp_server.sim.world import TURTLE_ARENA

__all__ = ["CEILING_HEIGHT", "PILLAR", "ROOM_MAP_CELLS", "ray_distance", "turtle_room_map"]

#: Centre x, centre y and radius of the pillar, in metres (turtlesim coordinates).
PILLAR = (8.5, 8.5, 0.5)
#: Height of the room's ceiling (the depth camera sees it above the horizon).
CEILING_HEIGHT = 2.5
#: Cells a side of the room's map by default: the arena and half a metre beyond each wall in 0.05 m cells.
ROOM_MAP_CELLS = 242


def turtle_room_map(cells: int = ROOM_MAP_CELLS) -> GridMap:
    """The room as ``/map`` publishes it: frame ``map``, which coincides with turtlesim's ``world``."""
    return room_map(TURTLE_ARENA, PILLAR, cells=cells)


def ray_distance(x: float, y: float, angle: float) -> float:
    """How far a ray from (x, y) in direction ``angle`` (radians, turtlesim's frame) travels to a wall or
    the pillar."""
    dx, dy = math.cos(angle), math.sin(angle)
    best = math.inf
    # The four walls of the square [0, ARENA] x [0, ARENA].
    if dx > 1e-12:
        best = min(best, (TURTLE_ARENA - x) / dx)
    elif dx < -1e-12:
        best = min(best, -x / dx)
    if dy > 1e-12:
        best = min(best, (TURTLE_ARENA - y) / dy)
    elif dy < -1e-12:
        best = min(best, -y / dy)
    cx, cy, radius = PILLAR
    ox, oy = x - cx, y - cy
    c = ox * ox + oy * oy - radius * radius
    if c > 0:
        b = ox * dx + oy * dy
        disc = b * b - c
        if b < 0 and disc >= 0:
            best = min(best, -b - math.sqrt(disc))
    return max(best, 0.0)
