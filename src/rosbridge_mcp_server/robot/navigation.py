"""Motion goals on the robot's map: where they send the robot, and whether that place is fit to go to.

* ``robot/motion_goals.py`` tells a motion goal by its type in any spelling and by any carrier, and reads what
  it asks for (poses, a path, a drive along the robot's heading, or why it cannot be placed);
* :func:`survey` learns what a judgement needs from the robot: the latest map, where the robot is on it and
  where each goal's frame is (``/tf``), as one :class:`Scene`, with a drive along the heading placed from the
  robot's pose;
* :func:`map_problem`, :func:`path_map_problem`, :func:`zone_problem` and :func:`distance_problem` are the
  checks, pure: inside the map, known free space with a margin for the robot's size (and no obstacle on a
  straight drive), the robot's footprint (a disc) outside the keep-out zones and inside an allowed zone, at
  the goal and along a straight drive, not too far. The guard (``safety/``) applies them with the policy's
  values, so one rule holds for every path a goal can take;
* :func:`navigation_action` and :func:`goal_request` are the goal a navigator takes (Nav2's
  ``NavigateToPose`` and ``NavigateThroughPoses``, ROS 1 ``move_base``), :class:`Progress` what its feedback
  says while it runs (the path driven, the distance left, the recoveries);
* ``pictures/navigation.py`` draws it all (the map, the zones, the robot, the goal, the path driven).

Pure but for :func:`survey` and :func:`goal_request`; no MCP.
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.frames import planar_pose
from rosbridge_mcp_server.robot.map_reader import read_map
from rosbridge_mcp_server.robot.motion_goals import GoalPose
from rosbridge_mcp_server.robot.occupancy import OCCUPIED_FROM, Grid, Pose2D

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = [
    "DEFAULT_ROBOT_RADIUS",
    "GoalPose",
    "NavigationAction",
    "Polygon",
    "Progress",
    "Scene",
    "distance_problem",
    "goal_request",
    "map_problem",
    "navigation_action",
    "path_map_problem",
    "place",
    "point_in_polygon",
    "pose_message",
    "survey",
    "zone_problem",
]

#: The margin (m) kept between a goal and anything occupied or unknown on the map, and the robot's footprint
#: (a disc of this radius) judged against the zones, when the policy names none.
DEFAULT_ROBOT_RADIUS = 0.2

#: A polygon in the map frame: its corners (x, y) in metres.
Polygon = tuple[tuple[float, float], ...]


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


def _point_segment(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    length = dx * dx + dy * dy
    t = 0.0 if length == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length))
    return math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy)


def _crosses(
    a: tuple[float, float], b: tuple[float, float], c: tuple[float, float], d: tuple[float, float]
) -> bool:
    def side(p: tuple[float, float], q: tuple[float, float], r: tuple[float, float]) -> float:
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    return side(a, b, c) * side(a, b, d) < 0 and side(c, d, a) * side(c, d, b) < 0


def edge_distance(
    a: tuple[float, float], b: tuple[float, float], polygon: Sequence[tuple[float, float]]
) -> float:
    """The least distance between the segment *a*-*b* (a point when they are equal) and *polygon*'s edges."""
    best = math.inf
    for i in range(len(polygon)):
        c, d = polygon[i], polygon[(i + 1) % len(polygon)]
        if _crosses(a, b, c, d):
            return 0.0
        best = min(best, _point_segment(a, c, d), _point_segment(b, c, d), _point_segment(c, a, b),
                   _point_segment(d, a, b))  # fmt: skip
    return best


def _where(pose: Pose2D, start: Pose2D | None) -> str:
    if start is None:
        return f"the goal ({pose.x:.2f}, {pose.y:.2f})"
    if (start.x, start.y) == (pose.x, pose.y):
        return f"the robot's pose ({pose.x:.2f}, {pose.y:.2f})"
    return f"the straight drive from ({start.x:.2f}, {start.y:.2f}) to ({pose.x:.2f}, {pose.y:.2f})"


