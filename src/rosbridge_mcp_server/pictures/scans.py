"""Range sensors seen from above: the top view of a ``LaserScan`` or ``PointCloud2`` (``robot/scans.py``
decodes them into points, the nearest hit and the free directions).

The top view puts the sensor in the middle, forward up and left to the left, as a driver sees it: points
are in the sensor's frame, metres, x forward and y left (REP 103). Pure: no I/O.
"""

from __future__ import annotations

import math

from PIL import Image, ImageDraw

from rosbridge_mcp_server.pictures.drawing import (
    OBSTACLE_COLOUR,
    ROBOT_COLOUR,
    TEXT_COLOUR,
    draw_scale_bar,
    font,
    label,
    nice_step,
)
from rosbridge_mcp_server.robot.scans import Nearest, ScanPoints

__all__ = ["FOOTPRINT_RADIUS", "draw_scan"]

#: Radius of the robot's footprint drawn around the sensor, metres.
FOOTPRINT_RADIUS = 0.2


def draw_scan(
    scan: ScanPoints,
    *,
    radius: float,
    size: int,
    nearest_hit: Nearest | None,
) -> tuple[Image.Image, float]:
    """The top view: ``radius`` metres around the sensor on a ``size``-pixel square, range rings, the
    footprint, the hits; returns it and the ring spacing in metres."""
    image = Image.new("RGB", (size, size), (255, 255, 255))
    draw = ImageDraw.Draw(image)
    centre = size / 2
    scale = (size / 2 - 8) / radius  # pixels per metre

    def pixel(x: float, y: float) -> tuple[float, float]:
        return (centre - y * scale, centre - x * scale)

    if scan.field_of_view is not None and scan.field_of_view[1] - scan.field_of_view[0] < 2 * math.pi - 0.05:
        # The laser's blind side, shaded.
        low, high = scan.field_of_view
        draw.pieslice(
            (centre - size, centre - size, centre + size, centre + size),
            start=-90 - math.degrees(low),
            end=270 - math.degrees(high),
            fill=(225, 225, 225),
        )
    ring = nice_step(radius, 5)
    small = font(11)
    # Counted, not summed: a ring added to itself until it passes a radius far below 1e-9 never got there.
    for count in range(1, min(int(radius / ring * (1 + 1e-9)), 10) + 1):
        r = count * ring
        px = r * scale
        draw.ellipse((centre - px, centre - px, centre + px, centre + px), outline=(190, 190, 190))
        draw.text((centre + 3, centre - px + 1), label(r, "m"), fill=(110, 110, 110), font=small)
    draw.line((centre, 0, centre, size), fill=(225, 225, 225))
    draw.line((0, centre, size, centre), fill=(225, 225, 225))
    for x, y in scan.points:
        px, py = pixel(x, y)
        if -2 <= px <= size + 2 and -2 <= py <= size + 2:
            draw.rectangle((px - 1, py - 1, px + 1, py + 1), fill=OBSTACLE_COLOUR)
    # At most the picture's size: Pillow traces an outline over its whole extent, so the footprint of a
    # picture a micrometre across (millions of pixels round) took a minute of CPU.
    foot = min(max(FOOTPRINT_RADIUS * scale, 4.0), float(size))
    draw.ellipse((centre - foot, centre - foot, centre + foot, centre + foot), outline=ROBOT_COLOUR, width=2)
    draw.line((centre, centre, centre, centre - foot * 1.6), fill=ROBOT_COLOUR, width=2)
    if nearest_hit is not None and nearest_hit.range <= radius * 1.5:
        px, py = pixel(nearest_hit.x, nearest_hit.y)
        draw.line((centre, centre, px, py), fill=(255, 150, 0), width=1)
        draw.ellipse((px - 5, py - 5, px + 5, py + 5), outline=(255, 150, 0), width=2)
    draw.text((centre, 2), "forward (x)", fill=TEXT_COLOUR, font=small, anchor="ma")
    draw.text((4, centre - 14), "left (y)", fill=TEXT_COLOUR, font=small)
    draw_scale_bar(draw, scale, (12, size - 12))
    return image, ring
