"""The console's map panel: the robot's pose from /tf and the latched map drawn with it, at a low rate.

While a page is open, the panel listens to ``/tf`` and ``/tf_static`` (a frame tree of its own) and to the map
topic (``nav_msgs/OccupancyGrid``, latched). Twice a second it looks up the base frame in ``map`` (the map's
own frame), or in ``odom`` when there is no map frame, and pushes the pose when it moved; the map picture is
drawn again (off the event loop, with ``pictures/maps.py``'s drawing and the robot's arrow) only when the map,
the pose or the plan changed, at most once a second. The navigator's plan (``plan`` beside the map topic, as
Nav2 and move_base publish it while driving a goal) is drawn with its goal at the end, and dropped when no
plan came for :data:`PLAN_KEEP` seconds (the goal ended). It only listens: nothing here publishes or calls
anything.
"""

from __future__ import annotations

import asyncio
import base64
import importlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import NotConnectedError, RosbridgeError
from rosbridge_mcp_server.robot.frames import TF_TOPICS
from rosbridge_mcp_server.robot.map_reader import GRID_TYPE
from rosbridge_mcp_server.robot.messages import short_type_name
from rosbridge_mcp_server.robot.names import absolute_name
from rosbridge_mcp_server.robot.occupancy import Grid, MapError, Pose2D, decode_grid, decode_path
from rosbridge_mcp_server.robot.transforms import FrameTree, TransformError, frame_name

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = [
    "DEFAULT_BASE_FRAME",
    "DEFAULT_MAP_TOPIC",
    "MAP_FPS",
    "MAP_MAX_SIZE",
    "PLAN_KEEP",
    "POSE_HZ",
    "MapPanel",
    "Picture",
    "pose_of",
    "trying_again",
]

#: What the console draws with (its map here, its camera in hub.py), loaded when a console is served.
_PICTURE_MODULES = (
    "rosbridge_mcp_server.pictures.drawing",
    "rosbridge_mcp_server.pictures.maps",
    "rosbridge_mcp_server.pictures.images",
)

DEFAULT_MAP_TOPIC = "/map"
DEFAULT_BASE_FRAME = "base_link"
#: How often the pose is looked up (and pushed when it moved).
POSE_HZ = 2.0
#: The map picture's budget: at most this many pictures a second, at most this many pixels a side.
MAP_FPS = 1.0
MAP_MAX_SIZE = 420
#: How soon a missing map topic, or a robot that was down, is looked for again (seconds).
RETRY_EVERY = 2.0
_PATH_TYPE = "nav_msgs/Path"
#: A plan older than this (seconds) is no longer drawn: Nav2 republishes its plan while a goal runs.
PLAN_KEEP = 3.0


@dataclass(frozen=True)
class Picture:
    """A picture ready for the page: the map panel's drawing, or a camera frame (``console/hub.py``)."""

    seq: int
    topic: str
    mime: str
    data: str  #: base64
    width: int
    height: int

    def event(self) -> dict[str, Any]:
        return {
            "seq": self.seq,
            "topic": self.topic,
            "src": f"data:{self.mime};base64,{self.data}",
            "width": self.width,
            "height": self.height,
        }


