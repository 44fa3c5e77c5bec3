"""A robot description (URDF) read safely: the joints, the links and the tree they make.

The URDF comes from the robot, so it is hostile text: it is bounded in size (``MAX_URDF_BYTES``), read
by expat (``bounded_xml.py``) with every DTD refused (so no entity can expand: no "billion laughs", no
external file), its elements counted and nested no deeper than ``MAX_DEPTH``, its joints and links counted,
every number finite, and its joints held to make one tree (one root, one parent per link, no cycle).
Whatever is wrong is said in one sentence (:class:`UrdfError`). Only what kinematics and limits need is
kept: links by name, and each joint's type, parent and child, origin, axis, limits and mimic. Geometry,
inertia and ``<transmission>`` are skipped.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Literal

from rosbridge_mcp_server.robot.arm.bounded_xml import (
    MAX_DEPTH,
    MAX_ELEMENTS,
    MAX_URDF_BYTES,
    UrdfError,
    XmlElement,
    plain,
    read_xml,
)
from rosbridge_mcp_server.robot.arm.geometry import GEOMETRY_TAGS, link_radius

__all__ = [
    "JOINT_TYPES",
    "MAX_DEPTH",
    "MAX_ELEMENTS",
    "MAX_JOINTS",
    "MAX_URDF_BYTES",
    "Joint",
    "JointType",
    "Limits",
    "Mimic",
    "Origin",
    "Robot",
    "UrdfError",
    "XmlElement",
    "parse_urdf",
    "read_xml",
]

#: The most joints (and links, less one) a description may have.
MAX_JOINTS = 256
#: The longest name kept (a link or joint name).
MAX_NAME = 200

JointType = Literal["revolute", "continuous", "prismatic", "fixed", "floating", "planar"]
JOINT_TYPES: tuple[JointType, ...] = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")

Vector = tuple[float, float, float]


@dataclass(frozen=True)
class Origin:
    """A joint's frame in its parent link's: ``xyz`` in metres, ``rpy`` in radians (fixed axes)."""

    xyz: Vector = (0.0, 0.0, 0.0)
    rpy: Vector = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Limits:
    """A ``<limit>``: positions (rad or m), speed (rad/s or m/s), effort (N·m or N); ``None``: absent."""

    lower: float | None = None
    upper: float | None = None
    velocity: float | None = None
    effort: float | None = None


@dataclass(frozen=True)
class Mimic:
    """This joint follows ``joint``: position = ``multiplier`` × that joint's + ``offset``."""

    joint: str
    multiplier: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class Joint:
    """One ``<joint>``: what a kinematic chain and a limit check need of it."""

    name: str
    type: JointType
    parent: str
    child: str
    origin: Origin = Origin()
    axis: Vector = (1.0, 0.0, 0.0)  #: unit length (URDF's default axis is x)
    limits: Limits = Limits()
    mimic: Mimic | None = None

    @property
    def movable(self) -> bool:
        """Whether it has one position of its own (revolute, continuous, prismatic; a mimic joint follows)."""
        return self.type in ("revolute", "continuous", "prismatic")

    @property
    def linear(self) -> bool:
        """Whether its position is a length (prismatic, metres) rather than an angle (radians)."""
        return self.type == "prismatic"

    @property
    def bounded(self) -> bool:
        """Whether its position has limits (continuous joints turn freely)."""
        return self.type in ("revolute", "prismatic")


