"""``view_map``: an occupancy grid (a map or a costmap) as a picture, with the robot, a plan, a scan on it."""

from __future__ import annotations

import asyncio
import math
from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.drawing import png_bytes
from rosbridge_mcp_server.robot.maps import (
    Grid,
    MapError,
    MapPicture,
    Overlay,
    Pose2D,
    decode_grid,
    decode_path,
    draw_map,
)
from rosbridge_mcp_server.robot.scans import ScanError, decode_scan, to_frame
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolImage,
    ToolSpec,
)
from rosbridge_mcp_server.tools.seeing import first_message, is_type, planar_pose, typed_topic

__all__ = ["SPEC", "MapAnswer", "run"]

_GRID = is_type("nav_msgs/OccupancyGrid")
_PATH = is_type("nav_msgs/Path")
_SCAN = is_type("sensor_msgs/LaserScan")
#: The longest the robot's, the path's and the scan's frames are waited for on /tf.
_TF_WAIT = 2.0


class PlanarPose(BaseModel):
    """A pose in the map's frame: metres and yaw in degrees."""

    x: float
    y: float
    yaw: float = Field(description="Degrees, counter-clockwise from +x")


class MapAnswer(BaseModel):
    """The map that was drawn and what is on the picture."""

    topic: str
    frame_id: str
    width: int = Field(description="Cells")
    height: int = Field(description="Cells")
    resolution: float = Field(description="Metres per cell")
    size_m: list[float] = Field(description="[width, height] in metres")
    origin: PlanarPose = Field(description="Cell (0, 0)'s corner in the map frame")
    known: float = Field(description="Share of cells known (0-1)")
    free: float
    occupied: float
    cost: float = Field(description="Share of cells with a cost between free and occupied (costmaps)")
    robot: PlanarPose | None = Field(description="base_frame in the map frame, when /tf knows it")
    notes: list[str] = Field(description="What could not be drawn, and why")
    path_poses: int | None = None
    scan_hits: int | None = None
    window: list[float] = Field(description="[x_min, y_min, x_max, y_max] shown, metres")
    image_width: int
    image_height: int
    pixels_per_metre: float
    image_bytes: int


SPEC = ToolSpec(
    name="view_map",
    title="Map picture",
    description=(
        "Draw an OccupancyGrid (map or costmap) as a picture: free white, occupied black, unknown grey, "
        "costs yellow to purple; the robot (blue arrow, from /tf), optionally a plan (green) and a scan "
        'projected onto it (red). Read-only. Example: {"topic": "/map", "path_topic": "/plan", "scan_topic": '
        '"/scan", "around_robot": 4}'
    ),
    hints=READS_ROBOT,
    output=MapAnswer,
)


async def run(
    ctx: ToolContext,
    *,
    topic: Annotated[
        str, Field(description="OccupancyGrid topic, e.g. /map or /global_costmap/costmap")
    ] = "/map",
    base_frame: Annotated[
        str, Field(description='Robot frame to draw, e.g. base_link; "" for none')
    ] = "base_link",
    path_topic: Annotated[str | None, Field(description="nav_msgs/Path to draw, e.g. /plan")] = None,
    scan_topic: Annotated[str | None, Field(description="LaserScan to project, e.g. /scan")] = None,
    around_robot: Annotated[
        float | None, Field(gt=0, le=1000, description="Show only this many metres around the robot, e.g. 3")
    ] = None,
    max_size: Annotated[int, Field(ge=64, le=2048, description="Longest side in pixels, e.g. 800")] = 800,
    timeout: Annotated[
        float, Field(gt=0, le=60, description="Seconds to wait for each message, e.g. 5")
    ] = 5.0,
) -> ToolAnswer:
    """Take one grid (and plan and scan), place them with /tf, draw off the event loop."""
    name, msg_type = await typed_topic(
        ctx,
        topic,
        "topic",
        accepts=_GRID,
        kind="nav_msgs/OccupancyGrid",
        hint="view_scan shows scans; subscribe_topic reads other topics.",
    )
    path_name = scan_name = None
    path_type = scan_type = ""
    if path_topic:
        path_name, path_type = await typed_topic(
            ctx, path_topic, "path_topic", accepts=_PATH, kind="nav_msgs/Path"
        )
    if scan_topic:
        scan_name, scan_type = await typed_topic(
            ctx, scan_topic, "scan_topic", accepts=_SCAN, kind="sensor_msgs/LaserScan"
        )
    notes: list[str] = []

    async def optional(topic_name: str | None, topic_type: str, what: str) -> dict[str, Any] | None:
        if topic_name is None:
            return None
        try:
            return await first_message(ctx, topic_name, topic_type, timeout, what)
        except ToolFailure as exc:
            notes.append(str(exc).split(" Is its publisher")[0])
            return None

    message, path_message, scan_message = await asyncio.gather(
        first_message(ctx, name, msg_type, timeout, "map"),
        optional(path_name, path_type, "path"),
        optional(scan_name, scan_type, "scan"),
    )
    try:
        grid = await asyncio.to_thread(decode_grid, message)
    except MapError as exc:
        raise ToolFailure(f"{exc} (topic {name}).") from None
    del message  # the decoded cells are the one copy kept
    frame = grid.frame_id or "map"
    overlay, robot = await _overlay(
        ctx,
        frame,
        base_frame=base_frame.strip(),
        path_message=path_message,
        scan_message=scan_message,
        notes=notes,
        tf_wait=min(_TF_WAIT, timeout),
    )
    window = None
    if around_robot is not None:
        if robot is None:
            notes.append("around_robot needs the robot's pose: the whole map is shown.")
        else:
            window = (
                robot.x - around_robot,
                robot.y - around_robot,
                robot.x + around_robot,
                robot.y + around_robot,
            )
    picture, data = await asyncio.to_thread(_draw, grid, max_size, overlay, window)
    answer = _answer(
        name,
        grid,
        picture,
        data,
        robot=robot,
        overlay=overlay,
        notes=notes,
        path_heard=path_message is not None,
    )
    return ToolAnswer(text=_text(answer, base_frame), data=answer, images=(ToolImage(data, "image/png"),))


