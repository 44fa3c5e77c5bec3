"""``view_map``: an occupancy grid (a map or a costmap) as a picture, with the robot, a plan, a scan on it."""

from __future__ import annotations

import asyncio
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.frames import planar_pose
from rosbridge_mcp_server.robot.map_reader import GRID_TYPE, receive_map
from rosbridge_mcp_server.robot.names import absolute_name
from rosbridge_mcp_server.robot.namespaces import under
from rosbridge_mcp_server.robot.occupancy import Grid, MapError, Pose2D, decode_path, to_frame
from rosbridge_mcp_server.robot.scans import ScanError, decode_scan
from rosbridge_mcp_server.robot.text import NAME_CHARS, shown
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolImage,
    ToolSpec,
)
from rosbridge_mcp_server.tools.namespaces import (
    NamespaceArgument,
    given_namespace,
    namespaced_topic,
    non_defaults,
)
from rosbridge_mcp_server.tools.typed_topics import first_message, is_type, typed_topic

if TYPE_CHECKING:
    from rosbridge_mcp_server.pictures.maps import MapPicture, Overlay

__all__ = ["SPEC", "MapAnswer", "run"]

_GRID = is_type(GRID_TYPE)
_PATH = is_type("nav_msgs/Path")
_SCAN = is_type("sensor_msgs/LaserScan")
#: The longest the robot's, the path's and the scan's frames are waited for on /tf.
_TF_WAIT = 2.0


class MapAnswer(BaseModel):
    """The map drawn; metres and degrees in the map's frame."""

    topic: str
    frame_id: str
    cells: list[int] = Field(description="[width, height]")
    resolution: float
    origin: list[float] = Field(description="[x, y, yaw]")
    shares: dict[str, float] = Field(description="known, free, occupied, cost: 0-1")
    robot: list[float] | None = Field(description="[x, y, yaw]")
    path_poses: int | None = None
    scan_hits: int | None = None
    window: list[float] = Field(description="[x_min, y_min, x_max, y_max]")
    pixels_per_metre: float
    notes: list[str]


SPEC = ToolSpec(
    name="view_map",
    title="Map picture",
    description=(
        "A map or costmap as a picture: the robot (blue, from /tf), a plan (green), a scan (red). "
        'Read-only. Example: {"path_topic": "/plan", "scan_topic": "/scan", '
        '"around_robot": 4}'
    ),
    hints=READS_ROBOT,
    output=MapAnswer,
)


async def _map(ctx: ToolContext, name: str, msg_type: str, timeout: float, notes: list[str]) -> Grid:
    """The grid (``robot/map_reader.py``: CBOR, once more as JSON where large CBOR is dropped), or a
    :class:`ToolFailure` saying none came or what is wrong with it."""
    try:
        reading = await receive_map(ctx.client, name, msg_type, timeout)
    except MapError as exc:
        raise ToolFailure(f"{exc} (topic {name}).") from None
    if reading.grid is None:
        raise ToolFailure(
            f"No map arrived on {name} within {timeout:g} s. Is its publisher running? get_topic_info "
            "shows the topic's publishers; a larger timeout waits longer."
        )
    if reading.note is not None:
        notes.append(reading.note)
    return reading.grid


async def run(
    ctx: ToolContext,
    *,
    topic: Annotated[str, Field(description="e.g. /map or /global_costmap/costmap")] = "/map",
    base_frame: Annotated[str, Field(description='Robot frame, e.g. base_link; "" for none')] = "base_link",
    path_topic: Annotated[str, Field(description="nav_msgs/Path, e.g. /plan")] = "",
    scan_topic: Annotated[str, Field(description="LaserScan, e.g. /scan")] = "",
    around_robot: Annotated[float, Field(ge=0, le=1000, description="Metres around the robot, e.g. 3")] = 0.0,
    max_size: Annotated[int, Field(ge=64, le=2048, description="Pixels, e.g. 800")] = 800,
    timeout: Annotated[float, Field(gt=0, le=60, description="Seconds per message, e.g. 5")] = 5.0,
    namespace: NamespaceArgument = None,
) -> ToolAnswer:
    """Take one grid (and plan and scan), place them with /tf, draw off the event loop."""
    given = {
        "topic": topic,
        "base_frame": base_frame,
        "path_topic": path_topic,
        "scan_topic": scan_topic,
        "around_robot": around_robot,
        "max_size": max_size,
        "timeout": timeout,
    }
    name, msg_type, ns, found_note = await namespaced_topic(
        ctx,
        topic,
        "topic",
        namespace,
        tool=SPEC.name,
        arguments=non_defaults(run, given),
        accepts=_GRID,
        kind=GRID_TYPE,
        hint="view_scan shows scans; subscribe_topic reads other topics.",
    )
    notes: list[str] = [found_note] if found_note is not None else []
    grid, path_message, scan_message = await _messages(
        ctx, (name, msg_type), ns, (path_topic, scan_topic), timeout=timeout, notes=notes
    )
    overlay, robot = await _overlay(
        ctx,
        grid.frame_id or "map",
        base_frame=base_frame.strip(),
        path_message=path_message,
        scan_message=scan_message,
        notes=notes,
        tf_wait=min(_TF_WAIT, timeout),
        namespace=ns if ns or given_namespace(ctx, namespace) is not None else None,
        topic=name,
    )
    off_map = _off_map(grid, robot, base_frame.strip())
    if off_map is not None:
        notes.insert(0, off_map)  # first: the model must not take the robot for missing
    window = _window(robot, around_robot, notes)
    picture, data = await asyncio.to_thread(_draw, grid, max_size, overlay, window)
    answer = _answer(
        name, grid, picture, robot=robot, overlay=overlay, notes=notes, path_heard=path_message is not None
    )
    text = _text(answer, base_frame, picture.image.size, drawn=off_map is None)
    return ToolAnswer(text=text, data=answer, images=(ToolImage(data, "image/png"),))