class MapPanel:
    """The pose and map of one robot for the console; ``changed`` is called when the panel's state changes,
    ``pushed`` when a new pose or picture is ready."""

    def __init__(
        self,
        client: RosbridgeClient,
        graph: RosGraph,
        changed: Callable[[], None],
        pushed: Callable[[], None],
    ) -> None:
        # Pillow and the drawing load with a served console, not at its first picture: E-STOP shares this
        # event loop, which an import would hold for tens of milliseconds mid-session. A server without
        # --console never loads them for the console.
        for module in _PICTURE_MODULES:
            importlib.import_module(module)
        self._client = client
        self._graph = graph
        self._changed = changed
        self._pushed = pushed
        self.topic = DEFAULT_MAP_TOPIC
        self.base_frame = DEFAULT_BASE_FRAME
        self.status = "off"
        self.map_status = "off"
        self.pose: dict[str, Any] | None = None
        self.image: Picture | None = None
        self.poses = 0
        self.images = 0
        self._task: asyncio.Task[None] | None = None
        self._tree = FrameTree()
        self._grid: Grid | None = None
        self._grid_seq = 0
        #: The latest plan in the map's frame (its last point is the goal) and when it came.
        self.plan: list[tuple[float, float]] = []
        self._plan_at = -math.inf
        self._plan_seq = 0

    # --- what the page reads -------------------------------------------------------------------------------

    def state(self) -> dict[str, Any]:
        """The panel's settings and what it is doing (the pose and the picture come as their own events)."""
        return {
            "topic": self.topic,
            "base_frame": self.base_frame,
            "status": self.status,
            "map_status": self.map_status,
        }

    def pose_event(self) -> dict[str, Any] | None:
        return self.pose

    def image_event(self) -> dict[str, Any] | None:
        return None if self.image is None else self.image.event()

    # --- starting, stopping, choosing ----------------------------------------------------------------------

    @property
    def running(self) -> bool:
        return self._task is not None

    def start(self) -> None:
        """Listen (a page is open); a no-op when already listening."""
        if self._task is None:
            self.status = self.map_status = "starting"
            self._task = asyncio.create_task(self._run(), name="console map")
            self._changed()

    def stop(self) -> None:
        """Stop listening (no page is open): every subscription of the panel ends."""
        if self._task is not None:
            self._task.cancel()
            self._task = None
        self.status = self.map_status = "off"
        self._changed()

    def choose(self, topic: str, base_frame: str) -> None:
        """Show ``topic``'s map and ``base_frame``'s pose; a bad topic name raises :class:`RosbridgeError`."""
        name = absolute_name(topic or DEFAULT_MAP_TOPIC, "topic")
        base = frame_name(base_frame) or DEFAULT_BASE_FRAME
        self.topic, self.base_frame = name, base
        self.pose = None
        self.image = None
        self.poses += 1
        self.images += 1
        if self._task is not None:
            self._task.cancel()
            self._task = None
            self.start()
        self._changed()

    # --- listening -----------------------------------------------------------------------------------------

    async def _run(self) -> None:
        self._tree = FrameTree()
        self._grid = None
        try:
            async with asyncio.TaskGroup() as group:
                group.create_task(self._transforms())
                group.create_task(self._map())
                group.create_task(self._plans())
                group.create_task(self._poses())
        finally:
            if self._task is None:  # stopped, not restarted by choose(): let go of the map's cells
                self._tree = FrameTree()
                self._grid = None

    async def _transforms(self) -> None:
        while True:
            try:
                types = {topic: await self._graph.topic_type(topic) for topic in TF_TOPICS}
                present = {topic: msg_type for topic, msg_type in types.items() if msg_type}
                if present:
                    async with asyncio.TaskGroup() as group:
                        for topic, msg_type in present.items():
                            group.create_task(self._transform_pump(topic, msg_type))
                else:
                    self._say(status="no pose: nothing publishes /tf or /tf_static")
            except* RosbridgeError as group:
                self._say(status=trying_again(group.exceptions[0]))
            # Not a sync: how soon to look again after the robot or the topics were missing.
            await asyncio.sleep(RETRY_EVERY)

    async def _transform_pump(self, topic: str, msg_type: str) -> None:
        async with self._client.subscribe(topic, msg_type, max_queue=100) as subscription:
            while True:
                message = await subscription.get()
                self._tree.add_message(message, static=topic == "/tf_static", received=time.monotonic())

    async def _map(self) -> None:
        topic = self.topic
        while True:
            try:
                msg_type = await self._graph.topic_type(topic)
                if not msg_type:
                    self._say(map_status=f"no map: {topic} is not in the robot's graph")
                elif short_type_name(msg_type) != GRID_TYPE:
                    self._say(map_status=f"no map: {topic} carries {msg_type}, not a {GRID_TYPE}")
                else:
                    await self._maps_of(topic, msg_type)
            except RosbridgeError as exc:
                self._say(map_status=trying_again(exc))
            # Not a sync: how soon to look again after the topic or the robot was missing.
            await asyncio.sleep(RETRY_EVERY)

    async def _maps_of(self, topic: str, msg_type: str) -> None:
        # A latched map arrives once; a SLAM map again every few seconds: keep only the newest.
        async with self._client.subscribe(topic, msg_type, queue_length=1, max_queue=1) as subscription:
            self._say(map_status=f"waiting for {topic}")
            while True:
                message = await subscription.get()
                try:
                    self._grid = await asyncio.to_thread(decode_grid, message)
                except MapError as exc:
                    self._say(map_status=f"cannot draw {topic}: {exc}")
                    continue
                del message
                self._grid_seq += 1
                grid = self._grid
                self._say(map_status=f"{topic}: {grid.width}x{grid.height} cells of {grid.resolution:.3g} m")

    async def _plans(self) -> None:
        topic = f"{self.topic.rsplit('/', 1)[0]}/plan"
        while True:
            try:
                msg_type = await self._graph.topic_type(topic)
                if msg_type and short_type_name(msg_type) == _PATH_TYPE:
                    async with self._client.subscribe(topic, msg_type, queue_length=1, max_queue=1) as plans:
                        while True:
                            frame, points = decode_path(await plans.get())
                            grid = self._grid
                            if grid is not None and frame not in ("", grid.frame_id or "map"):
                                continue  # drawn only in the map's own frame
                            self.plan, self._plan_at = points, time.monotonic()
                            self._plan_seq += 1
            except RosbridgeError:
                pass
            # Not a sync: how soon to look again after the topic or the robot was missing.
            await asyncio.sleep(RETRY_EVERY)

    def _current_plan(self) -> list[tuple[float, float]]:
        if self.plan and time.monotonic() - self._plan_at > PLAN_KEEP:
            self.plan = []
            self._plan_seq += 1
        return self.plan

    async def _poses(self) -> None:
        drawn: tuple[int, Any, int] | None = None
        last_draw = -math.inf
        while True:
            found = self._look_up()
            if isinstance(found, str):
                if self.pose is not None or self.status != found:
                    self.pose = None
                    self.poses += 1
                    self._say(status=found)
                    self._pushed()
            else:
                frame, pose = found
                shown = _pose_event(frame, self.base_frame, pose)
                if shown != self.pose:
                    self.pose = shown
                    self.poses += 1
                    self._say(status="live")
                    self._pushed()
            grid = self._grid
            plan = self._current_plan()
            key = (self._grid_seq, self.pose, self._plan_seq)
            if grid is not None and key != drawn and time.monotonic() - last_draw >= 1 / MAP_FPS:
                robot = None
                if not isinstance(found, str) and found[0] == (grid.frame_id or "map"):
                    robot = found[1]
                data, width, height = await asyncio.to_thread(_draw, grid, robot, plan)
                drawn, last_draw = key, time.monotonic()
                self.images += 1
                self.image = Picture(self.images, self.topic, "image/png", data, width, height)
                self._pushed()
            # The pose's rate: /tf may change 50 times a second, the page needs two.
            await asyncio.sleep(1 / POSE_HZ)

    def _look_up(self) -> tuple[str, Pose2D] | str:
        grid_frame = self._grid.frame_id if self._grid is not None else ""
        return pose_of(self._tree, self.base_frame, grid_frame or "map")

    def _say(self, *, status: str | None = None, map_status: str | None = None) -> None:
        before = (self.status, self.map_status)
        if status is not None:
            self.status = status
        if map_status is not None:
            self.map_status = map_status
        if (self.status, self.map_status) != before:
            self._changed()


