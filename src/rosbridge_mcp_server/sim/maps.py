"""Occupancy grids for simulated worlds: a grid, ray-casting against it, and its ``OccupancyGrid`` message.

A :class:`GridMap` holds ``nav_msgs/OccupancyGrid`` cells (``-1`` unknown, ``0`` free, ``100`` occupied,
anything between a cost) row by row from the origin, as map_server loads them. :meth:`GridMap.ray_distance`
walks the cells a ray crosses (Amanatides & Woo), so a laser can be simulated against any map;
:func:`room_map` rasterises the turtle world's room (turtlesim's square arena with its pillar, walls around it
and unknown space beyond). Pure: no I/O, no bridge.
"""

from __future__ import annotations

import math
import struct
from array import array
from dataclasses import dataclass
from typing import Any

__all__ = [
    "FREE",
    "OCCUPIED",
    "UNKNOWN",
    "GridMap",
    "room_map",
]

UNKNOWN = -1
FREE = 0
OCCUPIED = 100
#: map_server's default occupied_thresh (0.65) in OccupancyGrid values: a cell this high stops a ray.
OCCUPIED_THRESHOLD = 65


@dataclass
class GridMap:
    """An occupancy grid: ``width`` × ``height`` cells of ``resolution`` metres, cell (0, 0) at ``origin``.

    ``cells`` are int8 values, row-major from the origin's corner (row 0 is the lowest y), like
    ``OccupancyGrid.data``. The map frame is ``frame_id``; the grid is not rotated in it.
    """

    width: int
    height: int
    resolution: float
    origin: tuple[float, float]
    cells: array[int]
    frame_id: str = "map"

    def __post_init__(self) -> None:
        if self.width <= 0 or self.height <= 0 or self.resolution <= 0:
            raise ValueError("a map needs a positive width, height and resolution")
        if len(self.cells) != self.width * self.height:
            raise ValueError(f"expected {self.width * self.height} cells, got {len(self.cells)}")

    def cell(self, x: float, y: float) -> tuple[int, int] | None:
        """The (column, row) holding the point (x, y) of the map frame, or ``None`` outside the grid."""
        col = math.floor((x - self.origin[0]) / self.resolution)
        row = math.floor((y - self.origin[1]) / self.resolution)
        if 0 <= col < self.width and 0 <= row < self.height:
            return col, row
        return None

    def value(self, x: float, y: float) -> int:
        """The cell value at (x, y); unknown outside the grid."""
        found = self.cell(x, y)
        return UNKNOWN if found is None else self.cells[found[1] * self.width + found[0]]

    def ray_distance(self, x: float, y: float, angle: float, max_range: float) -> float:
        """How far a ray from (x, y) in direction ``angle`` (radians, map frame) goes before it enters an
        occupied cell (value ≥ 65); ``math.inf`` when it travels ``max_range`` or leaves the grid first.

        The ray starts in its own cell without stopping there, so a sensor inside an obstacle still sees out.
        """
        res = self.resolution
        fx = (x - self.origin[0]) / res
        fy = (y - self.origin[1]) / res
        col, row = math.floor(fx), math.floor(fy)
        dx, dy = math.cos(angle), math.sin(angle)
        step_x = 1 if dx > 0 else -1
        step_y = 1 if dy > 0 else -1
        # Distance (in cells) along the ray to the next vertical / horizontal cell boundary, and between them.
        t_max_x = ((col + (step_x > 0)) - fx) / dx if abs(dx) > 1e-12 else math.inf
        t_max_y = ((row + (step_y > 0)) - fy) / dy if abs(dy) > 1e-12 else math.inf
        t_delta_x = abs(1 / dx) if abs(dx) > 1e-12 else math.inf
        t_delta_y = abs(1 / dy) if abs(dy) > 1e-12 else math.inf
        limit = max_range / res
        width, height, cells = self.width, self.height, self.cells
        while True:
            if t_max_x < t_max_y:
                travelled = t_max_x
                t_max_x += t_delta_x
                col += step_x
            else:
                travelled = t_max_y
                t_max_y += t_delta_y
                row += step_y
            if travelled > limit or not (0 <= col < width and 0 <= row < height):
                return math.inf
            if cells[row * width + col] >= OCCUPIED_THRESHOLD:
                return travelled * res

    def message(self, header: dict[str, Any], load_time: dict[str, int]) -> dict[str, Any]:
        """The ``nav_msgs/OccupancyGrid`` in wire form (every field), for a complete publish."""
        return {
            "header": header,
            "info": {
                "map_load_time": load_time,
                "resolution": self.resolution,
                "width": self.width,
                "height": self.height,
                "origin": {
                    "position": {"x": self.origin[0], "y": self.origin[1], "z": 0.0},
                    "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                },
            },
            "data": self.cells.tolist(),
        }


def room_map(
    arena: float,
    pillar: tuple[float, float, float],
    *,
    cells: int = 242,
    margin: float = 0.5,
    wall: float = 0.15,
) -> GridMap:
    """The square room ``[0, arena]²`` with a round ``pillar`` (centre x, y, radius) as a ``cells``² grid.

    The grid spans ``margin`` metres beyond each wall: a ``wall``-thick band of occupied cells just outside
    the room, unknown space beyond it (as a robot that never looked past the walls maps it). Built row by
    row, so a 4,000² map takes a moment, not minutes.
    """
    if cells < 8:
        raise ValueError("a room map needs at least 8 cells a side")
    # MapMetaData.resolution is a float32: keep it exact in one, and centre the room in the grid.
    resolution = struct.unpack("f", struct.pack("f", (arena + 2 * margin) / cells))[0]
    origin = -(cells * resolution - arena) / 2
    grid = array("b", bytes(cells * cells))

    def span(low: float, high: float) -> tuple[int, int]:
        """The columns (or rows) whose centres lie in [low, high]."""
        first = max(0, math.ceil((low - origin) / resolution - 0.5))
        last = min(cells - 1, math.floor((high - origin) / resolution - 0.5))
        return first, last + 1

    unknown_row = array("b", [UNKNOWN]) * cells
    wall_row = array("b", [UNKNOWN]) * cells
    wall_start, wall_end = span(-wall, arena + wall)
    wall_row[wall_start:wall_end] = array("b", [OCCUPIED]) * (wall_end - wall_start)
    room_row = array("b", wall_row)
    free_start, free_end = span(1e-9, arena - 1e-9)
    room_row[free_start:free_end] = array("b", [FREE]) * (free_end - free_start)
    inside_rows = span(1e-9, arena - 1e-9)
    wall_rows = span(-wall, arena + wall)
    cx, cy, radius = pillar
    for row in range(cells):
        if not wall_rows[0] <= row < wall_rows[1]:
            line = unknown_row
        elif not inside_rows[0] <= row < inside_rows[1]:
            line = wall_row
        else:
            y = origin + (row + 0.5) * resolution
            reach = radius * radius - (y - cy) ** 2
            if reach >= 0:
                line = array("b", room_row)
                first, last = span(cx - math.sqrt(reach), cx + math.sqrt(reach))
                line[first:last] = array("b", [OCCUPIED]) * max(0, last - first)
            else:
                line = room_row
        grid[row * cells : (row + 1) * cells] = line
    return GridMap(cells, cells, resolution, (origin, origin), grid)
