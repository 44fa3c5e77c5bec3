"""What an arm act is judged against: the robot description, where the joints are now, and the controllers.

:func:`learn_arm` reads them side by side just before an arm act is approved (``robot/acting.py``), whichever
tool and carrier sends it, so that the guard (``safety/arm.py``) judges every carrier the same. What could not
be read is a problem of the scene, never an exception: the guard decides what that means.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.arm.controllers import Controller, Semantic, list_controllers, parse_srdf
from rosbridge_mcp_server.robot.arm.urdf import Joint, Robot, UrdfError, parse_urdf
from rosbridge_mcp_server.robot.listening import listen

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = [
    "DESCRIPTION_TOPIC",
    "JOINT_STATES_TOPIC",
    "ArmScene",
    "gripper_joint",
    "joint_positions",
    "learn_arm",
    "read_description",
    "read_semantic",
]

DESCRIPTION_TOPIC = "/robot_description"
JOINT_STATES_TOPIC = "/joint_states"


@dataclass(frozen=True)
class ArmScene:
    """The arm as it was read: its description (``None`` when it could not be read), each joint's position now
    (from ``/joint_states``), the controllers (when ``list_controllers`` answered) and what could not be
    read."""

    robot: Robot | None
    positions: Mapping[str, float] = field(default_factory=dict)
    controllers: tuple[Controller, ...] = ()
    problems: tuple[str, ...] = ()


def joint_positions(message: Any) -> dict[str, float]:
    """A ``sensor_msgs/JointState``'s positions by joint name (finite numbers only)."""
    if not isinstance(message, Mapping):
        return {}
    names, positions = message.get("name"), message.get("position")
    if not isinstance(names, list) or not isinstance(positions, list):
        return {}
    out: dict[str, float] = {}
    for name, value in zip(names, positions, strict=False):
        number = value if isinstance(value, int | float) and not isinstance(value, bool) else math.nan
        if isinstance(name, str) and math.isfinite(number):
            out[name] = float(number)
    return out


async def read_description(
    client: RosbridgeClient, graph: RosGraph, timeout: float, topic: str = DESCRIPTION_TOPIC
) -> Robot | str:
    """The robot description latched on *topic*, or why it cannot be read."""
    try:
        msg_type = await graph.topic_type(topic)
        if not msg_type:
            return f"{topic} is not in the robot's graph"
        # Latched (transient local): rosbridge matches the publisher's durability; the last one comes at once.
        heard = await listen(client, topic, msg_type, count=1, duration=None, first_timeout=timeout)
    except RosbridgeError as exc:
        return f"reading {topic} failed: {exc}"
    if not heard.messages:
        return f"nothing arrived on {topic} within {timeout:g} s"
    data = heard.messages[0].message.get("data") if isinstance(heard.messages[0].message, dict) else None
    if not isinstance(data, str):
        return f"{topic} carries no URDF text"
    try:
        return await asyncio.to_thread(parse_urdf, data)
    except UrdfError as exc:
        return f"the robot description on {topic} cannot be read: {exc}"


async def _read_positions(client: RosbridgeClient, graph: RosGraph, timeout: float) -> dict[str, float] | str:
    try:
        msg_type = await graph.topic_type(JOINT_STATES_TOPIC)
        if not msg_type:
            return f"{JOINT_STATES_TOPIC} is not in the robot's graph"
        heard = await listen(
            client, JOINT_STATES_TOPIC, msg_type, count=1, duration=None, first_timeout=timeout
        )
    except RosbridgeError as exc:
        return f"reading {JOINT_STATES_TOPIC} failed: {exc}"
    if not heard.messages:
        return f"nothing arrived on {JOINT_STATES_TOPIC} within {timeout:g} s"
    return joint_positions(heard.messages[0].message)


async def _read_controllers(
    client: RosbridgeClient, graph: RosGraph, timeout: float
) -> tuple[Controller, ...]:
    try:
        if "/controller_manager/list_controllers" not in await graph.service_names():
            return ()
        return await list_controllers(client, timeout=timeout)
    except RosbridgeError:
        return ()


async def learn_arm(client: RosbridgeClient, graph: RosGraph, *, timeout: float) -> ArmScene:
    """The robot description, the joints' positions and the controllers, read side by side."""
    robot, positions, controllers = await asyncio.gather(
        read_description(client, graph, timeout),
        _read_positions(client, graph, timeout),
        _read_controllers(client, graph, timeout),
    )
    problems = [p for p in (robot, positions) if isinstance(p, str)]
    return ArmScene(
        robot=None if isinstance(robot, str) else robot,
        positions={} if isinstance(positions, str) else positions,
        controllers=controllers,
        problems=tuple(problems),
    )


def gripper_joint(robot: Robot, scene: ArmScene, controller: str) -> Joint | None:
    """The joint a gripper controller (``/gripper_controller``) moves: the one it claims, else the one
    movable,
    non-mimic joint whose name says gripper or finger."""
    leaf = controller.rsplit("/", 1)[-1]
    for found in scene.controllers:
        if found.name == leaf and len(found.joints) == 1:
            return robot.joint(found.joints[0])
    candidates = [
        joint
        for joint in robot.movable_joints
        if "gripper" in joint.name.lower() or "finger" in joint.name.lower()
    ]
    return candidates[0] if len(candidates) == 1 else None


SEMANTIC_TOPIC = "/robot_description_semantic"


async def read_semantic(client: RosbridgeClient, graph: RosGraph, timeout: float) -> Semantic | str:
    """The SRDF latched on ``/robot_description_semantic`` (MoveIt's named poses), or why it cannot be
    read."""
    try:
        msg_type = await graph.topic_type(SEMANTIC_TOPIC)
        if not msg_type:
            return f"{SEMANTIC_TOPIC} is not in the robot's graph (no SRDF, so no named poses)"
        heard = await listen(client, SEMANTIC_TOPIC, msg_type, count=1, duration=None, first_timeout=timeout)
    except RosbridgeError as exc:
        return f"reading {SEMANTIC_TOPIC} failed: {exc}"
    message = heard.messages[0].message if heard.messages else None
    data = message.get("data") if isinstance(message, dict) else None
    if not isinstance(data, str):
        return f"nothing readable arrived on {SEMANTIC_TOPIC} within {timeout:g} s"
    try:
        return await asyncio.to_thread(parse_srdf, data)
    except UrdfError as exc:
        return f"the SRDF on {SEMANTIC_TOPIC} cannot be read: {exc}"
