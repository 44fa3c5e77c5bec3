"""The Nav2 world's global planner: A* over the occupancy grid, with the obstacles inflated by the robot's
radius, like Nav2's NavFn/Smac planners on the inflated global costmap (simplified: a cell is either free or
not; no cost gradient).

Pure: no I/O. Poses are metres in the map frame; the grid is :class:`~.surroundings.Grid` (unrotated).
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

from rosbridge_mcp_server.sim.nodes.nav2.surroundings import Grid

__all__ = ["INFLATION_RADIUS", "PlanFailure", "Planner"]

#: The robot's radius plus a little clearance (m): cells nearer than this to an obstacle are not driven on.
INFLATION_RADIUS = 0.25
#: A map cell at or above this value is an obstacle (map_server's occupied_thresh 0.65); unknown (-1) too.
OCCUPIED_FROM = 65


@dataclass(frozen=True)
class PlanFailure:
    """Why no path: Nav2's ComputePathToPose error code and its message."""

    code: int
    message: str


#: nav2_msgs ComputePathToPose error codes (the navigators pass them on).
GOAL_OUTSIDE_MAP = 204
START_OCCUPIED = 205
GOAL_OCCUPIED = 206
NO_VALID_PATH = 208


class Planner:
    """Plans on one grid (inflated once when made)."""

    def __init__(self, grid: Grid, radius: float = INFLATION_RADIUS) -> None:
        self.grid = grid
        self.blocked = self._inflate(grid, radius)

    @staticmethod
    def _inflate(grid: Grid, radius: float) -> bytearray:
        width, height = grid.width, grid.height
        blocked = bytearray(width * height)
        reach = math.ceil(radius / grid.resolution)
        disc = [
            (dc, dr)
            for dr in range(-reach, reach + 1)
            for dc in range(-reach, reach + 1)
            if math.hypot(dc, dr) * grid.resolution <= radius
        ]
        for index, value in enumerate(grid.data):
            if value >= OCCUPIED_FROM or value < 0:
                col, row = index % width, index // width
                for dc, dr in disc:
                    c, r = col + dc, row + dr
                    if 0 <= c < width and 0 <= r < height:
                        blocked[r * width + c] = 1
        return blocked

    def cell(self, x: float, y: float) -> tuple[int, int] | None:
        """The (column, row) of a map point, or ``None`` off the map."""
        grid = self.grid
        col = math.floor((x - grid.origin_x) / grid.resolution)
        row = math.floor((y - grid.origin_y) / grid.resolution)
        if 0 <= col < grid.width and 0 <= row < grid.height:
            return col, row
        return None

    def centre(self, col: int, row: int) -> tuple[float, float]:
        grid = self.grid
        return (grid.origin_x + (col + 0.5) * grid.resolution, grid.origin_y + (row + 0.5) * grid.resolution)

    def free(self, col: int, row: int) -> bool:
        return not self.blocked[row * self.grid.width + col]

    def plan(
        self, start: tuple[float, float], goal: tuple[float, float]
    ) -> list[tuple[float, float]] | PlanFailure:
        """The path from *start* to *goal* (map points, from *start* to *goal*), or why there is none."""
        goal_cell = self.cell(*goal)
        if goal_cell is None:
            return PlanFailure(GOAL_OUTSIDE_MAP, f"Goal ({goal[0]:.2f}, {goal[1]:.2f}) is outside the map")
        if not self.free(*goal_cell):
            return PlanFailure(
                GOAL_OCCUPIED, f"Goal ({goal[0]:.2f}, {goal[1]:.2f}) is in an occupied or inflated cell"
            )
        start_cell = self.cell(*start)
        if start_cell is None:
            return PlanFailure(START_OCCUPIED, "The robot is outside the map")
        cells = self._search(start_cell, goal_cell)
        if cells is None:
            return PlanFailure(NO_VALID_PATH, f"No valid path to ({goal[0]:.2f}, {goal[1]:.2f})")
        points = [self.centre(c, r) for c, r in self._shortcut(cells)]
        return [start, *points[1:-1], goal]

    def _search(self, start: tuple[int, int], goal: tuple[int, int]) -> list[tuple[int, int]] | None:
        width = self.grid.width
        height = self.grid.height
        steps = [(1, 0, 1.0), (-1, 0, 1.0), (0, 1, 1.0), (0, -1, 1.0)]
        steps += [(dc, dr, math.sqrt(2)) for dc in (-1, 1) for dr in (-1, 1)]
        came: dict[tuple[int, int], tuple[int, int]] = {}
        cost = {start: 0.0}
        frontier = [(math.dist(start, goal), start)]
        while frontier:
            _, here = heapq.heappop(frontier)
            if here == goal:
                path = [here]
                while here in came:
                    here = came[here]
                    path.append(here)
                return path[::-1]
            col, row = here
            for dc, dr, length in steps:
                c, r = col + dc, row + dr
                if not (0 <= c < width and 0 <= r < height) or not self.free(c, r):
                    # The robot's own (inflated) cell may be left, never entered.
                    continue
                new = cost[here] + length
                if new < cost.get((c, r), math.inf):
                    cost[(c, r)] = new
                    came[(c, r)] = here
                    heapq.heappush(frontier, (new + math.dist((c, r), goal), (c, r)))
        return None

    def _shortcut(self, cells: list[tuple[int, int]]) -> list[tuple[int, int]]:
        """Fewer corners: each kept cell sees the next in a straight free line (a smoother's job in Nav2)."""
        if len(cells) <= 2:
            return cells
        kept = [cells[0]]
        anchor = 0
        for index in range(2, len(cells)):
            if not self._clear(cells[anchor], cells[index]):
                kept.append(cells[index - 1])
                anchor = index - 1
        kept.append(cells[-1])
        return kept

    def _clear(self, a: tuple[int, int], b: tuple[int, int]) -> bool:
        steps = max(abs(b[0] - a[0]), abs(b[1] - a[1])) * 2
        for i in range(1, steps):
            c = round(a[0] + (b[0] - a[0]) * i / steps)
            r = round(a[1] + (b[1] - a[1]) * i / steps)
            if not self.free(c, r):
                return False
        return True