def zone_problem(
    pose: Pose2D,
    allowed: Mapping[str, Polygon],
    keep_out: Mapping[str, Polygon],
    radius: float = 0.0,
    start: Pose2D | None = None,
) -> str | None:
    """Why the robot's footprint (a disc of *radius*) at *pose* — or swept along the straight drive from
    *start* — breaks the geofence: any of it inside a keep-out zone, or (when zones are allowed) not all of it
    inside one allowed zone; ``None`` when it keeps to them."""
    a = (start.x, start.y) if start is not None else (pose.x, pose.y)
    b = (pose.x, pose.y)
    where = _where(pose, start)
    for name, polygon in keep_out.items():
        if point_in_polygon(*b, polygon) and start is None:
            return f"{where} is inside the keep-out zone {name!r}"
        if point_in_polygon(*a, polygon) or point_in_polygon(*b, polygon):
            return f"{where} enters the keep-out zone {name!r}"
        gap = edge_distance(a, b, polygon)
        if gap == 0.0:
            return f"{where} passes through the keep-out zone {name!r}"
        if gap < radius:
            return (
                f"the robot's footprint (radius {radius:g} m) at {where} reaches {radius - gap:.2f} m into "
                f"the keep-out zone {name!r}"
            )
    if allowed and not any(
        point_in_polygon(*a, polygon)
        and point_in_polygon(*b, polygon)
        and edge_distance(a, b, polygon) >= radius
        for polygon in allowed.values()
    ):
        names = ", ".join(repr(name) for name in allowed)
        if start is None and not any(point_in_polygon(*b, polygon) for polygon in allowed.values()):
            return f"{where} is outside every allowed zone ({names})"
        return (
            f"the robot's footprint (radius {radius:g} m) at {where} is not inside one allowed zone ({names})"
        )
    return None


def path_map_problem(grid: Grid, start: Pose2D, end: Pose2D) -> str | None:
    """Why the straight drive from *start* to *end* cannot be driven on *grid*: it leaves the map, or crosses
    an obstacle or unknown space (its centre line, sampled every half cell); ``None`` when it is clear."""
    length = math.hypot(end.x - start.x, end.y - start.y)
    steps = max(1, math.ceil(length / (grid.resolution / 2)))
    where = _where(end, start)
    for step in range(1, steps + 1):
        x = start.x + (end.x - start.x) * step / steps
        y = start.y + (end.y - start.y) * step / steps
        col, row = grid.to_cell(x, y)
        if not (0 <= col < grid.width and 0 <= row < grid.height):
            return f"{where} leaves the map at ({x:.2f}, {y:.2f})"
        value = grid.cells[int(row) * grid.width + int(col)]
        if OCCUPIED_FROM <= value <= 100:
            return f"{where} runs into an obstacle at ({x:.2f}, {y:.2f})"
        if value > 100:
            return f"{where} crosses unknown space at ({x:.2f}, {y:.2f})"
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
    along: float | None = None,
    namespace: str = "",
) -> Scene:
    """The map (unless given), the robot's pose on it and the goal's poses placed in its frame, learnt
    together; what could not be learnt is a problem of the scene, never an exception. With *along* (a drive
    of that many metres along the robot's heading; 0: in place) the goal is where that drive ends. The
    robot's *namespace* (``robot/namespaces.py``) says whose tf places them."""
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
        *(
            planar_pose(client, graph, map_frame, frame, min(timeout, 3.0), namespace=namespace)
            for frame in frames
        )
    )
    where = dict(zip(frames, found, strict=True))
    robot = where[base_frame]
    if isinstance(robot, str):
        problems.append(f"no transform from {map_frame} to {base_frame}: {robot}")
    placed: list[Pose2D] = []
    if along is not None and not isinstance(robot, str):
        c, s = math.cos(robot.yaw), math.sin(robot.yaw)
        placed.append(Pose2D(robot.x + c * along, robot.y + s * along, robot.yaw))
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


# --- the navigator's goal and its progress -----------------------------------------------------------------

#: Most driven-path points kept for the picture.
_MAX_TRACK = 2000
_MOVE_BASE = "move_base_msgs/MoveBaseAction"
_THROUGH_POSES = "nav2_msgs/action/NavigateThroughPoses"


@dataclass(frozen=True)
class NavigationAction:
    """The action a navigation goal is sent to: its name at the root (a robot's namespace goes before it)
    and its type."""

    name: str
    type: str


def navigation_action(*, ros1: bool, waypoints: bool) -> NavigationAction:
    """``move_base`` on ROS 1; Nav2's ``NavigateThroughPoses`` for poses in a row, else ``NavigateToPose``."""
    if ros1:
        return NavigationAction("/move_base", _MOVE_BASE)
    if waypoints:
        return NavigationAction("/navigate_through_poses", _THROUGH_POSES)
    return NavigationAction("/navigate_to_pose", "nav2_msgs/action/NavigateToPose")


