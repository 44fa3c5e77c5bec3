"""The frame tree from ``/tf`` and ``/tf_static``, and look-ups across it.

Each ``geometry_msgs/TransformStamped`` says where ``child_frame_id`` is in ``header.frame_id``; every frame
has at most one parent, so the frames form a tree (a forest until every link has been heard). A look-up of
``target ← source`` walks from both frames up to their nearest common ancestor and composes the links,
inverting those walked downwards, like tf2's ``lookupTransform(target, source)``: the answer maps coordinates
in the source frame to the target frame (equivalently, the pose of the source frame in the target frame).

Frame names are compared without a leading ``/`` (tf2 dropped it; ROS 1 tf publishers may still send one).
Pure: no I/O; times are whatever clock the caller passes in.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import NotOnRobotError
from rosbridge_mcp_server.robot.occupancy import Pose2D, yaw_of
from rosbridge_mcp_server.robot.text import NAME_CHARS, shown

__all__ = ["FrameTree", "Lookup", "Transform", "TransformError", "frame_name"]

_MAX_DEPTH = 1000


class TransformError(NotOnRobotError):
    """A look-up that cannot be answered; ``str()`` says why and lists the frames seen."""


@dataclass(frozen=True)
class Transform:
    """A rigid transform: translation (x, y, z) then rotation as a unit quaternion (x, y, z, w)."""

    translation: tuple[float, float, float]
    rotation: tuple[float, float, float, float]

    @staticmethod
    def identity() -> Transform:
        """No motion."""
        return Transform((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))

    def compose(self, other: Transform) -> Transform:
        """``self ∘ other``: first ``other``, then ``self`` (``a_T_c = a_T_b.compose(b_T_c)``)."""
        moved = _rotate(self.rotation, other.translation)
        translation = (
            self.translation[0] + moved[0],
            self.translation[1] + moved[1],
            self.translation[2] + moved[2],
        )
        return Transform(translation, _normalized(_multiply(self.rotation, other.rotation)))

    def inverse(self) -> Transform:
        """The transform that undoes this one."""
        x, y, z, w = self.rotation
        conjugate = (-x, -y, -z, w)
        back = _rotate(conjugate, self.translation)
        return Transform((-back[0], -back[1], -back[2]), conjugate)

    def rpy_degrees(self) -> tuple[float, float, float]:
        """Roll, pitch, yaw in degrees (fixed axes X, Y, Z — as tf2's ``getRPY``)."""
        x, y, z, w = self.rotation
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        sin_pitch = max(-1.0, min(1.0, 2 * (w * y - z * x)))
        pitch = math.asin(sin_pitch)
        return (math.degrees(roll), math.degrees(pitch), math.degrees(yaw_of(self.rotation)))

    def planar(self) -> Pose2D:
        """Where this transform puts the source frame's origin in the plane: x, y and the yaw (radians)."""
        return Pose2D(self.translation[0], self.translation[1], yaw_of(self.rotation))


@dataclass(frozen=True)
class _Link:
    parent: str
    transform: Transform  # parent_T_child
    static: bool
    received: float  # caller's clock
    stamp: float | None  # header.stamp in seconds, None when zero or absent


@dataclass(frozen=True)
class Lookup:
    """The answer to ``target ← source``: the transform, the frames walked and how fresh the links were."""

    target: str
    source: str
    transform: Transform
    chain: tuple[str, ...]  # from target to source
    newest_received: float | None  # caller's clock; None when every link used is static
    newest_stamp: float | None
    static_only: bool


def frame_name(name: str) -> str:
    """A frame id as tf2 compares it: without a leading slash, trimmed."""
    return name.strip().lstrip("/")


class FrameTree:
    """Links between frames as heard on ``/tf`` and ``/tf_static``; the latest link per child wins."""

    def __init__(self) -> None:
        self._links: dict[str, _Link] = {}

    def add_message(self, msg: Mapping[str, Any], *, static: bool, received: float) -> int:
        """Take a ``tf2_msgs/TFMessage`` (or ROS 1 ``tf/tfMessage``); returns how many links it held."""
        transforms = msg.get("transforms")
        if not isinstance(transforms, list):
            return 0
        count = 0
        for item in transforms:
            if isinstance(item, Mapping) and self.add(item, static=static, received=received):
                count += 1
        return count

    def add(self, stamped: Mapping[str, Any], *, static: bool, received: float) -> bool:
        """Take one ``TransformStamped``; ``False`` (and ignored) when it is malformed."""
        header = stamped.get("header")
        child = stamped.get("child_frame_id")
        body = stamped.get("transform")
        if not isinstance(header, Mapping) or not isinstance(child, str) or not isinstance(body, Mapping):
            return False
        parent = header.get("frame_id")
        if not isinstance(parent, str):
            return False
        # Frame ids are robot text: kept escaped and capped (robot/text.py), as every answer shows them.
        parent, child = frame_name(shown(parent, NAME_CHARS)), frame_name(shown(child, NAME_CHARS))
        if not parent or not child or parent == child:
            return False
        transform = _transform(body)
        if transform is None:
            return False
        existing = self._links.get(child)
        # A static link stays: a dynamic message for the same child would be a misconfigured robot, and tf2
        # keeps the static one too.
        if existing is not None and existing.static and not static:
            return False
        self._links[child] = _Link(parent, transform, static, received, Dialect.seconds(header.get("stamp")))
        return True

    def frames(self) -> list[str]:
        """Every frame heard of, sorted."""
        names = set(self._links)
        names.update(link.parent for link in self._links.values())
        return sorted(names)

    def knows(self, frame: str) -> bool:
        """Whether ``frame`` has been heard of (as a child or a parent)."""
        name = frame_name(frame)
        return name in self._links or any(link.parent == name for link in self._links.values())

    def lookup(self, target: str, source: str) -> Lookup:
        """``target_T_source``, or :class:`TransformError` naming the unknown frame or the missing link."""
        target_name, source_name = frame_name(target), frame_name(source)
        for name, original in ((target_name, target), (source_name, source)):
            if not name:
                raise TransformError(f"The frame name {original!r} is empty. {self._seen()}")
            if not self.knows(name):
                raise TransformError(f"Frame {name!r} has not been seen on /tf or /tf_static. {self._seen()}")
        up_from_target = self._ancestors(target_name)
        up_from_source = self._ancestors(source_name)
        common = next((frame for frame in up_from_source if frame in up_from_target), None)
        if common is None:
            raise TransformError(
                f"Frames {target_name!r} and {source_name!r} are not connected: {target_name!r} goes up to "
                f"{up_from_target[-1]!r} and {source_name!r} up to {up_from_source[-1]!r}, and no transform "
                f"links those trees (yet). {self._seen()}"
            )
        source_side = up_from_source[: up_from_source.index(common) + 1]
        target_side = up_from_target[: up_from_target.index(common) + 1]
        # common_T_source: compose links upwards from the source.
        common_from_source = Transform.identity()
        used: list[_Link] = []
        for frame in source_side[:-1]:
            link = self._links[frame]
            common_from_source = link.transform.compose(common_from_source)
            used.append(link)
        common_from_target = Transform.identity()
        for frame in target_side[:-1]:
            link = self._links[frame]
            common_from_target = link.transform.compose(common_from_target)
            used.append(link)
        result = common_from_target.inverse().compose(common_from_source)
        chain = (*target_side, *reversed(source_side[:-1]))
        moving = [link for link in used if not link.static]
        return Lookup(
            target=target_name,
            source=source_name,
            transform=result,
            chain=tuple(chain),
            newest_received=max((link.received for link in moving), default=None),
            newest_stamp=max((link.stamp for link in moving if link.stamp is not None), default=None),
            static_only=not moving,
        )

    def _ancestors(self, frame: str) -> list[str]:
        """``frame``, its parent, its grandparent, … up to a root (a loop is cut where it closes)."""
        path = [frame]
        seen = {frame}
        current = frame
        while (link := self._links.get(current)) is not None and len(path) < _MAX_DEPTH:
            if link.parent in seen:
                break
            path.append(link.parent)
            seen.add(link.parent)
            current = link.parent
        return path

    def _seen(self) -> str:
        frames = self.frames()
        if not frames:
            return "No transforms were received: is anything publishing /tf or /tf_static?"
        shown = ", ".join(frames[:40]) + (f" … ({len(frames)} in all)" if len(frames) > 40 else "")
        return f"Frames seen: {shown}."


def _transform(body: Mapping[str, Any]) -> Transform | None:
    translation = body.get("translation")
    rotation = body.get("rotation")
    if not isinstance(translation, Mapping) or not isinstance(rotation, Mapping):
        return None
    try:
        t = (float(translation["x"]), float(translation["y"]), float(translation["z"]))
        q = (float(rotation["x"]), float(rotation["y"]), float(rotation["z"]), float(rotation["w"]))
    except (KeyError, TypeError, ValueError):
        return None
    if not all(math.isfinite(v) for v in (*t, *q)):
        return None
    norm = math.sqrt(sum(v * v for v in q))
    if norm < 1e-9:
        return None
    return Transform(t, (q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm))


def _multiply(
    a: tuple[float, float, float, float], b: tuple[float, float, float, float]
) -> tuple[float, float, float, float]:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def _rotate(
    q: tuple[float, float, float, float], v: tuple[float, float, float]
) -> tuple[float, float, float]:
    x, y, z, _ = _multiply(_multiply(q, (v[0], v[1], v[2], 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return (x, y, z)


def _normalized(q: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    norm = math.sqrt(sum(v * v for v in q)) or 1.0
    return (q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm)
