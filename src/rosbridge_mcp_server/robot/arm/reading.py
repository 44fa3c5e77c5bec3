"""Reading an arm off the robot: its description, its joint state now, its controllers and named poses.

Each part is read on its own and may be missing (a robot without ros2_control has no controllers, one
without MoveIt no SRDF): what could not be read is said in :attr:`ArmReading.notes`, never guessed. Only
the description is required (:class:`~rosbridge_mcp_server.errors.NotOnRobotError` without one).

Where the description comes from: the ``/robot_description`` topic (latched / transient local, published by
``robot_state_publisher``), else its ``robot_description`` parameter (ROS 2) or the ``/robot_description``
parameter (ROS 1). The SRDF: ``/robot_description_semantic``, else (ROS 1) the parameter of that name, else
``move_group``'s parameter of that name.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import NotOnRobotError, RosbridgeError
from rosbridge_mcp_server.robot.arm.bounded_xml import plain
from rosbridge_mcp_server.robot.arm.controllers import Controller, Semantic, list_controllers, parse_srdf
from rosbridge_mcp_server.robot.arm.urdf import Robot, UrdfError, parse_urdf
from rosbridge_mcp_server.robot.listening import listen
from rosbridge_mcp_server.robot.nodes import node_names
from rosbridge_mcp_server.robot.parameters import get_parameter

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = [
    "DESCRIPTION_TOPIC",
    "JOINT_STATES",
    "SEMANTIC_TOPIC",
    "ArmReading",
    "JointStateNow",
    "at_limit",
    "read_arm",
    "read_joint_states",
]

DESCRIPTION_TOPIC = "/robot_description"
SEMANTIC_TOPIC = "/robot_description_semantic"
JOINT_STATES = "/joint_states"
#: How close to a limit a joint counts as at it: 0.5° for angles, 1 mm for lengths.
AT_LIMIT_ANGLE = math.radians(0.5)
AT_LIMIT_LENGTH = 0.001
#: The most joints read from one JointState (a whole humanoid has ~60).
MAX_STATE_JOINTS = 256


@dataclass(frozen=True)
class JointStateNow:
    """One ``sensor_msgs/JointState`` as heard: each named joint's position, velocity and effort."""

    positions: Mapping[str, float]
    velocities: Mapping[str, float]
    efforts: Mapping[str, float]
    waited: float  #: seconds from asking until it came


@dataclass(frozen=True)
class ArmReading:
    """What :func:`read_arm` found."""

    robot: Robot
    description_source: str
    joint_state: JointStateNow | None = None
    controllers: tuple[Controller, ...] | None = None
    controller_manager: str | None = None
    semantic: Semantic | None = None
    semantic_source: str | None = None
    notes: tuple[str, ...] = field(default=())


def at_limit(robot: Robot, positions: Mapping[str, float]) -> list[tuple[str, str, float]]:
    """The joints at (or beyond) a limit: (joint, ``lower``/``upper``, the limit)."""
    found: list[tuple[str, str, float]] = []
    for joint in robot.movable_joints:
        value = positions.get(joint.name)
        lower, upper = joint.limits.lower, joint.limits.upper
        if value is None or not joint.bounded or lower is None or upper is None:
            continue
        slack = AT_LIMIT_LENGTH if joint.linear else AT_LIMIT_ANGLE
        if value <= lower + slack:
            found.append((joint.name, "lower", lower))
        elif value >= upper - slack:
            found.append((joint.name, "upper", upper))
    return found


async def read_arm(client: RosbridgeClient, graph: RosGraph, *, timeout: float) -> ArmReading:
    """The arm's description (required), joint state, controllers and named poses, each within *timeout*."""
    topics = {entry.name: entry.type for entry in await graph.topics()}
    notes: list[str] = []
    text, source = await _description(client, graph, topics, timeout)
    try:
        robot = parse_urdf(text)
    except UrdfError as exc:
        raise NotOnRobotError(f"The robot description ({source}) cannot be read: {exc}.") from None
    state = await read_joint_states(client, topics, timeout=timeout)
    if state is None:
        notes.append(
            f"no {JOINT_STATES} within {timeout:g} s"
            if JOINT_STATES in topics
            else f"{JOINT_STATES} is not in the graph: positions unknown"
        )
    manager, controllers = await _controllers(client, graph, notes)
    semantic, semantic_source = await _semantic(client, graph, topics, timeout, notes)
    return ArmReading(robot, source, state, controllers, manager, semantic, semantic_source, tuple(notes))


