"""What the Nav2 robot sees: the map and the laser's ranges, through the :class:`Surroundings` hook; the
default, :class:`TurtleRoom`, is the turtle world's room (the square arena with its pillar) as a grid and
rays."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from rosbridge_mcp_server.sim.nodes.room import PILLAR, ray_distance
from rosbridge_mcp_server.sim.world import TURTLE_ARENA

__all__ = ["MAP_RESOLUTION", "RANGE_MIN", "Grid", "Surroundings", "TurtleRoom"]

MAP_RESOLUTION = 0.1
RANGE_MIN = 0.15


@dataclass(frozen=True)
class Grid:
    """An occupancy grid: row-major cells (0 free, 100 occupied, -1 unknown) from the origin corner."""

    width: int
    height: int
    resolution: float
    origin_x: float
    origin_y: float
    data: list[int]


class Surroundings(Protocol):
    """What the Nav2 robot's map and laser see; the hook for a room model (poses in the map frame)."""

    def grid(self) -> Grid:
        """The map the map server publishes."""

    def ranges(
        self, x: float, y: float, yaw: float, angles: Sequence[float], range_max: float
    ) -> list[float]:
        """One laser sweep from (x, y, yaw): the distance along each angle (relative to yaw), ``inf`` beyond
        ``range_max``."""


class TurtleRoom:
    """The turtle world's room (a square arena with a round pillar), as a grid and as the laser sees it."""

    def grid(self) -> Grid:
        cells = math.ceil(TURTLE_ARENA / MAP_RESOLUTION) + 1
        cx, cy, radius = PILLAR
        data: list[int] = []
        for row in range(cells):
            for col in range(cells):
                x, y = (col + 0.5) * MAP_RESOLUTION, (row + 0.5) * MAP_RESOLUTION
                edge = row in (0, cells - 1) or col in (0, cells - 1)
                data.append(100 if edge or math.hypot(x - cx, y - cy) <= radius else 0)
        return Grid(cells, cells, MAP_RESOLUTION, -MAP_RESOLUTION / 2, -MAP_RESOLUTION / 2, data)

    def ranges(
        self, x: float, y: float, yaw: float, angles: Sequence[float], range_max: float
    ) -> list[float]:
        out: list[float] = []
        for angle in angles:
            distance = ray_distance(x, y, yaw + angle)
            out.append(math.inf if distance > range_max else max(distance, RANGE_MIN))
        return out
