"""``nav_msgs/OccupancyGrid`` maps as pictures, with the robot, a planned path and a laser scan on them.

The grid itself (``robot/occupancy.py``: cells one byte each, ``-1`` unknown, ``0`` free, ``100`` occupied,
costs in between) is drawn like rviz: free white, occupied black, unknown grey, costs shaded from yellow to
purple. When a large map is shrunk, a pixel over any occupied cell stays occupied, so one-cell walls survive.

Pure: no I/O. Coordinates are metres in the map's frame; the grid may be rotated in it (``info.origin``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from PIL import Image, ImageChops, ImageDraw

from rosbridge_mcp_server.pictures.drawing import (
    OBSTACLE_COLOUR,
    PATH_COLOUR,
    TEXT_COLOUR,
    draw_robot,
    draw_scale_bar,
    font,
    label,
    ticks,
)
from rosbridge_mcp_server.robot.occupancy import OCCUPIED_FROM, Grid, Pose2D

__all__ = [
    "MARGIN_BOTTOM",
    "MARGIN_LEFT",
    "MapPicture",
    "Overlay",
    "Shares",
    "draw_map",
]

#: Pixels left of and below the map for the axes' labels: map point (x, y) is drawn at
#: (MARGIN_LEFT + (x - x_min) · px/m, map height in pixels - (y - y_min) · px/m) for an unrotated grid.
MARGIN_LEFT = 44
MARGIN_BOTTOM = 38


@dataclass(frozen=True)
class Shares:
    """How much of the map is known, free, occupied, or a cost between (fractions of all cells)."""

    known: float
    free: float
    occupied: float
    cost: float


@dataclass(frozen=True)
class Overlay:
    """What to draw on the map: the robot, a path, scan hits — all in the map frame."""

    robot: Pose2D | None = None
    path: Sequence[tuple[float, float]] = ()
    hits: Sequence[tuple[float, float]] = ()


@dataclass(frozen=True)
class MapPicture:
    """The drawn map and what it shows: the window (map-frame metres) and the scale."""

    image: Image.Image
    shares: Shares
    window: tuple[float, float, float, float]  # x_min, y_min, x_max, y_max
    pixels_per_metre: float
    scale_bar: float


def shares(grid: Grid, histogram: Sequence[int]) -> Shares:
    """Shares of unknown (255), free (0), occupied (≥ 65) and cost (1–64) from a 256-bin histogram."""
    total = grid.width * grid.height
    free = histogram[0]
    occupied = sum(histogram[OCCUPIED_FROM:101])
    cost = sum(histogram[1:OCCUPIED_FROM])
    known = free + occupied + cost
    return Shares(known / total, free / total, occupied / total, cost / total)


# Draw order by cell value: what must survive shrinking (occupied) outranks costs, unknown and free.
def _rank_table() -> tuple[list[int], list[tuple[int, int, int]]]:
    """Cell byte → rank (0 free … 255 occupied), and each rank's colour."""
    ranks = [1] * 256  # anything outside -1..100 is drawn as unknown
    colours: list[tuple[int, int, int]] = [(205, 205, 205)] * 256
    ranks[0] = 0
    colours[0] = (254, 254, 254)
    for value in range(1, OCCUPIED_FROM):
        rank = 1 + value  # 2..65
        ranks[value] = rank
        t = value / OCCUPIED_FROM
        # light yellow → purple as the cost rises
        colours[rank] = (round(255 - 60 * t), round(235 - 200 * t), round(120 + 60 * t))
    for value in range(OCCUPIED_FROM, 101):
        ranks[value] = 255
    colours[255] = (0, 0, 0)
    colours[1] = (205, 205, 205)
    return ranks, colours


_RANKS, _RANK_COLOURS = _rank_table()
_PALETTE = [channel for colour in _RANK_COLOURS for channel in colour]
_OCCUPIED = [255 if OCCUPIED_FROM <= value <= 100 else 0 for value in range(256)]
_ANY = [0] + [255] * 255


