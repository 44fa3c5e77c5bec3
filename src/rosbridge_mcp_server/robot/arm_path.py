"""An arm's path as its controller interpolates it, and the geometry it is judged with. Pure; no MCP.

Between two trajectory points a ros2_control joint trajectory controller moves each joint linearly when the
points carry positions only, and along a cubic (Hermite) when both ends carry velocities (the arm starts at
rest). :func:`path_samples` walks that path a small step of joint travel at a time; :func:`segment_hits` and
:func:`inside_box` place points and the segments between links against boxes.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

from rosbridge_mcp_server.robot.arm.urdf import Joint
from rosbridge_mcp_server.robot.arm_goals import Trajectory, TrajectoryPoint

__all__ = [
    "CUBIC_SAMPLES",
    "MAX_SAMPLES",
    "STEP_METRES",
    "STEP_RADIANS",
    "Point",
    "hermite",
    "inside_box",
    "path_samples",
    "peak_speeds",
    "segment_hits",
]

Point = tuple[float, float, float]
#: Joint travel between two samples of a path: radians (revolute), metres (prismatic).
STEP_RADIANS = math.radians(2.0)
STEP_METRES = 0.01
#: Most samples of one path checked against the boxes; a longer path is refused as too long to check.
MAX_SAMPLES = 2000
#: Samples of a cubic segment when its peak speed or its swing is looked for.
CUBIC_SAMPLES = 32


def hermite(ends: tuple[float, float, float, float], span: float, s: float) -> tuple[float, float]:
    """Position and speed at fraction *s* of a cubic Hermite segment of *span* seconds between positions
    ``ends[0]`` and ``ends[1]`` with speeds ``ends[2]`` and ``ends[3]``."""
    p0, p1, v0, v1 = ends
    s2, s3 = s * s, s * s * s
    h00, h10, h01, h11 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2
    position = h00 * p0 + h10 * span * v0 + h01 * p1 + h11 * span * v1
    d00, d10, d01, d11 = 6 * s2 - 6 * s, 3 * s2 - 4 * s + 1, -6 * s2 + 6 * s, 3 * s2 - 2 * s
    speed = (d00 * p0 + d10 * span * v0 + d01 * p1 + d11 * span * v1) / span
    return position, speed


def peak_speeds(
    start: tuple[float, ...],
    end: tuple[float, ...],
    v_start: tuple[float, ...] | None,
    v_end: tuple[float, ...] | None,
    span: float,
) -> list[float]:
    """Each joint's fastest speed over one segment of *span* seconds."""
    if v_start is None or v_end is None:
        return [abs(b - a) / span for a, b in zip(start, end, strict=True)]
    return [
        max(abs(hermite((a, b, va, vb), span, k / CUBIC_SAMPLES)[1]) for k in range(CUBIC_SAMPLES + 1))
        for a, b, va, vb in zip(start, end, v_start, v_end, strict=True)
    ]


def path_samples(
    trajectory: Trajectory, joints: list[Joint], begin: tuple[float, ...]
) -> Iterator[tuple[float, ...]] | None:
    """The joint positions along the path the controller interpolates, at most :data:`STEP_RADIANS` (or
    :data:`STEP_METRES`) of travel apart; ``None`` when that takes more than :data:`MAX_SAMPLES`."""
    total = 1
    # The arm starts at rest: a first point with velocities makes the first segment a cubic too.
    previous: tuple[float, ...] = begin
    previous_speeds: tuple[float, ...] | None = tuple(0.0 for _ in begin)
    previous_time = 0.0
    segments: list[tuple[tuple[float, ...], TrajectoryPoint, tuple[float, ...] | None, int, float]] = []
    for point in trajectory.points:
        travel = max(
            (abs(b - a) / (STEP_METRES if j.linear else STEP_RADIANS))
            for j, a, b in zip(joints, previous, point.positions, strict=True)
        )
        cubic = previous_speeds is not None and point.velocities is not None
        count = max(1, math.ceil(travel * (2 if cubic else 1)))
        total += count
        segments.append((previous, point, previous_speeds, count, point.time - previous_time))
        previous, previous_speeds, previous_time = point.positions, point.velocities, point.time
    if total > MAX_SAMPLES:
        return None

    def walk() -> Iterator[tuple[float, ...]]:
        yield begin
        for start, point, v_start, count, span in segments:
            for k in range(1, count + 1):
                s = k / count
                if v_start is not None and point.velocities is not None and span > 0:
                    yield tuple(
                        hermite((a, b, va, vb), span, s)[0]
                        for a, b, va, vb in zip(
                            start, point.positions, v_start, point.velocities, strict=True
                        )
                    )
                else:
                    yield tuple(a + (b - a) * s for a, b in zip(start, point.positions, strict=True))

    return walk()


def inside_box(point: Point, low: Point, high: Point, margin: float) -> bool:
    return all(lo + margin <= p <= hi - margin for p, lo, hi in zip(point, low, high, strict=True))


def segment_hits(a: Point, b: Point, low: Point, high: Point, margin: float) -> bool:
    """Whether the segment a–b meets the box *low*–*high* grown by *margin* (slab test)."""
    t0, t1 = 0.0, 1.0
    for p, q, least, most in zip(a, b, low, high, strict=True):
        lo, hi, d = least - margin, most + margin, q - p
        if abs(d) < 1e-12:
            if p < lo or p > hi:
                return False
            continue
        u0, u1 = (lo - p) / d, (hi - p) / d
        if u0 > u1:
            u0, u1 = u1, u0
        t0, t1 = max(t0, u0), min(t1, u1)
        if t0 > t1:
            return False
    return True
