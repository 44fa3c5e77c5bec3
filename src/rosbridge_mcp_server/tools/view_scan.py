"""``view_scan``: a laser scan or point cloud seen from above, the nearest obstacle and the free sectors."""

from __future__ import annotations

import asyncio
import math
from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.messages import short_type_name
from rosbridge_mcp_server.robot.scans import (
    Nearest,
    ScanError,
    ScanPoints,
    Sector,
    decode_cloud,
    decode_scan,
    free_sectors,
    nearest,
)
from rosbridge_mcp_server.robot.text import NAME_CHARS
from rosbridge_mcp_server.robot.text import shown as escaped
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolImage,
    ToolSpec,
)
from rosbridge_mcp_server.tools.namespaces import NamespaceArgument, namespaced_topic, non_defaults
from rosbridge_mcp_server.tools.typed_topics import first_message, is_type

__all__ = ["SPEC", "ScanAnswer", "run"]

_RANGE_SENSOR = is_type("sensor_msgs/LaserScan", "sensor_msgs/PointCloud2")
_SECTORS_LISTED = 4
#: The smallest radius drawn (metres): a laser's own minimum range is about this.
MIN_RADIUS = 0.1


class ScanAnswer(BaseModel):
    """The scan drawn; metres, and bearings in degrees (0 ahead, + left)."""

    topic: str
    message_type: str
    frame_id: str
    points: int
    nulls: int = Field(description="Readings sent as null (inf or NaN), taken as free")
    nearest: list[float] | None = Field(description="[range, bearing]")
    clearance: float
    free_sectors: list[list[float]] = Field(description="[from, to] bearings, widest first")
    radius: float
    ring_spacing: float


SPEC = ToolSpec(
    name="view_scan",
    title="Scan from above",
    description=(
        "A LaserScan or PointCloud2 from above (forward up), with the "
        'nearest obstacle and free directions. Read-only. Example: {"topic": "/scan", "clearance": 1.0}'
    ),
    hints=READS_ROBOT,
    output=ScanAnswer,
)


async def run(
    ctx: ToolContext,
    *,
    topic: Annotated[str, Field(description="e.g. /scan")] = "/scan",
    radius: Annotated[float, Field(ge=0, le=1000, description="Metres shown (0: fit), e.g. 5")] = 0.0,
    clearance: Annotated[float, Field(gt=0, le=100, description="Metres free, e.g. 1")] = 1.0,
    max_size: Annotated[int, Field(ge=64, le=2048, description="Pixels, e.g. 600")] = 600,
    timeout: Annotated[float, Field(gt=0, le=60, description="Seconds, e.g. 5")] = 5.0,
    namespace: NamespaceArgument = None,
) -> ToolAnswer:
    """Take one scan or cloud, find the nearest hit and free sectors, draw it off the event loop."""
    if 0 < radius < MIN_RADIUS:
        raise ToolFailure(
            f"radius {radius:g} m is below the {MIN_RADIUS:g} m the picture shows at least; give 0 to fit "
            f"the scan, or {MIN_RADIUS:g} to 1000 m."
        )
    name, msg_type, _, note = await namespaced_topic(
        ctx,
        topic,
        "topic",
        namespace,
        tool=SPEC.name,
        arguments=non_defaults(
            run,
            {
                "topic": topic,
                "radius": radius,
                "clearance": clearance,
                "max_size": max_size,
                "timeout": timeout,
            },
        ),
        accepts=_RANGE_SENSOR,
        kind="sensor_msgs/LaserScan or PointCloud2",
        hint="view_map shows maps; subscribe_topic reads other topics.",
    )
    message = await first_message(ctx, name, msg_type, timeout, "scan")
    cloud = short_type_name(msg_type) == "sensor_msgs/PointCloud2"
    try:
        scan, found, sectors, image, ring, shown = await asyncio.to_thread(
            _work, message, cloud, radius, clearance, max_size
        )
    except ScanError as exc:
        raise ToolFailure(f"{exc} (topic {name}).") from None
    del message
    answer = ScanAnswer(
        topic=name,
        message_type=msg_type,
        frame_id=escaped(scan.frame_id, NAME_CHARS),  # the robot's text: a publisher may put anything there
        points=len(scan.points),
        nulls=scan.nulls,
        nearest=None if found is None else [round(found.range, 3), round(found.bearing, 1)],
        clearance=clearance,
        free_sectors=[[round(s.start, 1), round(s.end, 1)] for s in sectors],
        radius=round(shown, 3),
        ring_spacing=ring,
    )
    text = _text(answer) if note is None else f"{note}\n{_text(answer)}"
    return ToolAnswer(text=text, data=answer, images=(ToolImage(image, "image/png"),))


def _work(
    message: dict[str, Any], cloud: bool, radius: float | None, clearance: float, max_size: int
) -> tuple[ScanPoints, Nearest | None, list[Sector], bytes, float, float]:
    from rosbridge_mcp_server.pictures.drawing import png_bytes  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.pictures.scans import draw_scan  # noqa: PLC0415 - on first use

    scan = decode_cloud(message) if cloud else decode_scan(message)
    found = nearest(scan)
    sectors = free_sectors(scan, clearance)
    shown = radius or _fitting_radius(scan)
    picture, ring = draw_scan(scan, radius=shown, size=max_size, nearest_hit=found)
    return scan, found, sectors, png_bytes(picture), ring, shown


def _fitting_radius(scan: ScanPoints) -> float:
    """Enough to show the farthest hit (and no more than the sensor's range), at least 1 m."""
    farthest = max((math.hypot(x, y) for x, y in scan.points), default=0.0)
    if scan.range_max is not None:
        farthest = min(farthest, scan.range_max)
    return max(1.0, math.ceil(farthest * 1.05 * 2) / 2)


def _text(answer: ScanAnswer) -> str:
    parts = [f"{answer.topic} ({answer.message_type}, frame {answer.frame_id or '?'}): {answer.points} hits"]
    if answer.nulls:
        parts.append(
            f"{answer.nulls} readings null (beyond range or invalid: JSON cannot tell; taken as free)"
        )
    if answer.nearest is None:
        parts.append("nothing hit")
    else:
        parts.append(
            f"nearest obstacle {answer.nearest[0]:g} m at bearing {answer.nearest[1]:g}° "
            "(0 ahead, + left; orange circle)"
        )
    if answer.free_sectors and answer.free_sectors[0][1] - answer.free_sectors[0][0] >= 358:
        parts.append(f"free beyond {answer.clearance:g} m all around")
    elif answer.free_sectors:
        listed = ", ".join(f"{start:g}° to {end:g}°" for start, end in answer.free_sectors[:_SECTORS_LISTED])
        more = len(answer.free_sectors) - _SECTORS_LISTED
        parts.append(
            f"free beyond {answer.clearance:g} m: {listed}" + (f" (+{more} narrower)" if more > 0 else "")
        )
    else:
        parts.append(f"no direction is free for {answer.clearance:g} m")
    parts.append(
        f"picture: {answer.radius:g} m around the sensor, forward up, rings every {answer.ring_spacing:g} m, "
        "hits red, footprint blue"
    )
    return "; ".join(parts) + "."