@dataclass(frozen=True)
class Robot:
    """A robot description: its links, its joints (in the file's order) and the tree they make."""

    name: str
    links: tuple[str, ...]
    joints: tuple[Joint, ...]
    root: str
    _by_name: Mapping[str, Joint] = field(repr=False, compare=False, default_factory=dict)
    _parent_joint: Mapping[str, Joint] = field(repr=False, compare=False, default_factory=dict)
    _children: Mapping[str, tuple[Joint, ...]] = field(repr=False, compare=False, default_factory=dict)
    #: Each link's capsule radius (m) where its URDF geometry gives one (``robot/arm/geometry.py``).
    radii: Mapping[str, float] = field(repr=False, compare=False, default_factory=dict)

    def joint(self, name: str) -> Joint | None:
        """The joint called *name*, or ``None``."""
        return self._by_name.get(name)

    def parent_joint(self, link: str) -> Joint | None:
        """The joint whose child is *link* (``None`` for the root or an unknown link)."""
        return self._parent_joint.get(link)

    def child_joints(self, link: str) -> tuple[Joint, ...]:
        """The joints whose parent is *link*."""
        return self._children.get(link, ())

    @property
    def movable_joints(self) -> tuple[Joint, ...]:
        """The joints with a position of their own, mimic joints left out, in the file's order."""
        return tuple(joint for joint in self.joints if joint.movable and joint.mimic is None)

    def chain(self, base: str, tip: str) -> tuple[Joint, ...]:
        """The joints from link *base* down to link *tip*, in order; :class:`UrdfError` when *tip* is not
        below *base* (or either is not a link)."""
        for link in (base, tip):
            if link not in self._children and link not in self._parent_joint and link != self.root:
                raise UrdfError(f"no link {link!r} in the robot description")
        joints: list[Joint] = []
        link = tip
        while link != base:
            joint = self._parent_joint.get(link)
            if joint is None:
                raise UrdfError(f"link {tip!r} is not below link {base!r} in the robot description")
            joints.append(joint)
            link = joint.parent
        return tuple(reversed(joints))

    def end_effectors(self) -> tuple[str, ...]:
        """The links at the end of an arm, below two or more movable joints (a wheel, below one, is not):
        ``tool0`` (or a ``*_tcp``/``*_ee_link``… link) where there is one, else the leaf links, a finger (a
        ``*finger*``/``*jaw*`` link, or one moved by a prismatic joint) counted as its parent link."""
        named = [link for link in self.links if _tool_like(link) and self._moved(link)]
        if named:
            return tuple(named)
        leaves = [link for link in self.links if not self._children.get(link)]
        tips = dict.fromkeys(self._above_fingers(leaf) for leaf in leaves)
        return tuple(tip for tip in tips if self._moved(tip))

    def moves_a_finger(self, joint: Joint) -> bool:
        """Whether *joint* moves a gripper's finger (a leaf link moved by a prismatic joint, or a
        ``*finger*``/``*jaw*`` leaf): open and closed are its limits, so being at one is normal."""
        leaf = not self._children.get(joint.child)
        return leaf and (joint.linear or _finger_like(joint.child))

    def _moved(self, link: str) -> bool:
        """Whether two or more joints with positions of their own lie above *link*."""
        return sum(1 for joint in self._above(link) if joint.movable and joint.mimic is None) >= 2

    def _above(self, link: str) -> Iterator[Joint]:
        joint = self._parent_joint.get(link)
        while joint is not None:
            yield joint
            joint = self._parent_joint.get(joint.parent)

    def _above_fingers(self, leaf: str) -> str:
        joint = self._parent_joint.get(leaf)
        if joint is not None and (joint.linear or _finger_like(leaf)):
            return joint.parent
        return leaf


def _tool_like(link: str) -> bool:
    lowered = link.lower()
    return lowered in ("tool0", "tcp", "ee_link", "end_effector", "flange") or lowered.endswith(
        ("_tcp", "_tool0", "_ee_link", "_end_effector")
    )


def _finger_like(link: str) -> bool:
    lowered = link.lower()
    return "finger" in lowered or "jaw" in lowered


_URDF_TAGS = (
    frozenset({"link", "joint", "parent", "child", "origin", "axis", "limit", "mimic"}) | GEOMETRY_TAGS
)


# --- from elements to joints --------------------------------------------------------------------------------


