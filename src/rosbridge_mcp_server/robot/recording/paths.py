"""The path a recording shows the robot driving, in the map's frame.

A path topic may be odometry (``nav_msgs/Odometry``), a pose (``PoseStamped``, ``PoseWithCovarianceStamped``),
a plan (``nav_msgs/Path``: its last message's poses) or ``/tf`` itself (the robot's base frame in the map,
``map → odom → base``). Poses in another frame than the map's (``/odom`` is in ``odom``) are placed in the
map through the recording's own ``/tf``: the ``map → odom`` transform in force when each pose was taken (the
latest one before it, else the first). When the recording has no such transform, the path is drawn as if the
frames coincided and :attr:`RecordedPath.note` says so plainly. Pure: it reads decoded messages.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from rosbridge_mcp_server.robot.occupancy import Pose2D, yaw_of

__all__ = ["BASE_FRAMES", "PathReader", "RecordedPath", "compose"]

#: The frames a robot's base goes by (REP 105), looked for in ``/tf`` when it is the path topic.
BASE_FRAMES = ("base_footprint", "base_link")
#: What a path can be read from, for the answer when the topic holds none of it.
DRAWABLE = "Odometry, PoseStamped, PoseWithCovarianceStamped, nav_msgs/Path or tf2_msgs/TFMessage (/tf)"


def compose(a: Pose2D, b: Pose2D) -> Pose2D:
    """``b`` (given in ``a``'s frame) in the frame ``a`` is given in."""
    cos, sin = math.cos(a.yaw), math.sin(a.yaw)
    return Pose2D(a.x + cos * b.x - sin * b.y, a.y + sin * b.x + cos * b.y, a.yaw + b.yaw)


def _frame(message: Mapping[str, Any]) -> str:
    header = message.get("header")
    return str(header.get("frame_id", "")).lstrip("/") if isinstance(header, Mapping) else ""


def _pose(pose: Any) -> Pose2D | None:
    if isinstance(pose, Mapping) and isinstance(pose.get("pose"), Mapping):
        pose = pose["pose"]  # Odometry, PoseWithCovarianceStamped, a Path's PoseStamped
    if not isinstance(pose, Mapping):
        return None
    position = pose.get("position", pose.get("translation"))
    if not isinstance(position, Mapping):
        return None
    x, y = position.get("x"), position.get("y")
    if not isinstance(x, int | float) or not isinstance(y, int | float):
        return None
    if not (math.isfinite(x) and math.isfinite(y)):
        return None
    return Pose2D(float(x), float(y), yaw_of(pose.get("orientation", pose.get("rotation"))))


@dataclass
class RecordedPath:
    """The poses (map frame where it could be placed), the frame they came in, and what to say about it."""

    poses: list[Pose2D] = field(default_factory=list)
    frame: str = ""
    note: str = ""


@dataclass
class PathReader:
    """Fed every message of the path topic and of ``/tf``; :meth:`path` places the poses in the map."""

    path_topic: str
    #: (time, pose, frame) of each pose of the path topic.
    _raw: list[tuple[int, Pose2D, str]] = field(default_factory=list)
    #: parent → child → [(time, transform)], from /tf.
    _tf: dict[tuple[str, str], list[tuple[int, Pose2D]]] = field(default_factory=dict)
    _kinds: set[str] = field(default_factory=set)
    map_frame: str = ""

    def feed(self, topic: str, time_ns: int, message: Any) -> None:
        if not isinstance(message, Mapping):
            return
        if isinstance(message.get("transforms"), list):
            self._transforms(time_ns, message["transforms"], record=topic == self.path_topic)
            return
        if topic != self.path_topic:
            return
        if isinstance(message.get("poses"), list):  # nav_msgs/Path: the latest plan replaces the last
            self._kinds.add("plan")
            self._raw = [
                (time_ns, pose, _frame(item) or _frame(message))
                for item in message["poses"]
                if isinstance(item, Mapping) and (pose := _pose(item)) is not None
            ]
            return
        pose = _pose(message.get("pose"))
        if pose is not None:
            self._kinds.add("pose")
            self._raw.append((time_ns, pose, _frame(message)))

    def _transforms(self, time_ns: int, transforms: list[Any], *, record: bool) -> None:
        for item in transforms:
            if not isinstance(item, Mapping):
                continue
            parent, child = _frame(item), str(item.get("child_frame_id", "")).lstrip("/")
            pose = _pose(item.get("transform"))
            if pose is None or not parent or not child:
                continue
            self._tf.setdefault((parent, child), []).append((time_ns, pose))
            if record and child in BASE_FRAMES:
                self._kinds.add("tf")
                self._raw.append((time_ns, pose, parent))

    def _link(self, parent: str, child: str, time_ns: int, depth: int = 3) -> Pose2D | None:
        """The ``parent → child`` transform at ``time_ns`` (each link the latest before it, else its first),
        directly or through up to ``depth`` frames between (``map → world → odom``)."""
        found = self._tf.get((parent, child))
        if found:
            at = bisect.bisect_right([t for t, _ in found], time_ns) - 1
            return found[max(at, 0)][1]
        if depth == 0:
            return None
        for mid in [c for p, c in self._tf if p == parent and c != child]:
            rest = self._link(mid, child, time_ns, depth - 1)
            if rest is not None:
                first = self._link(parent, mid, time_ns, 0)
                return compose(first, rest) if first is not None else None
        return None

    def path(self, map_frame: str) -> RecordedPath:
        self.map_frame = map_frame
        for found in self._tf.values():
            found.sort(key=lambda item: item[0])
        self._raw.sort(key=lambda item: item[0])
        if not self._raw:
            note = (
                f"{self.path_topic} holds no pose: a path is read from {DRAWABLE}." if not self._kinds else ""
            )
            return RecordedPath(note=note)
        if "tf" in self._kinds:  # several base frames may be published: keep the first one seen per parent
            first = self._raw[0][2]
            self._raw = [r for r in self._raw if r[2] == first]
        frames = {frame for _, _, frame in self._raw}
        poses: list[Pose2D] = []
        unplaced: set[str] = set()
        for time_ns, pose, frame in self._raw:
            if not frame or frame == self.map_frame or not self.map_frame:
                poses.append(pose)
                continue
            link = self._link(self.map_frame, frame, time_ns)
            if link is None:
                unplaced.add(frame)
                poses.append(pose)
                continue
            poses.append(compose(link, pose))
        shown = ", ".join(sorted(frames))
        note = ""
        if unplaced:
            note = (
                f"The path is in {', '.join(repr(f) for f in sorted(unplaced))} and the recording has no "
                f"{self.map_frame} → {sorted(unplaced)[0]} transform on /tf to place it on the map: drawn as "
                "if the frames coincided (a recording with /tf places it)."
            )
        return RecordedPath(poses, shown, note)