async def _extra(
    ctx: ToolContext, ns: str, topic: str, argument: str, *, accepts: Callable[[str], bool], kind: str
) -> tuple[str, str] | None:
    """The plan's or the scan's topic (under the map's namespace) and its type, checked; ``None``: not
    asked."""
    if not topic:
        return None
    return await typed_topic(
        ctx, under(ns, absolute_name(topic, argument)), argument, accepts=accepts, kind=kind
    )


async def _messages(
    ctx: ToolContext,
    grid_topic: tuple[str, str],
    ns: str,
    asked: tuple[str, str],
    *,
    timeout: float,
    notes: list[str],
) -> tuple[Grid, dict[str, Any] | None, dict[str, Any] | None]:
    """The grid, and the plan and the scan (*asked*: their topics, ``""`` for none) checked and awaited
    alongside it (each a note when it did not come), given up with it when it fails."""
    path_topic, scan_topic = asked
    extras = (
        await _extra(ctx, ns, path_topic, "path_topic", accepts=_PATH, kind="nav_msgs/Path"),
        await _extra(ctx, ns, scan_topic, "scan_topic", accepts=_SCAN, kind="sensor_msgs/LaserScan"),
    )

    async def optional(topic: tuple[str, str] | None, what: str) -> dict[str, Any] | None:
        if topic is None:
            return None
        try:
            return await first_message(ctx, topic[0], topic[1], timeout, what)
        except ToolFailure:
            notes.append(f"{what} not drawn: nothing arrived on {topic[0]} within {timeout:g} s.")
            return None

    tasks = [
        asyncio.create_task(optional(extras[0], "path")),
        asyncio.create_task(optional(extras[1], "scan")),
    ]
    try:
        grid = await _map(ctx, *grid_topic, timeout, notes)
        path_message, scan_message = await asyncio.gather(*tasks)
    finally:
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
    return grid, path_message, scan_message


def _window(
    robot: Pose2D | None, around_robot: float, notes: list[str]
) -> tuple[float, float, float, float] | None:
    """The map-frame box *around_robot* metres about the robot (``None``: the whole map)."""
    if not around_robot:
        return None
    if robot is None:
        notes.append("around_robot needs the robot's pose: the whole map is shown.")
        return None
    return (robot.x - around_robot, robot.y - around_robot, robot.x + around_robot, robot.y + around_robot)


async def _overlay(
    ctx: ToolContext,
    frame: str,
    *,
    base_frame: str,
    path_message: dict[str, Any] | None,
    scan_message: dict[str, Any] | None,
    notes: list[str],
    tf_wait: float,
    namespace: str | None = "",
    topic: str = "",
) -> tuple[Overlay, Pose2D | None]:
    """The robot's pose, the path and the scan hits in the map's frame (each placed through /tf)."""
    from rosbridge_mcp_server.pictures.maps import Overlay  # noqa: PLC0415 - on first use

    path_frame, path = decode_path(path_message) if path_message is not None else ("", [])
    scan = None
    if scan_message is not None:
        try:
            scan = decode_scan(scan_message)
        except ScanError as exc:
            notes.append(f"scan not drawn: {exc}")

    async def pose(source: str, what: str) -> Pose2D | None:
        found = await planar_pose(
            ctx.client, ctx.graph, frame, source, tf_wait, namespace=namespace, topic=topic
        )
        if isinstance(found, str):
            notes.append(f"{what} not drawn: {found}")
            return None
        return found

    async def nothing() -> None:
        return None

    if scan is not None and scan.points and not scan.frame_id:
        notes.append("scan not drawn: its header has no frame_id to place it by.")
    robot, path_pose, scan_pose = await asyncio.gather(
        pose(base_frame, "robot") if base_frame and base_frame != frame else nothing(),
        # A path without a frame is taken to be in the map's.
        pose(path_frame or frame, "path") if path else nothing(),
        pose(scan.frame_id, "scan") if scan is not None and scan.points and scan.frame_id else nothing(),
    )
    placed_path = to_frame(path, path_pose.x, path_pose.y, path_pose.yaw) if path and path_pose else []
    hits = to_frame(scan.points, scan_pose.x, scan_pose.y, scan_pose.yaw) if scan and scan_pose else []
    return Overlay(robot=robot, path=placed_path, hits=hits), robot