def pose_message(frame: str, pose: Pose2D) -> dict[str, Any]:
    """*pose* as a ``geometry_msgs/PoseStamped`` in *frame* (on the floor, turned by its yaw)."""
    half = pose.yaw / 2
    return {
        "header": {"frame_id": frame},
        "pose": {
            "position": {"x": pose.x, "y": pose.y, "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(half), "w": math.cos(half)},
        },
    }


async def goal_request(
    graph: RosGraph, action_type: str, frame: str, goals: Sequence[Pose2D]
) -> dict[str, Any]:
    """The goal *action_type* takes for *goals* (in *frame*): ``move_base``'s ``target_pose``, Nav2's
    ``pose``, or its ``poses`` (as one ``nav_msgs/Goals`` where the action takes that: Kilted on)."""
    stamped = [pose_message(frame, goal) for goal in goals]
    if action_type == _MOVE_BASE:
        return {"target_pose": stamped[0]}
    if action_type != _THROUGH_POSES:
        return {"pose": stamped[0]}
    if await _takes_goals(graph, action_type):
        return {"poses": {"header": {"frame_id": frame}, "goals": stamped}}
    return {"poses": stamped}


async def _takes_goals(graph: RosGraph, action_type: str) -> bool:
    """Whether the action's goal takes its poses as one ``nav_msgs/Goals`` (Kilted on), not as a list."""
    try:
        typedefs = await graph.action_goal_typedefs(action_type)
    except RosbridgeError:
        return False
    return any(
        name.lstrip("_") == "poses" and length == -1 and base.endswith("/Goals")
        for typedef in (typedefs or {}).values()
        for name, base, length in typedef.fields()
    )


class Progress:
    """A navigation goal's progress as its feedback tells it (Nav2's ``current_pose``, ``distance_remaining``,
    ``estimated_time_remaining``, ``number_of_recoveries``; ``move_base``'s ``base_position``)."""

    def __init__(self, start: Pose2D, last_goal: Pose2D) -> None:
        #: The path driven in the map frame, from the start (at most :data:`_MAX_TRACK` points).
        self.track: list[tuple[float, float]] = [(start.x, start.y)]
        #: The recoveries the navigator counted last (0 until it says).
        self.recoveries = 0
        self.began = time.monotonic()
        self._goal = last_goal

    def feed(self, goal_id: str, feedback: Mapping[str, Any]) -> str:
        """Take one feedback message; the progress in words."""
        current = feedback.get("current_pose") or feedback.get("base_position")
        pose = current.get("pose") if isinstance(current, dict) else None
        here = pose.get("position") if isinstance(pose, dict) else None
        if isinstance(here, dict) and len(self.track) < _MAX_TRACK:
            px, py = here.get("x"), here.get("y")
            if isinstance(px, int | float) and isinstance(py, int | float):
                self.track.append((float(px), float(py)))
        remaining = feedback.get("distance_remaining")
        if remaining is None and self.track:
            remaining = math.hypot(self.track[-1][0] - self._goal.x, self.track[-1][1] - self._goal.y)
        count = feedback.get("number_of_recoveries")
        parts = [f"goal {goal_id}"]
        if isinstance(remaining, int | float):
            parts.append(f"{remaining:.2f} m to go")
        parts.append(f"{self.seconds:.0f} s")
        left = feedback.get("estimated_time_remaining")
        if isinstance(left, dict):
            seconds = float(left.get("sec", 0) or 0) + float(left.get("nanosec", 0) or 0) / 1e9
            parts.append(f"~{seconds:.0f} s left")
        if isinstance(count, int):
            self.recoveries = count
            parts.append(f"{count} recoveries")
        return ", ".join(parts)

    def ended_at(self, final: Pose2D | None) -> None:
        """The robot's pose once the goal ended (``None``: not known) closes the path driven."""
        if final is not None:
            self.track.append((final.x, final.y))

    @property
    def seconds(self) -> float:
        return time.monotonic() - self.began

    @property
    def driven(self) -> float:
        """Metres driven along the track."""
        return sum(math.dist(self.track[i], self.track[i + 1]) for i in range(len(self.track) - 1))
