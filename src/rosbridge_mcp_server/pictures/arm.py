"""An arm motion, drawn from the side: the arm's skeleton (joint to joint, by forward kinematics of its URDF)
where it starts (grey) and where the goal puts it (magenta), over the policy's workspace (green) and keep-out
(red) boxes, seen along the y axis of the boxes' frame (x to the right, z up). Pure: no I/O.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from PIL import Image, ImageDraw

from rosbridge_mcp_server.pictures.drawing import TEXT_COLOUR, Rgb, font, label, ticks
from rosbridge_mcp_server.robot.arm.kinematics import Chain, inverse, transform_point, translation
from rosbridge_mcp_server.robot.arm.urdf import Robot, UrdfError

__all__ = ["draw_arm"]

SIZE = 360
MARGIN = 28
_START: Rgb = (140, 140, 140)
_GOAL: Rgb = (220, 40, 160)
_WORKSPACE: Rgb = (30, 150, 60)
_KEEP_OUT: Rgb = (210, 30, 30)
#: Boxes are drawn clipped to this many metres around the arm (a policy box may be the whole room).
_REACH = 2.0

Point = tuple[float, float, float]
Box = tuple[str, Point, Point]


def _skeletons(robot: Robot, positions: Mapping[str, float], frame: str) -> list[list[Point]]:
    try:
        base = None if frame == robot.root else inverse(Chain(robot, robot.root, frame).tip_pose(positions))
        out = []
        for tool in robot.end_effectors():
            chain = Chain(robot, robot.root, tool)
            points = [(0.0, 0.0, 0.0), *(translation(pose) for _, pose in chain.poses(positions))]
            out.append([transform_point(base, p) if base is not None else p for p in points])
        return out
    except UrdfError:
        return []


def draw_arm(
    robot: Robot,
    start: Mapping[str, float],
    goal: Mapping[str, float],
    *,
    frame: str | None = None,
    workspace: Sequence[Box] = (),
    keep_out: Sequence[Box] = (),
) -> Image.Image:
    """The side view of the arm at *start* and at *goal* (joint positions, radians and metres)."""
    frame = frame or robot.root
    arms = [(_START, _skeletons(robot, start, frame)), (_GOAL, _skeletons(robot, goal, frame))]
    xs = [p[0] for _, chains in arms for chain in chains for p in chain] or [0.0]
    zs = [p[2] for _, chains in arms for chain in chains for p in chain] or [0.0]
    low_x, high_x = min(xs) - 0.1, max(xs) + 0.1
    low_z, high_z = min(*zs, 0.0) - 0.1, max(zs) + 0.1
    span = max(high_x - low_x, high_z - low_z, 0.2)
    scale = (SIZE - 2 * MARGIN) / span

    def at(x: float, z: float) -> tuple[float, float]:
        return MARGIN + (x - low_x) * scale, SIZE - MARGIN - (z - low_z) * scale

    image = Image.new("RGB", (SIZE, SIZE), (255, 255, 255))
    draw = ImageDraw.Draw(image)
    for colour, boxes in ((_WORKSPACE, workspace), (_KEEP_OUT, keep_out)):
        for name, lo, hi in boxes:
            x0, x1 = max(lo[0], low_x - _REACH), min(hi[0], high_x + _REACH)
            z0, z1 = max(lo[2], low_z - _REACH), min(hi[2], high_z + _REACH)
            if x0 < x1 and z0 < z1:
                (left, bottom), (right, top) = at(x0, z0), at(x1, z1)
                draw.rectangle((left, top, right, bottom), outline=colour, width=2)
                # The name inside the box's lower left corner, where the picture shows it.
                corner = (min(max(left, 0.0), SIZE - 60.0) + 4, min(max(bottom, 40.0), float(SIZE)) - 16)
                draw.text(corner, name, fill=colour, font=font(11))
    draw.line((*at(low_x, 0.0), *at(high_x, 0.0)), fill=(200, 200, 200), width=1)  # z = 0
    for colour, chains in arms:
        for chain in chains:
            points = [at(p[0], p[2]) for p in chain]
            draw.line(points, fill=colour, width=4, joint="curve")
            for x, y in points:
                draw.ellipse((x - 3, y - 3, x + 3, y + 3), fill=colour)
    for value in ticks(low_x, high_x, 4):
        x, y = at(value, low_z)
        draw.text((x - 8, SIZE - MARGIN + 6), label(value), fill=TEXT_COLOUR, font=font(10))
    draw.text(
        (4, 4),
        f"side view in {frame} (x right, z up; m): start grey, goal magenta",
        fill=TEXT_COLOUR,
        font=font(11),
    )
    return image
