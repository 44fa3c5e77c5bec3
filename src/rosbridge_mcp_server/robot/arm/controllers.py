"""The arm's controllers (ros2_control's ``controller_manager``) and its named poses (MoveIt's SRDF).

``list_controllers`` answers ``controller_manager_msgs/srv/ListControllers``: each controller's name, type,
state (``active``, ``inactive``, ``unconfigured``, ``finalized``) and the command interfaces it claims
(``<joint>/position``, ``<joint>/velocity``…), which name the joints it moves. Its reply is robot text: the
number of controllers and of interfaces is bounded, and names are kept only when they are short strings.

An SRDF (``/robot_description_semantic``, or ``move_group``'s parameter of that name) gives planning groups
and named poses (``<group_state name="home" group="arm"><joint name=... value=.../>``); it is read as
boundedly as the URDF (``urdf.read_xml``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.robot.arm.bounded_xml import plain
from rosbridge_mcp_server.robot.arm.urdf import MAX_NAME, UrdfError, read_xml

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient

__all__ = [
    "CONTROLLER_MANAGER",
    "Controller",
    "NamedPose",
    "Semantic",
    "list_controllers",
    "parse_controllers",
    "parse_srdf",
]

#: Where ros2_control's controller manager serves its services, unless the robot namespaces it.
CONTROLLER_MANAGER = "/controller_manager"
#: The most controllers and interfaces per controller kept from one reply.
MAX_CONTROLLERS = 64
MAX_INTERFACES = 256
#: The most named poses and groups kept from an SRDF.
MAX_POSES = 64


@dataclass(frozen=True)
class Controller:
    """One controller as ``list_controllers`` describes it."""

    name: str
    type: str
    state: str
    claimed_interfaces: tuple[str, ...]  #: ``<joint>/<interface>``, claimed now (an active controller's)
    required_interfaces: tuple[str, ...]  #: the command interfaces it needs when active

    @property
    def active(self) -> bool:
        return self.state == "active"

    @property
    def joints(self) -> tuple[str, ...]:
        """The joints it moves (claims, or would claim when active), in order."""
        interfaces = self.claimed_interfaces or self.required_interfaces
        return tuple(
            dict.fromkeys(interface.rpartition("/")[0] for interface in interfaces if "/" in interface)
        )


def _text(value: Any, limit: int = MAX_NAME) -> str | None:
    """*value* when it is a short name that shows as what it is (no control or direction characters)."""
    return value if isinstance(value, str) and value and len(value) <= limit and plain(value) else None


def _texts(value: Any) -> tuple[str, ...]:
    if not isinstance(value, list):
        return ()
    return tuple(text for item in value[:MAX_INTERFACES] if (text := _text(item)) is not None)


#: ros_control's (ROS 1) controller states, as ros2_control says them.
ROS1_STATES = {"running": "active", "stopped": "inactive", "initialized": "inactive"}
#: ros_control's hardware interfaces (``hardware_interface::PositionJointInterface``) → the interface.
_ROS1_INTERFACES = {"Position": "position", "Velocity": "velocity", "Effort": "effort"}


def _ros1_interfaces(item: Mapping[str, Any]) -> tuple[str, ...]:
    """ROS 1's ``claimed_resources`` (a hardware interface and its joints) as ``<joint>/<interface>``."""
    resources = item.get("claimed_resources")
    out: list[str] = []
    for entry in resources[:MAX_INTERFACES] if isinstance(resources, list) else ():
        if not isinstance(entry, dict):
            continue
        kind = str(entry.get("hardware_interface", "")).rpartition("::")[2]
        interface = next((v for k, v in _ROS1_INTERFACES.items() if kind.startswith(k)), "command")
        out += [f"{joint}/{interface}" for joint in _texts(entry.get("resources"))]
    return tuple(out[:MAX_INTERFACES])


