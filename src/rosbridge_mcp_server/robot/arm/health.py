"""What is wrong with an arm, for ``diagnose`` (``robot/diagnosis.py`` turns each :class:`ArmFault` into a
finding): a controller that is not active, a joint at (or past) a limit of its URDF.

A silent ``/joint_states`` is the streams area's (a key stream that sends nothing is a problem there).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from rosbridge_mcp_server.robot.arm.controllers import Controller
from rosbridge_mcp_server.robot.arm.reading import at_limit
from rosbridge_mcp_server.robot.arm.urdf import UrdfError, parse_urdf

__all__ = ["ArmFault", "controller_faults", "limit_faults"]


@dataclass(frozen=True)
class ArmFault:
    """One thing wrong with the arm: a controller or a joint, one sentence, and details."""

    kind: Literal["controller", "limit"]
    subject: str
    summary: str
    details: dict[str, Any] = field(default_factory=dict)


def controller_faults(manager: str, controllers: tuple[Controller, ...]) -> list[ArmFault]:
    """Every controller that is not active: what it would move, and that its commands are refused."""
    faults = []
    for controller in controllers:
        if controller.active:
            continue
        joints = controller.joints
        moves = f"; it moves {', '.join(joints[:8])}{' …' if len(joints) > 8 else ''}" if joints else ""
        faults.append(
            ArmFault(
                "controller",
                controller.name,
                f"Controller {controller.name} ({controller.type}) of {manager} is {controller.state}: "
                f"goals and commands to it are refused or ignored{moves}.",
                {"state": controller.state, "type": controller.type, "joints": list(joints)},
            )
        )
    return faults


def limit_faults(description: Any, joint_state: Any) -> tuple[list[ArmFault], str]:
    """The joints of *joint_state* (a JointState message) at a limit of *description* (the URDF text; a
    gripper's fingers left out), and what was checked (or why not)."""
    if not isinstance(description, str) or not description.strip():
        return [], "no robot description heard: limits not checked"
    try:
        robot = parse_urdf(description)
    except UrdfError as exc:
        return [], f"the robot description cannot be read ({exc}): limits not checked"
    if not isinstance(joint_state, Mapping):
        return [], "no joint state heard: limits not checked"
    names = joint_state.get("name") or []
    values = joint_state.get("position") or []
    positions = {
        n: float(v)
        for n, v in zip(names, values, strict=False)
        if isinstance(n, str) and isinstance(v, int | float) and not isinstance(v, bool)
    }
    faults = []
    for name, side, limit in at_limit(robot, positions):
        joint = robot.joint(name)
        if joint is not None and robot.moves_a_finger(joint):
            continue  # a gripper open or closed is at a limit by design
        unit = "m" if joint is not None and joint.linear else "rad"
        faults.append(
            ArmFault(
                "limit",
                name,
                f"Joint {name} is at its {side} limit ({positions[name]:.4g} {unit}; limit {limit:g} "
                f"{unit}): it cannot move further {'down' if side == 'lower' else 'up'}.",
                {"position": positions[name], "side": side, "limit": limit},
            )
        )
    bounded = sum(1 for j in robot.movable_joints if j.bounded and j.name in positions)
    return faults, f"{bounded} joints against their URDF limits"
