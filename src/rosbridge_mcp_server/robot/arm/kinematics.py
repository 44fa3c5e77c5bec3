"""Forward kinematics of a robot description, in pure Python (``math`` only).

A pose is a :data:`Transform`: a rigid transform as the 12 numbers of a 3×4 matrix, row by row (rotation
and translation; the last row of the 4×4, ``0 0 0 1``, is implied). :class:`Chain` is the joints from one
link down to another, with each joint's fixed origin turned into a transform once; :meth:`Chain.poses` then
costs one compose and one joint motion per joint (a motion about a coordinate axis mixes two columns only).

Why no library (pin, ikpy, kinpy, yourdfpy were measured): docs/architecture.md, "The arm"; in short,
~14 µs a 7-joint pose here, 100 poses in ~1.4 ms, and no 190-440 MB of numpy/scipy/C++ wheels to install.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from rosbridge_mcp_server.robot.arm.urdf import Joint, Origin, Robot, UrdfError

__all__ = [
    "IDENTITY",
    "Chain",
    "MissingJointsError",
    "Transform",
    "compose",
    "from_origin",
    "from_quaternion",
    "inverse",
    "joint_values",
    "link_poses",
    "quaternion",
    "rpy",
    "transform_point",
    "translation",
]

#: A rigid transform: the 3×4 matrix ``[R | t]`` row by row (``r00 r01 r02 tx … r20 r21 r22 tz``).
Transform = tuple[float, float, float, float, float, float, float, float, float, float, float, float]
Vector = tuple[float, float, float]

IDENTITY: Transform = (1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0)


class MissingJointsError(UrdfError):
    """A pose asked for without the position of every joint it depends on; ``missing`` names them."""

    def __init__(self, missing: tuple[str, ...]) -> None:
        self.missing = missing
        shown = ", ".join(missing[:8]) + (f" and {len(missing) - 8} more" if len(missing) > 8 else "")
        super().__init__(f"no position for joint(s) {shown}")


def compose(a: Transform, b: Transform) -> Transform:
    """``a ∘ b``: *b* expressed in *a*'s parent frame."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11 = a
    b0, b1, b2, b3, b4, b5, b6, b7, b8, b9, b10, b11 = b
    return (
        a0 * b0 + a1 * b4 + a2 * b8,
        a0 * b1 + a1 * b5 + a2 * b9,
        a0 * b2 + a1 * b6 + a2 * b10,
        a0 * b3 + a1 * b7 + a2 * b11 + a3,
        a4 * b0 + a5 * b4 + a6 * b8,
        a4 * b1 + a5 * b5 + a6 * b9,
        a4 * b2 + a5 * b6 + a6 * b10,
        a4 * b3 + a5 * b7 + a6 * b11 + a7,
        a8 * b0 + a9 * b4 + a10 * b8,
        a8 * b1 + a9 * b5 + a10 * b9,
        a8 * b2 + a9 * b6 + a10 * b10,
        a8 * b3 + a9 * b7 + a10 * b11 + a11,
    )


def inverse(t: Transform) -> Transform:
    """The inverse of a rigid transform (``Rᵀ``, ``-Rᵀ t``)."""
    r0, r1, r2, x, r4, r5, r6, y, r8, r9, r10, z = t
    return (
        r0, r4, r8, -(r0 * x + r4 * y + r8 * z),
        r1, r5, r9, -(r1 * x + r5 * y + r9 * z),
        r2, r6, r10, -(r2 * x + r6 * y + r10 * z),
    )  # fmt: skip


def from_origin(origin: Origin) -> Transform:
    """A URDF ``<origin>`` as a transform: ``R = Rz(yaw) Ry(pitch) Rx(roll)``, then ``xyz``."""
    roll, pitch, yaw = origin.rpy
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    x, y, z = origin.xyz
    return (
        cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr, x,
        sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr, y,
        -sp, cp * sr, cp * cr, z,
    )  # fmt: skip


def from_quaternion(xyz: Vector, q: tuple[float, float, float, float]) -> Transform:
    """A transform from a translation and a unit quaternion ``(x, y, z, w)`` (normalised here)."""
    x, y, z, w = q
    n = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
    x, y, z, w = x / n, y / n, z / n, w / n
    return (
        1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w), xyz[0],
        2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w), xyz[1],
        2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y), xyz[2],
    )  # fmt: skip


def translation(t: Transform) -> Vector:
    """Where the frame's origin is, in metres."""
    return (t[3], t[7], t[11])