def parse_controllers(reply: Any) -> tuple[Controller, ...]:
    """The controllers of a ``ListControllers`` reply (``{"controller": [...]}``); what is not a controller
    (no name, wrong kinds) is left out. ROS 1's form (``running``/``stopped``, ``claimed_resources``) is read
    into ROS 2's words."""
    items = reply.get("controller") if isinstance(reply, dict) else None
    if not isinstance(items, list):
        return ()
    controllers: list[Controller] = []
    for item in items[:MAX_CONTROLLERS]:
        if not isinstance(item, dict) or (name := _text(item.get("name"))) is None:
            continue
        state = _text(item.get("state"), 40) or "?"
        if "claimed_resources" in item:  # ROS 1: what it claims when running
            resources = _ros1_interfaces(item)
            state = ROS1_STATES.get(state, state)
            claimed, required = (resources if state == "active" else ()), resources
        else:
            claimed = _texts(item.get("claimed_interfaces"))
            required = _texts(item.get("required_command_interfaces"))
        controllers.append(
            Controller(
                name=name,
                type=_text(item.get("type")) or "?",
                state=state,
                claimed_interfaces=claimed,
                required_interfaces=required,
            )
        )
    return tuple(controllers)


async def list_controllers(
    client: RosbridgeClient, manager: str = CONTROLLER_MANAGER, *, timeout: float | None = None
) -> tuple[Controller, ...]:
    """The controllers *manager* runs (a read: ``list_controllers`` changes nothing)."""
    reply = await client.call_service(f"{manager.rstrip('/')}/list_controllers", {}, timeout=timeout)
    return parse_controllers(reply)


# --- the SRDF -----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class NamedPose:
    """A ``<group_state>``: a named pose of a planning group, joint positions in radians / metres."""

    name: str
    group: str
    positions: Mapping[str, float]


@dataclass(frozen=True)
class Semantic:
    """What an SRDF says that we use: the planning groups (their joints or chain) and the named poses."""

    groups: Mapping[str, tuple[str, ...]]  #: group → its joints (or ``base→tip`` for a chain group)
    poses: tuple[NamedPose, ...]
    end_effectors: Mapping[str, str]  #: end effector name → its parent link

    def pose(self, name: str, group: str | None = None) -> NamedPose | None:
        """The named pose *name* (of *group* when given)."""
        return next((p for p in self.poses if p.name == name and group in (None, p.group)), None)


_SRDF_TAGS = frozenset({"group", "group_state", "end_effector", "joint", "chain"})


def parse_srdf(text: str | bytes) -> Semantic:
    """The groups, named poses and end effectors of an SRDF, read safely (:class:`UrdfError` otherwise)."""
    data = text.encode("utf-8", "surrogatepass") if isinstance(text, str) else text
    root = read_xml(data, "semantic description (SRDF)", _SRDF_TAGS)
    groups: dict[str, tuple[str, ...]] = {}
    poses: list[NamedPose] = []
    end_effectors: dict[str, str] = {}
    for element in root.children:
        name = _text(element.attrs.get("name"))
        if name is None:
            continue
        if element.tag == "group" and len(groups) < MAX_POSES:
            groups[name] = _group_members(element.children)
        elif element.tag == "group_state" and len(poses) < MAX_POSES:
            poses.append(
                NamedPose(name, element.attrs.get("group", "")[:MAX_NAME], _pose_joints(name, element))
            )
        elif element.tag == "end_effector" and (parent := _text(element.attrs.get("parent_link"))):
            end_effectors[name] = parent
    return Semantic(groups, tuple(poses), end_effectors)


def _group_members(children: list[Any]) -> tuple[str, ...]:
    members: list[str] = []
    for child in children[:MAX_INTERFACES]:
        if child.tag == "joint" and (name := _text(child.attrs.get("name"))):
            members.append(name)
        elif child.tag == "chain" and (base := _text(child.attrs.get("base_link"))):
            members.append(f"{base}→{_text(child.attrs.get('tip_link')) or '?'}")
    return tuple(members)


def _pose_joints(pose: str, element: Any) -> dict[str, float]:
    positions: dict[str, float] = {}
    for child in element.children[:MAX_INTERFACES]:
        joint = _text(child.attrs.get("name")) if child.tag == "joint" else None
        if joint is None:
            continue
        try:
            value = float(child.attrs.get("value", "").split()[0])
        except (ValueError, IndexError):
            raise UrdfError(f"named pose {pose!r}: joint {joint!r} has no numeric value") from None
        if not math.isfinite(value):
            raise UrdfError(f"named pose {pose!r}: joint {joint!r} is not a finite number")
        positions[joint] = value
    return positions
