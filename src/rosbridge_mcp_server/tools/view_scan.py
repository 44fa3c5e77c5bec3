"""``view_scan``: a laser scan or point cloud seen from above, the nearest obstacle and the free sectors."""

from __future__ import annotations

import asyncio
import math
from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.drawing import png_bytes
from rosbridge_mcp_server.robot.messages import short_type_name
from rosbridge_mcp_server.robot.scans import (
    Nearest,
    ScanError,
    ScanPoints,
    Sector,
    decode_cloud,
    decode_scan,
    draw_scan,
    free_sectors,
    nearest,
)
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolImage,
    ToolSpec,
)
from rosbridge_mcp_server.tools.seeing import first_message, is_type, typed_topic

__all__ = ["SPEC", "ScanAnswer", "run"]

_RANGE_SENSOR = is_type("sensor_msgs/LaserScan", "sensor_msgs/PointCloud2")
_SECTORS_LISTED = 4


class Obstacle(BaseModel):
    """The nearest hit."""

    range: float = Field(description="Metres from the sensor")
    bearing: float = Field(description="Degrees: 0 ahead, positive to the left")


class FreeSector(BaseModel):
    """Bearings with nothing within the clearance."""

    start: float = Field(description="Degrees")
    end: float = Field(description="Degrees (counter-clockwise from start)")


class ScanAnswer(BaseModel):
    """The scan or cloud that was drawn and what it shows."""

    topic: str
    message_type: str
    frame_id: str
    points: int = Field(description="Hits drawn")
    nearest: Obstacle | None
    clearance: float = Field(description="Metres a free sector is clear for")
    free_sectors: list[FreeSector] = Field(description="Widest first")
    radius: float = Field(description="Metres shown around the sensor")
    ring_spacing: float = Field(description="Metres between range rings")
    image_bytes: int


SPEC = ToolSpec(
    name="view_scan",
    title="Scan from above",
    description=(
        "Draw a LaserScan or PointCloud2 from above around the sensor (forward up, left left) with range "
        "rings and the robot's footprint; says the nearest obstacle and the free directions. Read-only. "
        'Example: {"topic": "/scan", "clearance": 1.0}'
    ),
    hints=READS_ROBOT,
    output=ScanAnswer,
)


async def run(
    ctx: ToolContext,
    *,
    topic: Annotated[str, Field(description="LaserScan or PointCloud2 topic, e.g. /scan")] = "/scan",
    radius: Annotated[
        float | None,
        Field(gt=0, le=1000, description="Metres to show around the sensor, e.g. 5 (default: fits)"),
    ] = None,
    clearance: Annotated[
        float, Field(gt=0, le=100, description="Metres a free direction is clear, e.g. 1")
    ] = 1.0,
    max_size: Annotated[int, Field(ge=64, le=2048, description="Picture side in pixels, e.g. 600")] = 600,
    timeout: Annotated[float, Field(gt=0, le=60, description="Seconds to wait for a message, e.g. 5")] = 5.0,
) -> ToolAnswer:
    """Take one scan or cloud, find the nearest hit and free sectors, draw it off the event loop."""
    name, msg_type = await typed_topic(
        ctx,
        topic,
        "topic",
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
        frame_id=scan.frame_id,
        points=len(scan.points),
        nearest=None
        if found is None
        else Obstacle(range=round(found.range, 3), bearing=round(found.bearing, 1)),
        clearance=clearance,
        free_sectors=[FreeSector(start=round(s.start, 1), end=round(s.end, 1)) for s in sectors],
        radius=round(shown, 3),
        ring_spacing=ring,
        image_bytes=len(image),
    )
    return ToolAnswer(text=_text(answer), data=answer, images=(ToolImage(image, "image/png"),))


def _work(
    message: dict[str, Any], cloud: bool, radius: float | None, clearance: float, max_size: int
) -> tuple[ScanPoints, Nearest | None, list[Sector], bytes, float, float]:
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
    if answer.nearest is None:
        parts.append("nothing hit")
    else:
        parts.append(
            f"nearest obstacle {answer.nearest.range:g} m at bearing {answer.nearest.bearing:g}° "
            "(0 ahead, + left; orange circle)"
        )
    if answer.free_sectors:
        listed = ", ".join(f"{s.start:g}° to {s.end:g}°" for s in answer.free_sectors[:_SECTORS_LISTED])
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
