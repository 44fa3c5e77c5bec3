"""``nav_msgs/OccupancyGrid`` messages as pictures, with the robot, a planned path and a laser scan on them.

A map's cells are ``-1`` unknown, ``0`` free, ``100`` occupied, and (in costmaps) costs in between. Drawn like
rviz: free white, occupied black, unknown grey, costs shaded from yellow to purple. Cells are one byte each
from the moment they arrive (a 4,000² map is 16 MB, never a list of Python objects beyond the one the JSON
decoder made); when a large map is shrunk, a pixel over any occupied cell stays occupied, so one-cell walls
survive.

A map whose declared width × height would take more than the decode budget (``budget.py``; the cells and the
few copies drawing makes, :data:`_CELL_COST` bytes a cell) is refused before its data is touched.

Pure: no I/O. Coordinates are metres in the map's frame; the grid may be rotated in it (``info.origin``).
"""

from __future__ import annotations

import base64
import math
from array import array
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

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
from rosbridge_mcp_server.robot.budget import budget_problem

__all__ = [
    "MARGIN_BOTTOM",
    "MARGIN_LEFT",
    "OCCUPIED_FROM",
    "Grid",
    "MapError",
    "MapPicture",
    "Overlay",
    "Pose2D",
    "Shares",
    "decode_grid",
    "decode_path",
    "draw_map",
]

#: Occupied from this value on (map_server's occupied_thresh 0.65).
OCCUPIED_FROM = 65
#: Pixels left of and below the map for the axes' labels: map point (x, y) is drawn at
#: (MARGIN_LEFT + (x - x_min) · px/m, map height in pixels - (y - y_min) · px/m) for an unrotated grid.
MARGIN_LEFT = 44
MARGIN_BOTTOM = 38
#: Bytes per cell while a map is decoded and drawn: the cells, the cropped and ranked copies, the walls kept
#: when shrinking (two more), all one byte a cell.
_CELL_COST = 5


class MapError(ValueError):
    """A message that is not a usable occupancy grid; ``str()`` says which field is wrong."""


@dataclass(frozen=True)
class Pose2D:
    """A position (metres) and heading (radians, counter-clockwise from +x) in a plane."""

    x: float
    y: float
    yaw: float


@dataclass(frozen=True)
class Grid:
    """An occupancy grid: cells as one unsigned byte each (``-1`` is 255), row 0 at the origin."""

    width: int
    height: int
    resolution: float
    origin: Pose2D
    frame_id: str
    cells: bytes

    def to_cell(self, x: float, y: float) -> tuple[float, float]:
        """Map-frame metres → (column, row) in cells (fractional; the grid may be rotated)."""
        dx, dy = x - self.origin.x, y - self.origin.y
        c, s = math.cos(self.origin.yaw), math.sin(self.origin.yaw)
        return ((c * dx + s * dy) / self.resolution, (-s * dx + c * dy) / self.resolution)

    def to_map(self, col: float, row: float) -> tuple[float, float]:
        """(column, row) in cells → map-frame metres."""
        gx, gy = col * self.resolution, row * self.resolution
        c, s = math.cos(self.origin.yaw), math.sin(self.origin.yaw)
        return (self.origin.x + c * gx - s * gy, self.origin.y + s * gx + c * gy)


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


def decode_grid(message: Mapping[str, Any]) -> Grid:
    """An ``OccupancyGrid`` message (``data`` ints from JSON, an int8 ``array`` from CBOR, bytes, or base64)
    as a :class:`Grid`."""
    info = message.get("info")
    if not isinstance(info, Mapping):
        raise MapError("The message has no 'info' (MapMetaData): is it a nav_msgs/OccupancyGrid?")
    width, height = info.get("width"), info.get("height")
    resolution = info.get("resolution")
    if not isinstance(width, int) or not isinstance(height, int) or width <= 0 or height <= 0:
        raise MapError(f"The map's size is {width!r} x {height!r} cells; both must be positive.")
    if not isinstance(resolution, int | float) or not resolution > 0 or not math.isfinite(resolution):
        raise MapError(f"The map's resolution is {resolution!r}; it must be positive metres per cell.")
    problem = budget_problem("The map", f"{width}x{height} cells", width * height * _CELL_COST)
    if problem is not None:
        raise MapError(problem)
    data = message.get("data")
    if isinstance(data, str):
        cells = base64.b64decode(data)
    elif isinstance(data, bytes | bytearray):
        cells = bytes(data)
    elif isinstance(data, array) and data.itemsize == 1:
        # A CBOR typed array (tag 72, int8): its bytes are the cells, no list of ints in between.
        cells = data.tobytes()
    elif isinstance(data, list):
        try:
            cells = array("b", data).tobytes()
        except (OverflowError, TypeError):
            raise MapError("The map's data holds values that are not int8 cells (-1 to 100).") from None
    else:
        raise MapError("The map message has no 'data' array.")
    if len(cells) != width * height:
        raise MapError(f"The map has {len(cells)} cells of data; {width} x {height} needs {width * height}.")
    origin = info.get("origin")
    origin = origin if isinstance(origin, Mapping) else {}
    position = origin.get("position")
    position = position if isinstance(position, Mapping) else {}
    header = message.get("header")
    frame = header.get("frame_id", "") if isinstance(header, Mapping) else ""
    return Grid(
        width=width,
        height=height,
        resolution=float(resolution),
        origin=Pose2D(
            _number(position.get("x")), _number(position.get("y")), yaw_of(origin.get("orientation"))
        ),
        frame_id=str(frame).lstrip("/"),
        cells=cells,
    )


def yaw_of(quaternion: object) -> float:
    """The rotation about z of a ``geometry_msgs/Quaternion`` (identity when missing or malformed)."""
    if not isinstance(quaternion, Mapping):
        return 0.0
    x, y, z, w = (_number(quaternion.get(k), 1.0 if k == "w" else 0.0) for k in ("x", "y", "z", "w"))
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def _number(value: object, default: float = 0.0) -> float:
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return default


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
    if window is not None:
        corners = [grid.to_cell(x, y) for x in (window[0], window[2]) for y in (window[1], window[3])]
        col0 = max(0, math.floor(min(c for c, _ in corners)))
        col1 = min(grid.width, math.ceil(max(c for c, _ in corners)))
        row0 = max(0, math.floor(min(r for _, r in corners)))
        row1 = min(grid.height, math.ceil(max(r for _, r in corners)))
        if col1 <= col0 or row1 <= row0:
            col0, col1, row0, row1 = 0, grid.width, 0, grid.height
    else:
        col0, col1, row0, row1 = 0, grid.width, 0, grid.height
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


def decode_path(message: Mapping[str, Any]) -> tuple[str, list[tuple[float, float]]]:
    """A ``nav_msgs/Path``: its frame and the (x, y) of its poses (malformed poses skipped)."""
    header = message.get("header")
    frame = str(header.get("frame_id", "")).lstrip("/") if isinstance(header, Mapping) else ""
    points: list[tuple[float, float]] = []
    poses = message.get("poses")
    for stamped in poses if isinstance(poses, list) else ():
        pose = stamped.get("pose") if isinstance(stamped, Mapping) else None
        position = pose.get("position") if isinstance(pose, Mapping) else None
        if isinstance(position, Mapping):
            x, y = position.get("x"), position.get("y")
            if (
                isinstance(x, int | float)
                and isinstance(y, int | float)
                and math.isfinite(x)
                and math.isfinite(y)
            ):
                points.append((float(x), float(y)))
    return frame, points