def parse_urdf(text: str | bytes) -> Robot:
    """The robot description in *text*, read safely; :class:`UrdfError` saying what is wrong otherwise."""
    data = text.encode("utf-8", "surrogatepass") if isinstance(text, str) else text
    root = read_xml(data, "robot description", _URDF_TAGS, levels=4)
    link_elements = [element for element in root.children if element.tag == "link"]
    links = [_name(element, "link") for element in link_elements]
    joint_elements = [element for element in root.children if element.tag == "joint"]
    if len(joint_elements) > MAX_JOINTS or len(links) > MAX_JOINTS + 1:
        raise UrdfError(
            f"the robot description has {len(joint_elements)} joints and {len(links)} links; "
            f"at most {MAX_JOINTS} joints are read"
        )
    if not links:
        raise UrdfError("the robot description has no <link>")
    _unique(links, "link")
    joints = tuple(_joint(element) for element in joint_elements)
    _unique([joint.name for joint in joints], "joint")
    radii = {
        name: radius
        for name, element in zip(links, link_elements, strict=True)
        if (radius := link_radius(element)) is not None
    }
    return _tree(_name(root, "robot", required=False) or "robot", tuple(links), joints, radii)


def _name(element: XmlElement, what: str, *, required: bool = True) -> str:
    name = element.attrs.get("name", "")
    if not name and required:
        raise UrdfError(f"a <{what}> has no name")
    if len(name) > MAX_NAME or not plain(name):
        raise UrdfError(
            f"a <{what}> name is longer than {MAX_NAME} characters or holds control or direction characters"
        )
    return name


def _unique(names: list[str], what: str) -> None:
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise UrdfError(f"two {what}s are called {name!r}")
        seen.add(name)


def _joint(element: XmlElement) -> Joint:
    name = _name(element, "joint")
    kind = element.attrs.get("type", "")
    if kind not in JOINT_TYPES:
        raise UrdfError(
            f"joint {name!r} has type {kind[:40]!r}; a URDF joint is one of {', '.join(JOINT_TYPES)}"
        )
    ends = []
    for end in ("parent", "child"):
        tag = element.first(end)
        if tag is None or not tag.attrs.get("link"):
            raise UrdfError(f"joint {name!r} has no <{end} link=...>")
        ends.append(tag.attrs["link"])
    origin = element.first("origin")
    axis = element.first("axis")
    return Joint(
        name=name,
        type=kind,  # checked against JOINT_TYPES above
        parent=ends[0],
        child=ends[1],
        origin=Origin(
            _vector(origin, "xyz", name) if origin is not None else (0.0, 0.0, 0.0),
            _vector(origin, "rpy", name) if origin is not None else (0.0, 0.0, 0.0),
        ),
        axis=_axis(axis, name),
        limits=_limits(element.first("limit"), name, kind),
        mimic=_mimic(element.first("mimic"), name),
    )