async def _one_message(client: RosbridgeClient, topic: str, msg_type: str, timeout: float) -> Any:
    # No qos sent: a ROS 2 rosbridge subscribes transient-local by itself when every publisher is (as
    # robot_state_publisher's /robot_description is), and older bridges take no qos at all.
    heard = await listen(client, topic, msg_type, count=1, duration=None, first_timeout=timeout)
    return heard.messages[0].message if heard.messages else None


async def _description(
    client: RosbridgeClient, graph: RosGraph, topics: Mapping[str, str], timeout: float
) -> tuple[str, str]:
    if DESCRIPTION_TOPIC in topics:
        message = await _one_message(client, DESCRIPTION_TOPIC, topics[DESCRIPTION_TOPIC], timeout)
        text = message.get("data") if isinstance(message, dict) else None
        if isinstance(text, str) and text.strip():
            return text, f"topic {DESCRIPTION_TOPIC}"
    version = (await graph.ros_info()).version
    name = "/robot_state_publisher:robot_description" if version == 2 else DESCRIPTION_TOPIC
    try:
        _, value = await get_parameter(graph, client, name)
    except RosbridgeError:
        value = None
    if isinstance(value, str) and value.strip():
        return value, f"parameter {name}"
    raise NotOnRobotError(
        f"No robot description: {DESCRIPTION_TOPIC} is not published (or sent nothing within {timeout:g} s) "
        f"and the parameter {name} is not set. Is robot_state_publisher running?"
    )


async def read_joint_states(
    client: RosbridgeClient, topics: Mapping[str, str], *, timeout: float
) -> JointStateNow | None:
    """The next ``/joint_states`` message; ``None`` when none comes within *timeout* or none is published."""
    if JOINT_STATES not in topics:
        return None
    start = time.monotonic()
    message = await _one_message(client, JOINT_STATES, topics[JOINT_STATES], timeout)
    if not isinstance(message, dict):
        return None
    names = [n if isinstance(n, str) and plain(n) else "" for n in message.get("name") or []][
        :MAX_STATE_JOINTS
    ]
    return JointStateNow(
        _by_name(names, message.get("position")),
        _by_name(names, message.get("velocity")),
        _by_name(names, message.get("effort")),
        time.monotonic() - start,
    )


def _by_name(names: list[str], values: Any) -> dict[str, float]:
    if not isinstance(values, list):
        return {}
    return {
        name: float(value)
        for name, value in zip(names, values, strict=False)
        if name and isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
    }


async def _controllers(
    client: RosbridgeClient, graph: RosGraph, notes: list[str]
) -> tuple[str | None, tuple[Controller, ...] | None]:
    services = [s for s in await graph.service_names() if s.endswith("/list_controllers")]
    if not services:
        notes.append("no controller_manager (no …/list_controllers service): controllers unknown")
        return None, None
    usual = "/controller_manager/list_controllers"
    service = usual if usual in services else services[0]
    manager = service.removesuffix("/list_controllers")
    try:
        return manager, await list_controllers(client, manager)
    except RosbridgeError as exc:
        notes.append(f"{service} failed: {str(exc)[:200]}")
        return manager, None


async def _semantic(
    client: RosbridgeClient, graph: RosGraph, topics: Mapping[str, str], timeout: float, notes: list[str]
) -> tuple[Semantic | None, str | None]:
    text: Any = None
    source: str | None = None
    if SEMANTIC_TOPIC in topics:
        message = await _one_message(client, SEMANTIC_TOPIC, topics[SEMANTIC_TOPIC], timeout)
        text, source = (message.get("data") if isinstance(message, dict) else None), f"topic {SEMANTIC_TOPIC}"
    elif (await graph.ros_info()).version == 1:
        # MoveIt on ROS 1 keeps the SRDF in the global parameter of that name.
        try:
            _, text = await get_parameter(graph, client, SEMANTIC_TOPIC)
            source = f"parameter {SEMANTIC_TOPIC}"
        except RosbridgeError:
            text = None
    elif "/move_group" in await node_names(graph):
        try:
            _, text = await get_parameter(graph, client, "/move_group:robot_description_semantic")
            source = "parameter /move_group:robot_description_semantic"
        except RosbridgeError:
            text = None
    if not isinstance(text, str) or not text.strip():
        return None, None
    try:
        return parse_srdf(text), source
    except UrdfError as exc:
        notes.append(f"the SRDF ({source}) cannot be read: {exc}")
        return None, None