def transform_point(t: Transform, point: Vector) -> Vector:
    """*point* (in the frame *t* describes) in *t*'s parent frame."""
    x, y, z = point
    return (
        t[0] * x + t[1] * y + t[2] * z + t[3],
        t[4] * x + t[5] * y + t[6] * z + t[7],
        t[8] * x + t[9] * y + t[10] * z + t[11],
    )


def rpy(t: Transform) -> Vector:
    """The rotation as URDF's roll, pitch, yaw (radians)."""
    pitch = math.atan2(-t[8], math.hypot(t[0], t[4]))
    if abs(math.cos(pitch)) < 1e-9:  # gimbal lock: put everything in yaw
        return (0.0, pitch, math.atan2(-t[1], t[5]))
    return (math.atan2(t[9], t[10]), pitch, math.atan2(t[4], t[0]))


def quaternion(t: Transform) -> tuple[float, float, float, float]:
    """The rotation as a unit quaternion ``(x, y, z, w)`` (ROS's order)."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = t[0], t[1], t[2], t[4], t[5], t[6], t[8], t[9], t[10]
    trace = r00 + r11 + r22
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        return ((r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s, 0.25 * s)
    if r00 > r11 and r00 > r22:
        s = 2.0 * math.sqrt(1.0 + r00 - r11 - r22)
        return (0.25 * s, (r01 + r10) / s, (r02 + r20) / s, (r21 - r12) / s)
    if r11 > r22:
        s = 2.0 * math.sqrt(1.0 + r11 - r00 - r22)
        return ((r01 + r10) / s, 0.25 * s, (r12 + r21) / s, (r02 - r20) / s)
    s = 2.0 * math.sqrt(1.0 + r22 - r00 - r11)
    return ((r02 + r20) / s, (r12 + r21) / s, 0.25 * s, (r10 - r01) / s)


# --- joint motion -----------------------------------------------------------------------------------------


def _rotate(t: Transform, axis: Vector, angle: float) -> Transform:
    """``t ∘ R(axis, angle)``; about a coordinate axis only two columns change."""
    c, s = math.cos(angle), math.sin(angle)
    if axis in ((0.0, 0.0, 1.0), (0.0, 0.0, -1.0)):
        s = s if axis[2] > 0 else -s
        return (
            t[0] * c + t[1] * s, t[1] * c - t[0] * s, t[2], t[3],
            t[4] * c + t[5] * s, t[5] * c - t[4] * s, t[6], t[7],
            t[8] * c + t[9] * s, t[9] * c - t[8] * s, t[10], t[11],
        )  # fmt: skip
    if axis in ((0.0, 1.0, 0.0), (0.0, -1.0, 0.0)):
        s = s if axis[1] > 0 else -s
        return (
            t[0] * c - t[2] * s, t[1], t[2] * c + t[0] * s, t[3],
            t[4] * c - t[6] * s, t[5], t[6] * c + t[4] * s, t[7],
            t[8] * c - t[10] * s, t[9], t[10] * c + t[8] * s, t[11],
        )  # fmt: skip
    if axis in ((1.0, 0.0, 0.0), (-1.0, 0.0, 0.0)):
        s = s if axis[0] > 0 else -s
        return (
            t[0], t[1] * c + t[2] * s, t[2] * c - t[1] * s, t[3],
            t[4], t[5] * c + t[6] * s, t[6] * c - t[5] * s, t[7],
            t[8], t[9] * c + t[10] * s, t[10] * c - t[9] * s, t[11],
        )  # fmt: skip
    x, y, z = axis  # Rodrigues
    v = 1.0 - c
    rotation: Transform = (
        c + x * x * v, x * y * v - z * s, x * z * v + y * s, 0.0,
        y * x * v + z * s, c + y * y * v, y * z * v - x * s, 0.0,
        z * x * v - y * s, z * y * v + x * s, c + z * z * v, 0.0,
    )  # fmt: skip
    return compose(t, rotation)


def _slide(t: Transform, axis: Vector, distance: float) -> Transform:
    """``t ∘ translate(axis × distance)``."""
    x, y, z = axis[0] * distance, axis[1] * distance, axis[2] * distance
    return (
        t[0], t[1], t[2], t[0] * x + t[1] * y + t[2] * z + t[3],
        t[4], t[5], t[6], t[4] * x + t[5] * y + t[6] * z + t[7],
        t[8], t[9], t[10], t[8] * x + t[9] * y + t[10] * z + t[11],
    )  # fmt: skip


def _move(t: Transform, joint: Joint, position: float) -> Transform:
    if joint.type in ("revolute", "continuous"):
        return _rotate(t, joint.axis, position)
    if joint.type == "prismatic":
        return _slide(t, joint.axis, position)
    return t  # fixed; floating and planar joints are held at their origin (they have no single position)


def joint_values(robot: Robot, positions: Mapping[str, float], joints: tuple[Joint, ...]) -> list[float]:
    """The position of each of *joints* (mimic joints from the joint they follow; 0 for joints without one);
    :class:`MissingJointsError` naming every movable joint *positions* lacks."""
    values: list[float] = []
    missing: list[str] = []
    for joint in joints:
        if not joint.movable:
            values.append(0.0)
            continue
        source = joint.mimic.joint if joint.mimic is not None else joint.name
        value = positions.get(source)
        if value is None:
            missing.append(source)
            values.append(0.0)
            continue
        values.append(
            value * joint.mimic.multiplier + joint.mimic.offset if joint.mimic is not None else value
        )
    if missing:
        raise MissingJointsError(tuple(dict.fromkeys(missing)))
    return values


# --- chains -----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Step:
    """One joint of a chain, with what its pose needs worked out once."""

    joint: Joint
    origin: Transform
    shift: Vector | None  #: the origin's translation when it does not rotate (the common case: cheaper)
    source: str | None  #: whose position moves it (a mimic joint's leader), ``None`` for a fixed joint
    multiplier: float
    offset: float

    def pose(self, parent: Transform, positions: Mapping[str, float]) -> Transform:
        """The child link's pose, given its parent link's (*positions* holds ``source``)."""
        placed = compose(parent, self.origin) if self.shift is None else _slide(parent, self.shift, 1.0)
        if self.source is None:
            return placed
        return _move(placed, self.joint, positions[self.source] * self.multiplier + self.offset)


def _step(joint: Joint) -> _Step:
    mimic = joint.mimic
    return _Step(
        joint,
        from_origin(joint.origin),
        joint.origin.xyz if joint.origin.rpy == (0.0, 0.0, 0.0) else None,
        (mimic.joint if mimic is not None else joint.name) if joint.movable else None,
        mimic.multiplier if mimic is not None else 1.0,
        mimic.offset if mimic is not None else 0.0,
    )


class Chain:
    """The joints from link ``base`` down to link ``tip``, ready for forward kinematics."""

    def __init__(self, robot: Robot, base: str, tip: str) -> None:
        self.robot = robot
        self.base = base
        self.tip = tip
        self.joints = robot.chain(base, tip)
        self._steps = tuple(_step(joint) for joint in self.joints)
        #: The joints whose positions the chain needs (mimic joints' leaders), in chain order.
        self.variables: tuple[str, ...] = tuple(
            dict.fromkeys(
                (joint.mimic.joint if joint.mimic is not None else joint.name)
                for joint in self.joints
                if joint.movable
            )
        )

    def poses(self, positions: Mapping[str, float]) -> list[tuple[str, Transform]]:
        """Each link of the chain below ``base`` (in order) with its pose in ``base``'s frame."""
        self._require(positions)
        pose = IDENTITY
        out: list[tuple[str, Transform]] = []
        for step in self._steps:
            pose = step.pose(pose, positions)
            out.append((step.joint.child, pose))
        return out

    def tip_pose(self, positions: Mapping[str, float]) -> Transform:
        """Where ``tip`` is in ``base``'s frame."""
        self._require(positions)
        pose = IDENTITY
        for step in self._steps:
            pose = step.pose(pose, positions)
        return pose

    def _require(self, positions: Mapping[str, float]) -> None:
        missing = tuple(name for name in self.variables if name not in positions)
        if missing:
            raise MissingJointsError(missing)


def link_poses(
    robot: Robot, positions: Mapping[str, float], *, missing_as_zero: bool = False
) -> dict[str, Transform]:
    """Every link's pose in the root link's frame. Joints without a position: :class:`MissingJointsError`, or
    held at 0 with ``missing_as_zero``."""
    if not missing_as_zero:
        joint_values(robot, positions, robot.joints)  # raises naming what is missing
    poses: dict[str, Transform] = {robot.root: IDENTITY}
    todo = [robot.root]
    while todo:
        link = todo.pop()
        for joint in robot.child_joints(link):
            (value,) = joint_values(robot, _with_zeros(robot, positions, joint), (joint,))
            poses[joint.child] = _move(compose(poses[link], from_origin(joint.origin)), joint, value)
            todo.append(joint.child)
    return poses


def _with_zeros(robot: Robot, positions: Mapping[str, float], joint: Joint) -> Mapping[str, float]:
    source = joint.mimic.joint if joint.mimic is not None else joint.name
    if not joint.movable or source in positions:
        return positions
    return {source: 0.0}