def trying_again(exc: BaseException) -> str:
    """What the page says while a listener waits to try again after ``exc``."""
    # A lost robot is said once, shortly (the page marks the last pose and picture stale); the long text
    # written for the model would stand twice in the panel, under the pose and under the map.
    if isinstance(exc, NotConnectedError):
        return "the robot is not connected (trying again)"
    return f"{exc} (trying again)"


def pose_of(tree: FrameTree, base_frame: str, map_frame: str = "map") -> tuple[str, Pose2D] | str:
    """``base_frame`` in ``map_frame``, else in ``odom`` (no map frame heard): (frame, pose), or why not."""
    frames = [map_frame] if tree.knows(map_frame) else []
    frames += [] if map_frame == "odom" else ["odom"]
    problem = ""
    for frame in frames:
        try:
            found = tree.lookup(frame, base_frame)
        except TransformError as exc:
            problem = str(exc)
            continue
        return frame, found.transform.planar()
    if not tree.frames():
        return "no pose yet: no transform heard on /tf or /tf_static"
    return (
        f"no pose: {problem}" if problem else f"no pose: neither {map_frame} nor odom has been heard on /tf"
    )


def _pose_event(frame: str, base: str, pose: Pose2D) -> dict[str, Any]:
    # Rounded to what the page shows, so a robot standing still pushes nothing.
    return {
        "frame": frame,
        "base_frame": base,
        "x": round(pose.x, 2),
        "y": round(pose.y, 2),
        "yaw": round(math.degrees(pose.yaw), 1),
    }


def _draw(grid: Grid, robot: Pose2D | None, plan: list[tuple[float, float]]) -> tuple[str, int, int]:
    from rosbridge_mcp_server.pictures.drawing import png_bytes  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.pictures.maps import Overlay, draw_map  # noqa: PLC0415 - on first use

    picture = draw_map(grid, max_size=MAP_MAX_SIZE, overlay=Overlay(robot=robot, path=plan))
    data = png_bytes(picture.image)
    return base64.b64encode(data).decode("ascii"), picture.image.width, picture.image.height
