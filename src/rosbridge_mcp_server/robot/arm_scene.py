"""What an arm act is judged against: the robot description, where the joints are now, the controllers and the
named poses.

:func:`learn_arm` reads them (``robot/arm/reading.py``'s :func:`read_arm`, as ``view_arm`` sees the arm: the
``/robot_description`` topic, else ``robot_state_publisher``'s parameter) just before an arm act is approved
(``robot/acting/``), whichever tool and carrier sends it, so that the guard (``safety/arm.py``) judges every
carrier the same. What could not be read is a problem of the scene, never an exception: the guard decides
what that means.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.arm.controllers import Controller, Semantic
from rosbridge_mcp_server.robot.arm.reading import JOINT_STATES, read_arm, read_joint_states
from rosbridge_mcp_server.robot.arm.urdf import Joint, Robot

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["ArmScene", "gripper_joint", "learn_arm", "positions_now"]


@dataclass(frozen=True)
class ArmScene:
    """The arm as it was read: its description (``None`` when it could not be read), each joint's position now
    (from ``/joint_states``), the controllers (when ``list_controllers`` answered), the SRDF (when there is
    one) and what could not be read."""

    robot: Robot | None
    positions: Mapping[str, float] = field(default_factory=dict)
    controllers: tuple[Controller, ...] = ()
    problems: tuple[str, ...] = ()
    semantic: Semantic | None = None


async def learn_arm(client: RosbridgeClient, graph: RosGraph, *, timeout: float) -> ArmScene:
    """The robot description, the joints' positions, the controllers and the SRDF."""
    try:
        reading = await read_arm(client, graph, timeout=timeout)
    except RosbridgeError as exc:  # no description (NotOnRobotError), or the bridge failed
        return ArmScene(None, problems=(str(exc).rstrip("."),))
    positions = dict(reading.joint_state.positions) if reading.joint_state is not None else {}
    return ArmScene(
        reading.robot,
        positions,
        reading.controllers or (),
        tuple(reading.notes),
        reading.semantic,
    )


async def positions_now(client: RosbridgeClient, graph: RosGraph, timeout: float) -> dict[str, float]:
    """The joints' positions from the next ``/joint_states`` (empty when none comes)."""
    topics = {entry.name: entry.type for entry in await graph.topics()}
    if JOINT_STATES not in topics:
        return {}
    state = await read_joint_states(client, topics, timeout=timeout)
    return dict(state.positions) if state is not None else {}


def gripper_joint(robot: Robot, scene: ArmScene, controller: str) -> Joint | None:
    """The joint a gripper controller (``/gripper_controller``) moves: the one it claims, else the one
    movable, non-mimic joint whose name says gripper or finger."""
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
