"""Range sensors as data: ``LaserScan`` and ``PointCloud2`` decoded into points, the nearest hit, and the
directions free for a clearance.

Points are in the sensor's frame, metres, x forward and y left (REP 103). A bearing is measured from x
towards y (left is positive), in degrees. A laser reading counts when it is finite and within
``[range_min, range_max]``; ``+inf`` (nothing within range, REP 117) is free space, NaN (no valid reading) is
unknown. rosbridge's JSON sends both as ``null``, which cannot tell them apart: a ``null`` is taken as
"nothing within range" (lasers report that far more often than an error) and counted, so the text can say so.
A point cloud counts its finite points with x, y (and z when given) as FLOAT32/FLOAT64.

What a message declares is held to the decode budget (``budget.py``) before anything is decoded: a scan's
beams (each a bearing and a range, and a point for a hit, as Python objects: :data:`_BEAM_COST` bytes), a
cloud's width × height × point_step bytes.

What ``view_scan`` and ``view_map`` read, and ``pictures/scans.py`` draws. Pure: no I/O.
"""

from __future__ import annotations

import base64
import math
import struct
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from rosbridge_mcp_server.robot.budget import budget_problem

__all__ = [
    "Nearest",
    "ScanError",
    "ScanPoints",
    "Sector",
    "decode_cloud",
    "decode_scan",
    "free_sectors",
    "nearest",
]

_MAX_CLOUD_POINTS = 200_000
#: Bytes a laser beam takes decoded: (bearing, range) and (x, y) tuples of floats, and their list slots.
_BEAM_COST = 240


class ScanError(ValueError):
    """A message that is not a usable scan or cloud; ``str()`` says which field is wrong."""


@dataclass(frozen=True)
class ScanPoints:
    """Hits in the sensor frame, and (for a laser) each beam's bearing and whether it was free or unknown."""

    frame_id: str
    points: list[tuple[float, float]]
    range_max: float | None
    #: Laser beams as (bearing in radians, range or inf or nan); empty for a point cloud.
    beams: list[tuple[float, float]]
    #: The field of view covered, in radians (from, to); None for a point cloud (all around).
    field_of_view: tuple[float, float] | None
    #: Laser readings that came as JSON ``null`` (inf or NaN), taken as nothing within range.
    nulls: int = 0


@dataclass(frozen=True)
class Nearest:
    """The nearest hit: range in metres and bearing in degrees (0 ahead, positive to the left)."""

    range: float
    bearing: float
    x: float
    y: float


@dataclass(frozen=True)
class Sector:
    """Bearings (degrees, from ``start`` counter-clockwise to ``end``) with nothing within the clearance."""

    start: float
    end: float

    @property
    def width(self) -> float:
        return self.end - self.start


def decode_scan(message: Mapping[str, Any]) -> ScanPoints:
    """A ``sensor_msgs/LaserScan`` as points and beams."""
    ranges = message.get("ranges")
    first, increment = message.get("angle_min"), message.get("angle_increment")
    if not isinstance(ranges, list):
        raise ScanError("The scan has no 'ranges' array: is it a sensor_msgs/LaserScan?")
    if not _finite(first) or not _finite(increment):
        raise ScanError(
            f"The scan's angle_min ({first!r}) and angle_increment ({increment!r}) must be numbers."
        )
    _within_budget("The scan", f"{len(ranges):,} beams", len(ranges) * _BEAM_COST)
    angle_min, step = _float(first), _float(increment)
    low, high = message.get("range_min"), message.get("range_max")
    range_min = _float(low) if _finite(low) else 0.0
    range_max = _float(high) if _finite(high) else math.inf
    points: list[tuple[float, float]] = []
    beams: list[tuple[float, float]] = []
    nulls = 0
    for i, value in enumerate(ranges):
        bearing = angle_min + i * step
        if value is None:
            nulls += 1
            beams.append((bearing, math.inf))
            continue
        if isinstance(value, float) and math.isnan(value):
            beams.append((bearing, math.nan))
            continue
        if not isinstance(value, int | float) or isinstance(value, bool):
            beams.append((bearing, math.nan))
            continue
        r = float(value)
        if r == math.inf or r > range_max:
            beams.append((bearing, math.inf))
        elif r < range_min or r < 0:
            beams.append((bearing, math.nan))
        else:
            beams.append((bearing, r))
            points.append((r * math.cos(bearing), r * math.sin(bearing)))
    end = angle_min + max(0, len(ranges) - 1) * step
    return ScanPoints(
        frame_id=_frame(message),
        points=points,
        range_max=range_max if math.isfinite(range_max) else None,
        beams=beams,
        field_of_view=(min(angle_min, end), max(angle_min, end)),
        nulls=nulls,
    )


_FLOAT_FIELDS = {7: ("f", 4), 8: ("d", 8)}