async def _overlay(
    ctx: ToolContext,
    frame: str,
    *,
    base_frame: str,
    path_message: dict[str, Any] | None,
    scan_message: dict[str, Any] | None,
    notes: list[str],
    tf_wait: float,
) -> tuple[Overlay, Pose2D | None]:
    """The robot's pose, the path and the scan hits in the map's frame (each placed through /tf)."""
    path_frame, path = decode_path(path_message) if path_message is not None else ("", [])
    scan = None
    if scan_message is not None:
        try:
            scan = decode_scan(scan_message)
        except ScanError as exc:
            notes.append(f"scan not drawn: {exc}")

    async def pose(source: str, what: str) -> Pose2D | None:
        if not source or source == frame:
            return Pose2D(0.0, 0.0, 0.0) if source else None
        found = await planar_pose(ctx, frame, source, tf_wait)
        if isinstance(found, str):
            notes.append(f"{what} not drawn: {found}")
            return None
        return found

    robot, path_pose, scan_pose = await asyncio.gather(
        pose(base_frame, "robot"),
        pose(path_frame if path else "", "path"),
        pose(scan.frame_id if scan is not None and scan.points else "", "scan"),
    )
    placed_path = to_frame(path, path_pose.x, path_pose.y, path_pose.yaw) if path and path_pose else []
    hits = to_frame(scan.points, scan_pose.x, scan_pose.y, scan_pose.yaw) if scan and scan_pose else []
    if robot is not None and base_frame == frame:
        robot = None
    return Overlay(robot=robot, path=placed_path, hits=hits), robot


def _draw(
    grid: Grid, max_size: int, overlay: Overlay, window: tuple[float, float, float, float] | None
) -> tuple[MapPicture, bytes]:
    picture = draw_map(grid, max_size=max_size, overlay=overlay, window=window)
    return picture, png_bytes(picture.image)


def _answer(
    name: str,
    grid: Grid,
    picture: MapPicture,
    data: bytes,
    *,
    robot: Pose2D | None,
    overlay: Overlay,
    notes: list[str],
    path_heard: bool,
) -> MapAnswer:
    return MapAnswer(
        topic=name,
        frame_id=grid.frame_id,
        width=grid.width,
        height=grid.height,
        resolution=round(grid.resolution, 6),
        size_m=[round(grid.width * grid.resolution, 3), round(grid.height * grid.resolution, 3)],
        origin=PlanarPose(
            x=round(grid.origin.x, 3), y=round(grid.origin.y, 3), yaw=round(math.degrees(grid.origin.yaw), 1)
        ),
        known=round(picture.shares.known, 4),
        free=round(picture.shares.free, 4),
        occupied=round(picture.shares.occupied, 4),
        cost=round(picture.shares.cost, 4),
        robot=None
        if robot is None
        else PlanarPose(x=round(robot.x, 3), y=round(robot.y, 3), yaw=round(math.degrees(robot.yaw), 1)),
        notes=notes,
        path_poses=len(overlay.path) if path_heard else None,
        scan_hits=len(overlay.hits) if overlay.hits or any(n.startswith("scan") for n in notes) else None,
        window=[round(v, 3) for v in picture.window],
        image_width=picture.image.width,
        image_height=picture.image.height,
        pixels_per_metre=round(picture.pixels_per_metre, 3),
        image_bytes=len(data),
    )


def _text(answer: MapAnswer, base_frame: str) -> str:
    parts = [
        f"{answer.topic} (frame {answer.frame_id or '?'}): {answer.width}x{answer.height} cells of "
        f"{answer.resolution:g} m = {answer.size_m[0]:g} x {answer.size_m[1]:g} m, origin "
        f"({answer.origin.x:g}, {answer.origin.y:g}, yaw {answer.origin.yaw:g}°)",
        f"known {answer.known:.0%} (free {answer.free:.0%}, occupied {answer.occupied:.0%}"
        + (f", cost {answer.cost:.0%}" if answer.cost else "")
        + ")",
    ]
    if answer.robot is not None:
        parts.append(
            f"robot {base_frame} at x={answer.robot.x:g} y={answer.robot.y:g} yaw={answer.robot.yaw:g}° "
            "(blue arrow)"
        )
    if answer.path_poses is not None:
        parts.append(f"path {answer.path_poses} poses (green)")
    if answer.scan_hits is not None:
        parts.append(f"scan {answer.scan_hits} hits (red)")
    window = answer.window
    parts.append(
        f"picture {answer.image_width}x{answer.image_height} px, {answer.pixels_per_metre:g} px/m, showing "
        f"x {window[0]:g}..{window[2]:g}, y {window[1]:g}..{window[3]:g} m"
    )
    text = "; ".join(parts) + "."
    if answer.notes:
        text += " " + " ".join(answer.notes)
    return text
