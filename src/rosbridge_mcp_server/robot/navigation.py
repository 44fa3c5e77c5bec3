"""Navigation goals on the robot's map: which action goals send the robot somewhere, where they send it, and
whether that place is fit to go to.

* :func:`navigation_goal` tells a navigation goal (Nav2 ``NavigateToPose``, ``NavigateThroughPoses``,
  ``FollowWaypoints``; ROS 1 ``move_base``) by its action type, and reads the poses out of it
  (:func:`goal_poses`), however the goal was spelt (``navigate_to`` or ``publish_action``);
* :func:`survey` learns what a judgement needs from the robot: the latest map, where the robot is on it and
  where each goal's frame is (``/tf``), as one :class:`Scene`;
* :func:`map_problem`, :func:`zone_problem` and :func:`distance_problem` are the checks, pure: inside the map,
  known free space with a margin for the robot's size, inside the allowed zones and outside the keep-out
  zones, not too far. The guard (``safety/``) applies them with the policy's values, so one rule holds for
  every path a goal can take;
* ``pictures/navigation.py`` draws it all (the map, the zones, the robot, the goal, the path driven).

Pure but for :func:`survey`; no MCP.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.frames import look_up_transform
from rosbridge_mcp_server.robot.listening import listen
from rosbridge_mcp_server.robot.messages import short_type_name
from rosbridge_mcp_server.robot.occupancy import OCCUPIED_FROM, Grid, MapError, Pose2D, decode_grid, yaw_of
from rosbridge_mcp_server.robot.transforms import TransformError

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = [
    "DEFAULT_ROBOT_RADIUS",
    "NAVIGATION_GOALS",
    "GoalPose",
    "Polygon",
    "Scene",
    "distance_problem",
    "goal_poses",
    "map_problem",
    "navigation_goal",
    "point_in_polygon",
    "survey",
    "zone_problem",
]

#: The margin (m) kept between a goal and anything occupied or unknown on the map, when the policy names none.
DEFAULT_ROBOT_RADIUS = 0.2

#: Navigation actions by type (``pkg/Name``, either dialect) → the goal field holding its pose(s).
NAVIGATION_GOALS: dict[str, str] = {
    "nav2_msgs/NavigateToPose": "pose",
    "nav2_msgs/NavigateThroughPoses": "poses",
    "nav2_msgs/FollowWaypoints": "poses",
    "move_base_msgs/MoveBase": "target_pose",
}

#: A polygon in the map frame: its corners (x, y) in metres.
Polygon = tuple[tuple[float, float], ...]


def navigation_goal(action_type: str) -> str | None:
    """The goal field holding the poses when *action_type* sends the robot somewhere, else ``None``.

    ``nav2_msgs/action/NavigateToPose``, ``nav2_msgs/NavigateToPose`` and ROS 1's
    ``move_base_msgs/MoveBaseAction`` are all recognised."""
    short = short_type_name(action_type.strip())
    if short.endswith("Action"):
        short = short[: -len("Action")]
    return NAVIGATION_GOALS.get(short)


@dataclass(frozen=True)
class GoalPose:
    """One pose a goal asks for, as written in it: frame (``""`` when the header names none), x, y, yaw."""

    frame: str
    x: float
    y: float
    yaw: float


def _finite(value: object) -> float | None:
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return None


def goal_poses(action_type: str, goal: Mapping[str, Any]) -> list[GoalPose] | str:
    """The poses of a navigation goal, or a sentence saying why they cannot be read (e.g. a non-finite x)."""
    key = navigation_goal(action_type)
    if key is None:
        return []
    value = goal.get(key)
    stamped = value if isinstance(value, list) else [value] if value is not None else []
    if not stamped:
        return f"the goal has no {key} to go to"
    out: list[GoalPose] = []
    for index, item in enumerate(stamped):
        where = f"{key}[{index}]" if isinstance(value, list) else key
        if not isinstance(item, Mapping):
            return f"{where} is not a geometry_msgs/PoseStamped"
        header = item.get("header")
        frame = str(header.get("frame_id", "")).lstrip("/") if isinstance(header, Mapping) else ""
        body = item.get("pose")
        body = body if isinstance(body, Mapping) else {}
        position = body.get("position")
        position = position if isinstance(position, Mapping) else {}
        x, y = _finite(position.get("x", 0.0)), _finite(position.get("y", 0.0))
        if x is None or y is None:
            return f"{where}.pose.position is not a finite point"
        orientation = body.get("orientation")
        if isinstance(orientation, Mapping) and any(
            _finite(orientation.get(k, 0.0)) is None for k in ("x", "y", "z", "w")
        ):
            return f"{where}.pose.orientation is not a finite quaternion"
        out.append(GoalPose(frame, x, y, yaw_of(orientation)))
    return out


@dataclass(frozen=True)
class Scene:
    """What a navigation goal is judged against, learnt from the robot just before it is sent.

    ``goals`` are the goal's poses placed in the map frame (empty when one could not be placed: ``problems``
    says why); ``robot`` is the robot's pose in the map frame, ``None`` when ``/tf`` did not tell."""

    map_topic: str
    base_frame: str
    grid: Grid | None = None
    robot: Pose2D | None = None
    goals: tuple[Pose2D, ...] = ()
    problems: tuple[str, ...] = ()
    notes: tuple[str, ...] = field(default=())

    @property
    def map_frame(self) -> str:
        return (self.grid.frame_id if self.grid is not None else "") or "map"


