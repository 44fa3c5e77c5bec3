"""``nav_msgs/OccupancyGrid`` and ``nav_msgs/Path`` messages as data: the grid, a pose in its plane, a path.

A map's cells are ``-1`` unknown, ``0`` free, ``100`` occupied, and (in costmaps) costs in between. Cells are
one byte each from the moment they arrive (a 4,000² map is 16 MB, never a list of Python objects beyond the
one the JSON decoder made). A map whose declared width × height would take more than the decode budget
(``budget.py``; the cells and the few copies drawing it makes, :data:`_CELL_COST` bytes a cell) is refused
before its data is touched.

What navigation judges a goal against (``navigation.py``) and what ``pictures/maps.py`` draws; a
quaternion's yaw (:func:`yaw_of`, the one copy) and points moved in the plane. Pure: no I/O
(``map_reader.py`` reads a map from the robot).
Coordinates are metres in the map's frame; the grid may be rotated in it (``info.origin``).
"""

from __future__ import annotations

import base64
import math
from array import array
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from rosbridge_mcp_server.robot.budget import budget_problem

__all__ = [
    "OCCUPIED_FROM",
    "Grid",
    "MapError",
    "Pose2D",
    "decode_grid",
    "decode_path",
    "to_frame",
    "yaw_of",
]

#: Occupied from this value on (map_server's occupied_thresh 0.65).
OCCUPIED_FROM = 65
#: Bytes per cell while a map is decoded and drawn: the cells, the cropped and ranked copies, the walls kept
#: when shrinking (two more), all one byte a cell.
_CELL_COST = 5
#: A real map's cells are a millimetre to a few metres; beyond these its extent (or its drawing's scale) is
#: no number a picture can use (1e308 m cells made an infinite extent, whose axis never ended).
MIN_RESOLUTION, MAX_RESOLUTION = 1e-6, 1e4
#: How far from its frame's origin a map may lie (UTM coordinates reach 1e7 m).
MAX_ORIGIN = 1e8


class MapError(ValueError):
    """A message that is not a usable occupancy grid; ``str()`` says which field is wrong."""


@dataclass(frozen=True)
class Pose2D:
    """A position (metres) and heading (radians, counter-clockwise from +x) in a plane."""

    x: float
    y: float
    yaw: float

    def rounded(self) -> list[float]:
        """``[x m, y m, yaw degrees]`` as an answer gives it: millimetres and tenths of a degree."""
        return [round(self.x, 3), round(self.y, 3), round(math.degrees(self.yaw), 1)]


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

    def extent(self) -> tuple[float, float, float, float]:
        """The map-frame box the grid covers: (x_min, y_min, x_max, y_max), metres (of its corners when the
        grid is rotated in its frame)."""
        corners = [self.to_map(col, row) for col in (0, self.width) for row in (0, self.height)]
        xs, ys = [x for x, _ in corners], [y for _, y in corners]
        return (min(xs), min(ys), max(xs), max(ys))

    def outside(self, x: float, y: float) -> float:
        """How far map-frame point (x, y) is outside the grid, metres: 0 on it, else to its nearest edge."""
        col, row = self.to_cell(x, y)
        beyond_col = max(0.0, -col, col - self.width)
        beyond_row = max(0.0, -row, row - self.height)
        return math.hypot(beyond_col, beyond_row) * self.resolution


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
    if not MIN_RESOLUTION <= resolution <= MAX_RESOLUTION:
        raise MapError(
            f"The map's resolution is {resolution:g} m per cell; a real map's is {MIN_RESOLUTION:g} to "
            f"{MAX_RESOLUTION:g} m, so it was not drawn (check what publishes it)."
        )
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
    x, y = _number(position.get("x")), _number(position.get("y"))
    if max(abs(x), abs(y)) > MAX_ORIGIN:
        raise MapError(
            f"The map's origin ({x:g}, {y:g}) lies over {MAX_ORIGIN:g} m from its frame's, farther than any "
            "real map's, so it was not drawn (check what publishes it)."
        )
    header = message.get("header")
    frame = header.get("frame_id", "") if isinstance(header, Mapping) else ""
    return Grid(
        width=width,
        height=height,
        resolution=float(resolution),
        origin=Pose2D(x, y, yaw_of(origin.get("orientation"))),
        frame_id=str(frame).lstrip("/"),
        cells=cells,
    )


def yaw_of(quaternion: object) -> float:
    """The rotation about z (radians) of a quaternion: a ``geometry_msgs/Quaternion`` or an (x, y, z, w)
    tuple (a tf ``Transform``'s rotation); identity when missing or malformed. The one place it is worked out.
    """
    if isinstance(quaternion, Mapping):
        parts = [quaternion.get(key) for key in ("x", "y", "z", "w")]
    elif isinstance(quaternion, tuple) and len(quaternion) == 4:
        parts = list(quaternion)
    else:
        return 0.0
    x, y, z, w = (_number(value, 1.0 if i == 3 else 0.0) for i, value in enumerate(parts))
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def to_frame(
    points: Sequence[tuple[float, float]], x: float, y: float, yaw: float
) -> list[tuple[float, float]]:
    """Points moved by a planar transform (rotate by ``yaw``, then shift by (x, y))."""
    c, s = math.cos(yaw), math.sin(yaw)
    return [(x + c * px - s * py, y + s * px + c * py) for px, py in points]


def _number(value: object, default: float = 0.0) -> float:
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return default


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