def _number(text: str, what: str, joint: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise UrdfError(f"joint {joint!r}: {what} {text[:40]!r} is not a number") from None
    if not math.isfinite(value):
        raise UrdfError(f"joint {joint!r}: {what} is {text[:40]!r}, not a finite number")
    return value


def _vector(element: XmlElement, attr: str, joint: str) -> Vector:
    text = element.attrs.get(attr)
    if text is None:
        return (0.0, 0.0, 0.0)
    parts = text.split()
    if len(parts) != 3:
        raise UrdfError(f"joint {joint!r}: {attr} {text[:60]!r} is not three numbers")
    x, y, z = (_number(part, attr, joint) for part in parts)
    return (x, y, z)


def _axis(element: XmlElement | None, joint: str) -> Vector:
    if element is None:
        return (1.0, 0.0, 0.0)
    x, y, z = _vector(element, "xyz", joint)
    length = math.sqrt(x * x + y * y + z * z)
    if length < 1e-9:
        raise UrdfError(f"joint {joint!r}: its axis has zero length")
    return (x / length, y / length, z / length)


def _limits(element: XmlElement | None, joint: str, kind: str) -> Limits:
    if element is None:
        if kind in ("revolute", "prismatic"):
            raise UrdfError(f"joint {joint!r} is {kind} but has no <limit>")
        return Limits()
    values = {
        key: _number(element.attrs[key], f"limit {key}", joint) if key in element.attrs else None
        for key in ("lower", "upper", "velocity", "effort")
    }
    if kind in ("revolute", "prismatic"):  # URDF: lower and upper default to 0
        values["lower"] = values["lower"] if values["lower"] is not None else 0.0
        values["upper"] = values["upper"] if values["upper"] is not None else 0.0
    lower, upper = values["lower"], values["upper"]
    if lower is not None and upper is not None and lower > upper:
        raise UrdfError(f"joint {joint!r}: limit lower {lower} is above upper {upper}")
    for key in ("velocity", "effort"):
        if (values[key] or 0.0) < 0:
            raise UrdfError(f"joint {joint!r}: limit {key} {values[key]} is negative")
    return Limits(lower, upper, values["velocity"], values["effort"])


def _mimic(element: XmlElement | None, joint: str) -> Mimic | None:
    if element is None:
        return None
    target = element.attrs.get("joint", "")
    if not target:
        raise UrdfError(f"joint {joint!r}: <mimic> names no joint")
    multiplier = _number(element.attrs.get("multiplier", "1"), "mimic multiplier", joint)
    offset = _number(element.attrs.get("offset", "0"), "mimic offset", joint)
    return Mimic(target, multiplier, offset)


def _tree(name: str, links: tuple[str, ...], joints: tuple[Joint, ...], radii: Mapping[str, float]) -> Robot:
    known = set(links)
    parent_joint: dict[str, Joint] = {}
    children: dict[str, list[Joint]] = {}
    by_name = {joint.name: joint for joint in joints}
    for joint in joints:
        for end in (joint.parent, joint.child):
            if end not in known:
                raise UrdfError(
                    f"joint {joint.name!r} names link {end[:MAX_NAME]!r}, which is not in the description"
                )
        if joint.child in parent_joint:
            raise UrdfError(
                f"link {joint.child!r} is the child of two joints ({parent_joint[joint.child].name!r} and "
                f"{joint.name!r}); a URDF is a tree"
            )
        parent_joint[joint.child] = joint
        children.setdefault(joint.parent, []).append(joint)
        if joint.mimic is not None:
            _check_mimic(joint, by_name)
    roots = [link for link in links if link not in parent_joint]
    if len(roots) != 1:
        raise UrdfError(
            "the robot description's joints form a cycle (no link without a parent)"
            if not roots
            else f"the robot description has {len(roots)} root links ({', '.join(roots[:5])}); a URDF has one"
        )
    _reach_all(roots[0], links, children)
    return Robot(
        name,
        links,
        joints,
        roots[0],
        by_name,
        parent_joint,
        {link: tuple(js) for link, js in children.items()},
        dict(radii),
    )


def _check_mimic(joint: Joint, by_name: Mapping[str, Joint]) -> None:
    assert joint.mimic is not None
    target = by_name.get(joint.mimic.joint)
    if target is None or target is joint:
        raise UrdfError(
            f"joint {joint.name!r} mimics {joint.mimic.joint[:MAX_NAME]!r}, which is not another joint"
        )
    if target.mimic is not None:
        raise UrdfError(
            f"joint {joint.name!r} mimics {target.name!r}, which mimics a joint itself; not followed"
        )
    if not joint.movable or not target.movable:
        raise UrdfError(
            f"joint {joint.name!r} mimics {target.name!r}; both must be revolute, continuous or prismatic"
        )


def _reach_all(root: str, links: tuple[str, ...], children: Mapping[str, list[Joint]]) -> None:
    """Every link is reached from the root (a link left out sits on a cycle of its own)."""
    reached = {root}
    todo = [root]
    while todo:
        for joint in children.get(todo.pop(), ()):
            if joint.child not in reached:
                reached.add(joint.child)
                todo.append(joint.child)
    missing = [link for link in links if link not in reached]
    if missing:
        raise UrdfError(
            f"links {', '.join(missing[:5])} sit on a cycle of joints, not below the root {root!r}"
        )