def decode_cloud(message: Mapping[str, Any]) -> ScanPoints:
    """A ``sensor_msgs/PointCloud2`` as its finite (x, y) points (at most 200,000, evenly picked)."""
    fields = message.get("fields")
    if not isinstance(fields, list):
        raise ScanError("The cloud has no 'fields': is it a sensor_msgs/PointCloud2?")
    layout: dict[str, tuple[int, str, int]] = {}
    for field in fields:
        if isinstance(field, Mapping) and field.get("name") in ("x", "y", "z"):
            kind = _FLOAT_FIELDS.get(field.get("datatype", 0))
            offset = field.get("offset")
            if kind is not None and isinstance(offset, int):
                layout[str(field["name"])] = (offset, kind[0], kind[1])
    if "x" not in layout or "y" not in layout:
        names = [str(f.get("name")) for f in fields if isinstance(f, Mapping)]
        raise ScanError(
            f"The cloud has no FLOAT32/FLOAT64 x and y fields (its fields: {', '.join(names) or 'none'})."
        )
    data = message.get("data")
    _within_budget("The cloud", *_cloud_size(message, data))
    raw = (
        base64.b64decode(data)
        if isinstance(data, str)
        else bytes(data)
        if isinstance(data, bytes | list)
        else b""
    )
    step = message.get("point_step")
    if not isinstance(step, int) or step <= 0:
        raise ScanError(f"The cloud's point_step is {step!r}; it must be a positive number of bytes.")
    count = len(raw) // step
    order = ">" if message.get("is_bigendian") else "<"
    x_off, x_code, _ = layout["x"]
    y_off, y_code, _ = layout["y"]
    stride = max(1, math.ceil(count / _MAX_CLOUD_POINTS))
    unpack_x = struct.Struct(order + x_code).unpack_from
    unpack_y = struct.Struct(order + y_code).unpack_from
    points: list[tuple[float, float]] = []
    for index in range(0, count, stride):
        base = index * step
        if base + step > len(raw):
            break
        x, y = unpack_x(raw, base + x_off)[0], unpack_y(raw, base + y_off)[0]
        if math.isfinite(x) and math.isfinite(y):
            points.append((x, y))
    return ScanPoints(frame_id=_frame(message), points=points, range_max=None, beams=[], field_of_view=None)


def _cloud_size(message: Mapping[str, Any], data: object) -> tuple[str, int]:
    """What a cloud declares (width × height points of point_step bytes), or its data's length when that
    says more: its bytes, decoded, plus the points kept."""
    sizes = [_count(message.get(key)) for key in ("width", "height", "point_step")]
    declared = sizes[0] * sizes[1] * sizes[2]
    held = len(data) * 3 // 4 if isinstance(data, str) else len(data) if isinstance(data, bytes | list) else 0
    needed = max(declared, held) + _MAX_CLOUD_POINTS * _BEAM_COST // 2
    text = f"{sizes[0]}x{sizes[1]} points of {sizes[2]} bytes" if declared >= held else f"{held:,} bytes"
    return text, needed


def _count(value: object) -> int:
    return value if isinstance(value, int) and not isinstance(value, bool) and value > 0 else 0


def _within_budget(what: str, declared: str, needed: int) -> None:
    problem = budget_problem(what, declared, needed)
    if problem is not None:
        raise ScanError(problem)


def _finite(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _float(value: object) -> float:
    return float(value) if isinstance(value, int | float) else math.nan


def _frame(message: Mapping[str, Any]) -> str:
    header = message.get("header")
    return str(header.get("frame_id", "")).lstrip("/") if isinstance(header, Mapping) else ""


def nearest(scan: ScanPoints) -> Nearest | None:
    """The hit nearest the sensor, or ``None`` when nothing was hit."""
    if not scan.points:
        return None
    x, y = min(scan.points, key=lambda p: p[0] * p[0] + p[1] * p[1])
    return Nearest(math.hypot(x, y), math.degrees(math.atan2(y, x)), x, y)


def free_sectors(scan: ScanPoints, clearance: float, *, min_width: float = 10.0) -> list[Sector]:
    """Bearings where nothing is within ``clearance`` metres, widest first, each at least ``min_width``
    degrees. A laser's unknown (NaN) beams and its blind side are not free; a cloud is judged in 1° bins."""
    if scan.beams:
        beams = sorted((math.degrees(b), r) for b, r in scan.beams)
        free = [(b, not math.isnan(r) and r > clearance) for b, r in beams]
        step = abs(beams[1][0] - beams[0][0]) if len(beams) > 1 else 1.0
    else:
        blocked = set()
        for x, y in scan.points:
            if x * x + y * y <= clearance * clearance:
                blocked.add(math.floor(math.degrees(math.atan2(y, x))))
        free = [(float(b), b not in blocked) for b in range(-180, 180)]
        step = 1.0
    sectors: list[Sector] = []
    start: float | None = None
    last = 0.0
    for bearing, ok in free:
        if ok and start is None:
            start = bearing
        elif not ok and start is not None:
            sectors.append(Sector(start, last))
            start = None
        last = bearing
    if start is not None:
        sectors.append(Sector(start, last))
    # A sector running through ±180° (the back, for a full circle) is one sector.
    if len(sectors) > 1 and sectors[0].start <= -180 + step and sectors[-1].end >= 180 - 2 * step:
        sectors = [Sector(sectors[-1].start, sectors[0].end + 360), *sectors[1:-1]]
    sectors = [s for s in sectors if s.width + step >= min_width]
    return sorted(sectors, key=lambda s: (-s.width, s.start))
