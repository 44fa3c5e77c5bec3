"""A navigation goal on the robot's map, drawn: the map around the robot, the goal(s), the start, the path
driven and the policy's zones. What is drawn is ``robot/navigation.py``'s (a :class:`Scene`'s grid, poses and
zones). Pure: no I/O.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from PIL import ImageDraw

from rosbridge_mcp_server.pictures.maps import MARGIN_BOTTOM, MARGIN_LEFT, MapPicture, Overlay, draw_map
from rosbridge_mcp_server.robot.navigation import Polygon
from rosbridge_mcp_server.robot.occupancy import Grid, Pose2D

__all__ = ["draw_scene"]

_GOAL_COLOUR = (220, 40, 160)
_START_COLOUR = (120, 120, 120)
_KEEP_OUT_COLOUR = (210, 30, 30)
_ALLOWED_COLOUR = (30, 150, 60)


def draw_scene(
    grid: Grid,
    *,
    robot: Pose2D | None,
    goals: Sequence[Pose2D],
    start: Pose2D | None = None,
    driven: Sequence[tuple[float, float]] = (),
    allowed: Mapping[str, Polygon] | None = None,
    keep_out: Mapping[str, Polygon] | None = None,
    max_size: int = 640,
) -> MapPicture:
    """The map around the robot, the goal(s), the start and the path driven, with the zones outlined: the
    robot blue, the path green, the goals magenta, the start grey, allowed zones green, keep-out red."""
    points = [(p.x, p.y) for p in goals] + list(driven)
    for pose in (robot, start):
        if pose is not None:
            points.append((pose.x, pose.y))
    window = None
    if points:
        pad = 1.5
        xs, ys = [x for x, _ in points], [y for _, y in points]
        span = max(max(xs) - min(xs), max(ys) - min(ys)) / 2 + pad
        cx, cy = (max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2
        window = (cx - span, cy - span, cx + span, cy + span)
    picture = draw_map(grid, max_size=max_size, overlay=Overlay(robot=robot, path=driven), window=window)
    draw = ImageDraw.Draw(picture.image)
    x_min, y_min, _, _ = picture.window
    scale = picture.pixels_per_metre
    height = picture.image.size[1]

    def pixel(x: float, y: float) -> tuple[float, float]:
        return (MARGIN_LEFT + (x - x_min) * scale, height - MARGIN_BOTTOM - (y - y_min) * scale)

    for zones, colour in ((allowed or {}, _ALLOWED_COLOUR), (keep_out or {}, _KEEP_OUT_COLOUR)):
        for polygon in zones.values():
            corners = [pixel(x, y) for x, y in polygon]
            if len(corners) >= 2:
                draw.line([*corners, corners[0]], fill=colour, width=2)
    if start is not None:
        sx, sy = pixel(start.x, start.y)
        draw.rectangle((sx - 4, sy - 4, sx + 4, sy + 4), outline=_START_COLOUR, width=2)
    for goal in goals:
        gx, gy = pixel(goal.x, goal.y)
        radius = 7
        draw.ellipse((gx - radius, gy - radius, gx + radius, gy + radius), outline=_GOAL_COLOUR, width=3)
        tip = (gx + 2 * radius * math.cos(goal.yaw), gy - 2 * radius * math.sin(goal.yaw))
        draw.line((gx, gy, *tip), fill=_GOAL_COLOUR, width=3)
    return picture