def draw_map(
    grid: Grid,
    *,
    max_size: int,
    overlay: Overlay,
    window: tuple[float, float, float, float] | None = None,
) -> MapPicture:
    """The map (or the ``window`` of it, map-frame metres) at most ``max_size`` pixels a side, plus axes
    ticks in metres, a scale bar, and the overlay. Grids rotated in their frame are drawn in grid axes."""
    raw = Image.frombuffer("L", (grid.width, grid.height), grid.cells, "raw", "L", 0, 1)
    found = shares(grid, raw.histogram())
    # Cells → columns/rows of the picture: the grid's own axes, row 0 at the bottom.
    col0, col1, row0, row1 = _cells_shown(grid, window)
    cells_w, cells_h = col1 - col0, row1 - row0
    plot = max(16, max_size - MARGIN_LEFT)
    scale = min(plot / cells_w, (max_size - MARGIN_BOTTOM) / cells_h)  # pixels per cell
    out_w, out_h = max(1, round(cells_w * scale)), max(1, round(cells_h * scale))
    cropped = raw.crop((col0, row0, col1, row1))
    ranked = cropped.point(_RANKS).resize((out_w, out_h), Image.Resampling.NEAREST)
    if scale < 0.75:
        # Shrinking samples one cell per pixel and would lose one-cell walls: a pixel covering any occupied
        # cell (box average above zero) is drawn occupied.
        walls = cropped.point(_OCCUPIED).resize((out_w, out_h), Image.Resampling.BOX).point(_ANY)
        ranked = ImageChops.lighter(ranked, walls)
    ranked = ranked.transpose(Image.Transpose.FLIP_TOP_BOTTOM)
    coloured = Image.frombuffer("P", ranked.size, ranked.tobytes(), "raw", "P", 0, 1)
    coloured.putpalette(_PALETTE)
    image = Image.new("RGB", (out_w + MARGIN_LEFT, out_h + MARGIN_BOTTOM), (255, 255, 255))
    # The overlay is drawn on the map's own picture, so what falls outside it (a scan's far hits around the
    # robot) is cut at the plot's edge instead of covering the axes' labels.
    drawn = coloured.convert("RGB")
    over = ImageDraw.Draw(drawn)

    def pixel(x: float, y: float) -> tuple[float, float]:
        col, row = grid.to_cell(x, y)
        return ((col - col0) * scale, out_h - (row - row0) * scale)

    pixels_per_metre = scale / grid.resolution
    if overlay.path:
        points = [pixel(x, y) for x, y in overlay.path]
        if len(points) > 1:
            over.line(points, fill=PATH_COLOUR, width=3, joint="curve")
        end = points[-1]
        over.ellipse((end[0] - 4, end[1] - 4, end[0] + 4, end[1] + 4), fill=PATH_COLOUR)
    for x, y in overlay.hits:
        px, py = pixel(x, y)
        over.rectangle((px - 1, py - 1, px + 1, py + 1), fill=OBSTACLE_COLOUR)
    if overlay.robot is not None:
        robot = overlay.robot
        draw_robot(over, pixel(robot.x, robot.y), robot.yaw - grid.origin.yaw, 0.25 * pixels_per_metre)
    image.paste(drawn, (MARGIN_LEFT, 0))
    draw = ImageDraw.Draw(image)
    _draw_axes(draw, grid, cells=(col0, col1, row0, row1), out_w=out_w, out_h=out_h)
    # Below the axis labels, outside the map: a box in a corner would hide that corner of the map.
    bar = draw_scale_bar(draw, pixels_per_metre, (MARGIN_LEFT, out_h + MARGIN_BOTTOM - 6), boxed=False)
    x_min, y_min = grid.to_map(col0, row0)
    x_max, y_max = grid.to_map(col1, row1)
    return MapPicture(image, found, (x_min, y_min, x_max, y_max), pixels_per_metre, bar)


def _cells_shown(grid: Grid, window: tuple[float, float, float, float] | None) -> tuple[int, int, int, int]:
    """(first column, end column, first row, end row) of the cells *window* covers; the whole grid without
    one, or when the window misses it."""
    whole = (0, grid.width, 0, grid.height)
    if window is None:
        return whole
    corners = [grid.to_cell(x, y) for x in (window[0], window[2]) for y in (window[1], window[3])]
    col0 = max(0, math.floor(min(c for c, _ in corners)))
    col1 = min(grid.width, math.ceil(max(c for c, _ in corners)))
    row0 = max(0, math.floor(min(r for _, r in corners)))
    row1 = min(grid.height, math.ceil(max(r for _, r in corners)))
    return whole if col1 <= col0 or row1 <= row0 else (col0, col1, row0, row1)


def _draw_axes(
    draw: ImageDraw.ImageDraw,
    grid: Grid,
    *,
    cells: tuple[int, int, int, int],
    out_w: int,
    out_h: int,
) -> None:
    """Metre ticks of the grid's axes along the bottom (x) and left (y) edges."""
    col0, col1, row0, row1 = cells
    x_low, x_high = col0 * grid.resolution, col1 * grid.resolution
    y_low, y_high = row0 * grid.resolution, row1 * grid.resolution
    # In grid axes: for an unrotated grid these are map-frame x and y.
    ox, oy = grid.origin.x, grid.origin.y
    plain = abs(grid.origin.yaw) < 1e-9
    shift_x, shift_y = (ox, oy) if plain else (0.0, 0.0)
    small = font(11)
    for value in ticks(x_low + shift_x, x_high + shift_x, max(2, out_w // 90)):
        px = MARGIN_LEFT + ((value - shift_x) / grid.resolution - col0) * (out_w / max(1, col1 - col0))
        draw.line((px, out_h, px, out_h + 4), fill=TEXT_COLOUR)
        if px < MARGIN_LEFT + out_w - 30:  # room for the axis name
            draw.text((px, out_h + 4), label(value), fill=TEXT_COLOUR, font=small, anchor="ma")
    for value in ticks(y_low + shift_y, y_high + shift_y, max(2, out_h // 70)):
        py = out_h - ((value - shift_y) / grid.resolution - row0) * (out_h / max(1, row1 - row0))
        draw.line((MARGIN_LEFT - 4, py, MARGIN_LEFT, py), fill=TEXT_COLOUR)
        if py > 18:  # room for the axis name
            draw.text((MARGIN_LEFT - 6, py), label(value), fill=TEXT_COLOUR, font=small, anchor="rm")
    draw.text((MARGIN_LEFT + out_w - 2, out_h + 4), "x m", fill=TEXT_COLOUR, font=small, anchor="ra")
    draw.text((2, 2), "y m", fill=TEXT_COLOUR, font=small)