def _draw(
    grid: Grid, max_size: int, overlay: Overlay, window: tuple[float, float, float, float] | None
) -> tuple[MapPicture, bytes]:
    from rosbridge_mcp_server.pictures.drawing import png_bytes  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.pictures.maps import draw_map  # noqa: PLC0415 - on first use

    picture = draw_map(grid, max_size=max_size, overlay=overlay, window=window)
    return picture, png_bytes(picture.image)


def _answer(
    name: str,
    grid: Grid,
    picture: MapPicture,
    *,
    robot: Pose2D | None,
    overlay: Overlay,
    notes: list[str],
    path_heard: bool,
) -> MapAnswer:
    shares = picture.shares
    return MapAnswer(
        topic=name,
        frame_id=shown(grid.frame_id, NAME_CHARS),  # the robot's text: a publisher may put anything there
        cells=[grid.width, grid.height],
        resolution=round(grid.resolution, 6),
        origin=grid.origin.rounded(),
        shares={
            "known": round(shares.known, 4),
            "free": round(shares.free, 4),
            "occupied": round(shares.occupied, 4),
            "cost": round(shares.cost, 4),
        },
        robot=None if robot is None else robot.rounded(),
        path_poses=len(overlay.path) if path_heard else None,
        scan_hits=len(overlay.hits) if overlay.hits or any(n.startswith("scan") for n in notes) else None,
        window=[round(v, 3) for v in picture.window],
        pixels_per_metre=round(picture.pixels_per_metre, 3),
        notes=notes,
    )


#: Farther than this off the map, how far is not worked out (a pose from /tf may be 1e308 m away).
FAR = 1e12


def _off_map(grid: Grid, robot: Pose2D | None, base_frame: str) -> str | None:
    """The note that the robot is outside the grid (so the picture cannot show it): where it is and how far
    outside the grid's extent; ``None`` when it is on the grid or not known."""
    if robot is None:
        return None
    outside = grid.outside(robot.x, robot.y)
    if outside <= 0:
        return None
    x_min, y_min, x_max, y_max = (round(v, 2) for v in grid.extent())
    x, y, frame = round(robot.x, 2), round(robot.y, 2), shown(grid.frame_id, NAME_CHARS) or "map"
    # Rounded up: a robot a millimetre off the map is not said to be 0 m off it. /tf may say 1e308 m.
    far = f"{math.ceil(outside * 100) / 100:g}" if outside < FAR else f"over {FAR:g}"
    return (
        f"The robot ({base_frame} at x={x:g} y={y:g} in {frame}) is off the map, "
        f"{far} m outside its extent (x {x_min:g}..{x_max:g}, "
        f"y {y_min:g}..{y_max:g} m), so the picture cannot show it."
    )


def _text(answer: MapAnswer, base_frame: str, size: tuple[int, int], *, drawn: bool) -> str:
    (width, height), resolution = answer.cells, answer.resolution
    x, y, yaw = answer.origin
    shares = answer.shares
    parts = [
        f"{answer.topic} (frame {answer.frame_id or '?'}): {width}x{height} cells of {resolution:g} m = "
        f"{round(width * resolution, 2):g} x {round(height * resolution, 2):g} m, origin ({x:g}, {y:g}, "
        f"yaw {yaw:g}°)",
        f"known {shares['known']:.0%} (free {shares['free']:.0%}, occupied {shares['occupied']:.0%}"
        + (f", cost {shares['cost']:.0%}" if shares["cost"] else "")
        + ")",
    ]
    if answer.robot is not None:
        rx, ry, ryaw = answer.robot
        shown = "(blue arrow)" if drawn else "(off the map: not drawn)"
        parts.append(f"robot {base_frame} at x={rx:g} y={ry:g} yaw={ryaw:g}° {shown}")
    if answer.path_poses is not None:
        parts.append(f"path {answer.path_poses} poses (green)")
    if answer.scan_hits is not None:
        parts.append(f"scan {answer.scan_hits} hits (red)")
    window = answer.window
    parts.append(
        f"picture {size[0]}x{size[1]} px, {answer.pixels_per_metre:g} px/m, showing x "
        f"{window[0]:g}..{window[2]:g}, y {window[1]:g}..{window[3]:g} m"
    )
    text = "; ".join(parts) + "."
    if answer.notes:
        text += " " + " ".join(answer.notes)
    return text
