"""The arm's ``/controller_manager``: ``list_controllers`` and ``switch_controller`` as ros2_control answers
them (the ROS 2 lab's arm, "The arm" in its NOTES.md), and on ROS 1 as ros_control's does (states
``running`` / ``stopped``, ``claimed_resources`` per hardware interface, ``start_controllers`` /
``stop_controllers``).

``switch_controller`` really (de)activates: STRICT (2) is all or nothing (an unknown name, or one already
in that state: ``ok`` false, nothing switched); BEST_EFFORT (1; also 0 AUTO, 3 FORCE_AUTO) switches what it
can and says ``ok`` false only when nothing named could be. Deactivating ``arm_controller`` aborts its
running goal and holds the arm; the ``arm-controller-inactive`` fault keeps it from activating
(a hardware fault on the arm).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Set
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.sim.nodes.arm.model import ARM_JOINTS, FINGER

if TYPE_CHECKING:
    from rosbridge_mcp_server.sim.nodes.kit import NodeKit

__all__ = ["ControllerManager"]

log = logging.getLogger("rosbridge_mcp_server.sim")

MANAGER = "/controller_manager"
#: ros_control's (ROS 1) types of the same controllers.
ROS1_TYPES = {
    "joint_trajectory_controller/JointTrajectoryController": "position_controllers/JointTrajectoryController",
    "position_controllers/GripperActionController": "position_controllers/GripperActionController",
    "joint_state_broadcaster/JointStateBroadcaster": "joint_state_controller/JointStateController",
}
STRICT = 2


@dataclass
class _Controller:
    name: str
    type: str
    command: tuple[str, ...]  #: the command interfaces it claims when active
    state: tuple[str, ...]  #: the state interfaces it reads
    active: bool = True


class ControllerManager:
    """The three controllers of the arm and the manager's services."""

    def __init__(self, kit: NodeKit, faults: Set[str], deactivated: Callable[[str], None]) -> None:
        """*faults*: the arm's (read as they are now); *deactivated*: told the name of a controller switched
        off, so the arm stops what that controller ran."""
        self.kit = kit
        self.faults = faults
        self.deactivated = deactivated
        positions = tuple(f"{j}/position" for j in (*ARM_JOINTS, FINGER))
        self.controllers = {
            c.name: c
            for c in (
                _Controller(
                    "arm_controller",
                    "joint_trajectory_controller/JointTrajectoryController",
                    tuple(f"{j}/position" for j in ARM_JOINTS),
                    tuple(f"{j}/{kind}" for j in ARM_JOINTS for kind in ("position", "velocity")),
                ),
                _Controller(
                    "gripper_controller",
                    "position_controllers/GripperActionController",
                    (f"{FINGER}/position",),
                    (f"{FINGER}/position", f"{FINGER}/velocity"),
                ),
                _Controller(
                    "joint_state_broadcaster", "joint_state_broadcaster/JointStateBroadcaster", (), positions
                ),
            )
        }
        if "arm-controller-inactive" in faults:
            self.controllers["arm_controller"].active = False

    def build(self) -> None:
        kit = self.kit
        kit.graph.node(MANAGER)
        kit.service(MANAGER, f"{MANAGER}/list_controllers", self._type("ListControllers"), self._list)
        kit.service(MANAGER, f"{MANAGER}/switch_controller", self._type("SwitchController"), self._switch)

    def _type(self, leaf: str) -> str | None:
        return self.kit.type(f"controller_manager_msgs/srv/{leaf}", f"controller_manager_msgs/{leaf}", "srv")

    def is_active(self, name: str) -> bool:
        controller = self.controllers.get(name)
        return controller is not None and controller.active

    async def _list(self, request: dict[str, Any]) -> dict[str, Any]:
        if not self.kit.ros2:
            return {"controller": [self._ros1_state(c) for c in self.controllers.values()]}
        return {
            "controller": [
                {
                    "name": c.name,
                    "state": "active" if c.active else "inactive",
                    "type": c.type,
                    "is_async": False,
                    "update_rate": 50,
                    "is_chainable": False,
                    "is_chained": False,
                    "claimed_interfaces": list(c.command) if c.active else [],
                    "required_command_interfaces": list(c.command),
                    "required_state_interfaces": list(c.state),
                }
                for c in self.controllers.values()
            ]
        }

    @staticmethod
    def _ros1_state(c: _Controller) -> dict[str, Any]:
        joints = [interface.rsplit("/", 1)[0] for interface in c.command]
        resources = [
            {"hardware_interface": "hardware_interface::PositionJointInterface", "resources": joints}
        ]
        return {
            "name": c.name,
            "state": "running" if c.active else "stopped",
            "type": ROS1_TYPES.get(c.type, c.type),
            "claimed_resources": resources if joints else [],
        }

    def _switchable(self, name: str, activate: bool) -> bool:
        controller = self.controllers.get(name)
        if controller is None or controller.active == activate:
            return False
        return not (activate and name == "arm_controller" and "arm-controller-inactive" in self.faults)

    async def _switch(self, request: dict[str, Any]) -> dict[str, Any]:
        stop, start = ("deactivate", "activate") if self.kit.ros2 else ("stop", "start")
        wanted = [(str(n), False) for n in request.get(f"{stop}_controllers") or []]
        wanted += [(str(n), True) for n in request.get(f"{start}_controllers") or []]
        possible = [(name, activate) for name, activate in wanted if self._switchable(name, activate)]
        if not wanted or (request.get("strictness") == STRICT and len(possible) != len(wanted)):
            log.warning("/controller_manager: switch refused (strict): %s", wanted)
            return {"ok": False}
        if not possible:
            return {"ok": False}
        for name, activate in possible:
            self.controllers[name].active = activate
            if not activate:
                self.deactivated(name)
        self.kit.world.notify()
        return {"ok": True}