def point_in_polygon(x: float, y: float, polygon: Sequence[tuple[float, float]]) -> bool:
    """Whether (x, y) is inside *polygon* (even-odd rule; a point on an edge may fall either way)."""
    inside = False
    count = len(polygon)
    for i in range(count):
        x1, y1 = polygon[i]
        x2, y2 = polygon[(i + 1) % count]
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def map_problem(grid: Grid, pose: Pose2D, radius: float) -> str | None:
    """Why *pose* is no place to send the robot on *grid*: off the map, in an obstacle, in unknown space, or
    nearer than *radius* to either; ``None`` when it is known free space with that margin."""
    col, row = grid.to_cell(pose.x, pose.y)
    where = f"({pose.x:.2f}, {pose.y:.2f})"
    if not (0 <= col < grid.width and 0 <= row < grid.height):
        x0, y0 = grid.to_map(0, 0)
        x1, y1 = grid.to_map(grid.width, grid.height)
        return (
            f"the goal {where} is off the map (the map covers x {min(x0, x1):.2f}..{max(x0, x1):.2f}, "
            f"y {min(y0, y1):.2f}..{max(y0, y1):.2f} m)"
        )
    centre = grid.cells[int(row) * grid.width + int(col)]
    if OCCUPIED_FROM <= centre <= 100:
        return f"the goal {where} is in an obstacle (an occupied map cell)"
    if centre > 100:
        return f"the goal {where} is in unknown space (not mapped)"
    reach = radius / grid.resolution
    span = math.ceil(reach)
    nearest: tuple[float, str] | None = None
    for dr in range(-span, span + 1):
        for dc in range(-span, span + 1):
            distance = math.hypot(dc, dr) * grid.resolution
            if distance > radius:
                continue
            c, r = int(col) + dc, int(row) + dr
            if not (0 <= c < grid.width and 0 <= r < grid.height):
                what = "the map's edge"
            else:
                value = grid.cells[r * grid.width + c]
                if OCCUPIED_FROM <= value <= 100:
                    what = "an obstacle"
                elif value > 100:
                    what = "unknown space"
                else:
                    continue
            if nearest is None or distance < nearest[0]:
                nearest = (distance, what)
    if nearest is not None:
        return (
            f"the goal {where} is {nearest[0]:.2f} m from {nearest[1]}, nearer than the robot's margin "
            f"{radius:g} m"
        )
    return None


def zone_problem(pose: Pose2D, allowed: Mapping[str, Polygon], keep_out: Mapping[str, Polygon]) -> str | None:
    """Why *pose* breaks the geofence: inside a keep-out zone, or (when zones are allowed) outside all."""
    for name, polygon in keep_out.items():
        if point_in_polygon(pose.x, pose.y, polygon):
            return f"the goal ({pose.x:.2f}, {pose.y:.2f}) is inside the keep-out zone {name!r}"
    if allowed and not any(point_in_polygon(pose.x, pose.y, polygon) for polygon in allowed.values()):
        names = ", ".join(repr(name) for name in allowed)
        return f"the goal ({pose.x:.2f}, {pose.y:.2f}) is outside every allowed zone ({names})"
    return None


