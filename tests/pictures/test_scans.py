"""Scans and clouds from above: beams to points, the nearest hit, free sectors, the picture."""

from __future__ import annotations

import base64
import math
import struct
from typing import Any

import pytest

from rosbridge_mcp_server.pictures.drawing import OBSTACLE_COLOUR, ROBOT_COLOUR
from rosbridge_mcp_server.pictures.scans import draw_scan
from rosbridge_mcp_server.robot.scans import ScanError, decode_cloud, decode_scan, free_sectors, nearest


def laser(ranges: list[Any], *, angle_min: float = -math.pi, range_max: float = 10.0) -> dict[str, Any]:
    return {
        "header": {"frame_id": "laser"},
        "angle_min": angle_min,
        "angle_increment": 2 * math.pi / len(ranges) if angle_min == -math.pi else math.radians(1),
        "range_min": 0.1,
        "range_max": range_max,
        "ranges": ranges,
    }


def cloud(points: list[tuple[float, float, float]], *, datatype: int = 7) -> dict[str, Any]:
    code, size = ("f", 4) if datatype == 7 else ("d", 8)
    data = b"".join(struct.pack(f"<{code}{code}{code}", *p) for p in points)
    return {
        "header": {"frame_id": "lidar3d"},
        "height": 1,
        "width": len(points),
        "fields": [
            {"name": name, "offset": i * size, "datatype": datatype, "count": 1}
            for i, name in enumerate("xyz")
        ],
        "is_bigendian": False,
        "point_step": 3 * size,
        "row_step": 3 * size * len(points),
        "data": base64.b64encode(data).decode(),
        "is_dense": True,
    }


def test_beams_become_points_and_inf_nan_and_out_of_range_are_not_hits() -> None:
    """360 beams from -180°, index 180 ahead: null, inf, NaN, too near and too far are not hits."""
    ranges: list[Any] = [math.inf] * 360
    ranges[180] = 2.0  # ahead
    ranges[270] = 1.0  # left (+90°)
    ranges[0] = None
    ranges[5] = math.nan
    ranges[10] = 0.05  # below range_min
    ranges[20] = 50.0  # beyond range_max
    scan = decode_scan(laser(ranges))
    assert scan.frame_id == "laser"
    assert scan.nulls == 1
    assert scan.points == [pytest.approx((2.0, 0.0)), pytest.approx((0.0, 1.0), abs=1e-9)]
    found = nearest(scan)
    assert found is not None
    assert (found.range, found.bearing) == pytest.approx((1.0, 90.0))


def test_a_malformed_scan_is_refused_naming_the_field() -> None:
    """No ranges, or angles that are not numbers, are errors saying so."""
    with pytest.raises(ScanError, match="no 'ranges'"):
        decode_scan({"angle_min": 0})
    with pytest.raises(ScanError, match="angle_min"):
        decode_scan({"ranges": [1.0], "angle_min": "zero", "angle_increment": 0.1})


def test_free_sectors_are_widest_first_and_join_across_the_back() -> None:
    """A wall ahead (±20°) and one on the right leave the left and the back-and-right-rear free."""
    ranges: list[Any] = [5.0] * 360
    for index in range(160, 201):
        ranges[index] = 0.5  # -20°..+20°
    for index in range(60, 100):
        ranges[index] = 0.8  # -120°..-81°
    sectors = free_sectors(decode_scan(laser(ranges)), 1.0)
    assert [(round(s.start), round(s.end)) for s in sectors] == [(21, 239), (-80, -21)]


def test_nan_beams_are_not_free_but_null_ones_are() -> None:
    """A run of NaN beams splits a free sector; null (inf or NaN after JSON) is taken as nothing in range."""
    ranges: list[Any] = [None] * 360
    for index in range(170, 191):
        ranges[index] = math.nan
    widths = [round(s.width) for s in free_sectors(decode_scan(laser(ranges)), 1.0)]
    assert widths == [338]


def test_a_point_cloud_gives_its_finite_xy_points_in_float32_and_float64() -> None:
    """NaN points are dropped; z is ignored for the top view."""
    for datatype in (7, 8):
        scan = decode_cloud(
            cloud([(1.0, 2.0, 0.5), (math.nan, 0.0, 0.0), (-3.0, 0.5, 1.0)], datatype=datatype)
        )
        assert scan.points == [(1.0, 2.0), (-3.0, 0.5)]
        assert scan.beams == []


def test_a_cloud_without_x_and_y_names_its_fields() -> None:
    """A cloud of only intensities cannot be drawn from above."""
    message = cloud([(1.0, 2.0, 3.0)])
    message["fields"] = [{"name": "intensity", "offset": 0, "datatype": 7, "count": 1}]
    with pytest.raises(ScanError, match=r"no FLOAT32/FLOAT64 x and y fields \(its fields: intensity\)"):
        decode_cloud(message)


def test_cloud_free_sectors_come_from_points_within_the_clearance() -> None:
    """A cloud's only near point (ahead, 0.5 m) blocks its one-degree bin."""
    sectors = free_sectors(decode_cloud(cloud([(0.5, 0.0, 0.0), (5.0, 5.0, 0.0)])), 1.0)
    assert len(sectors) == 1
    assert sectors[0].width == pytest.approx(358)


def test_the_top_view_puts_a_hit_ahead_above_the_sensor_and_left_to_the_left() -> None:
    """Forward is up, left is left; the footprint is drawn around the centre."""
    ranges: list[Any] = [math.inf] * 360
    ranges[180] = 2.0
    ranges[270] = 3.0
    scan = decode_scan(laser(ranges))
    image, ring = draw_scan(scan, radius=4.0, size=400, nearest_hit=None)
    scale = (400 / 2 - 8) / 4.0
    centre = 200
    assert ring == 1.0
    assert image.getpixel((centre, round(centre - 2.0 * scale))) == OBSTACLE_COLOUR
    assert image.getpixel((round(centre - 3.0 * scale), centre)) == OBSTACLE_COLOUR
    assert image.getpixel((round(centre + 3.0 * scale), centre)) != OBSTACLE_COLOUR
    foot = round(0.2 * scale)
    assert any(image.getpixel((centre + foot + d, centre)) == ROBOT_COLOUR for d in (-1, 0, 1))