def distance_problem(pose: Pose2D, robot: Pose2D, max_distance: float) -> str | None:
    """Why *pose* is too far from the robot (straight line), else ``None``."""
    distance = math.hypot(pose.x - robot.x, pose.y - robot.y)
    if distance > max_distance:
        return (
            f"the goal is {distance:.2f} m from the robot, beyond the maximum goal distance "
            f"{max_distance:g} m"
        )
    return None


# --- learning the scene ---------------------------------------------------------------------------------


async def read_map(
    client: RosbridgeClient, graph: RosGraph, topic: str, timeout: float
) -> tuple[Grid | None, str | None]:
    """The latest map on *topic* (CBOR when the bridge can), or why there is none."""
    msg_type = await graph.topic_type(topic)
    if not msg_type:
        return None, f"no map: {topic} is not in the robot's graph (is the map server running?)"
    if short_type_name(msg_type) != "nav_msgs/OccupancyGrid":
        return None, f"no map: {topic} carries {msg_type}, not nav_msgs/OccupancyGrid"
    dialect = await client.dialect()
    compression = dialect.compression_for(fixed_size_arrays=False)
    heard = await listen(
        client, topic, msg_type, count=1, duration=None, first_timeout=timeout, compression=compression
    )
    if not heard.messages and compression is not None and dialect.drops_large_cbor:
        heard = await listen(client, topic, msg_type, count=1, duration=None, first_timeout=timeout)
    if not heard.messages:
        return None, f"no map: nothing arrived on {topic} within {timeout:g} s"
    try:
        return await asyncio.to_thread(decode_grid, heard.messages[0].message), None
    except MapError as exc:
        return None, f"no usable map on {topic}: {exc}"


async def frame_pose(
    client: RosbridgeClient, graph: RosGraph, target: str, source: str, timeout: float
) -> Pose2D | str:
    """Where *source* is in *target* (x, y, yaw) from ``/tf``, or why it is not known."""
    if source == target:
        return Pose2D(0.0, 0.0, 0.0)
    try:
        found = await look_up_transform(client, graph, target, source, timeout=timeout)
    except TransformError as exc:
        return str(exc)
    t = found.lookup.transform
    x, y, z, w = t.rotation
    return Pose2D(
        t.translation[0], t.translation[1], math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    )


def place(pose: GoalPose, frame: Pose2D) -> Pose2D:
    """*pose* (given in a frame whose origin is at *frame* in the map) in the map frame."""
    c, s = math.cos(frame.yaw), math.sin(frame.yaw)
    return Pose2D(frame.x + c * pose.x - s * pose.y, frame.y + s * pose.x + c * pose.y, frame.yaw + pose.yaw)


async def survey(
    client: RosbridgeClient,
    graph: RosGraph,
    *,
    map_topic: str,
    base_frame: str,
    poses: Sequence[GoalPose],
    timeout: float,
    grid: Grid | None = None,
) -> Scene:
    """The map (unless given), the robot's pose on it and the goal's poses placed in its frame, learnt
    together; what could not be learnt is a problem of the scene, never an exception."""
    problems: list[str] = []
    if grid is None:
        try:
            grid, problem = await read_map(client, graph, map_topic, timeout)
        except RosbridgeError as exc:
            grid, problem = None, f"no map: reading {map_topic} failed: {exc}"
        if problem is not None:
            problems.append(problem)
    map_frame = (grid.frame_id if grid is not None else "") or "map"
    frames = sorted({pose.frame or map_frame for pose in poses} | {base_frame})
    found = await asyncio.gather(
        *(frame_pose(client, graph, map_frame, frame, min(timeout, 3.0)) for frame in frames)
    )
    where = dict(zip(frames, found, strict=True))
    robot = where[base_frame]
    if isinstance(robot, str):
        problems.append(f"no transform from {map_frame} to {base_frame}: {robot}")
    placed: list[Pose2D] = []
    for pose in poses:
        frame = pose.frame or map_frame
        origin = where[frame]
        if isinstance(origin, str):
            problems.append(f"the goal's frame {frame} cannot be placed in {map_frame}: {origin}")
            placed = []
            break
        placed.append(place(pose, origin))
    return Scene(
        map_topic=map_topic,
        base_frame=base_frame,
        grid=grid,
        robot=None if isinstance(robot, str) else robot,
        goals=tuple(placed),
        problems=tuple(problems),
    )
