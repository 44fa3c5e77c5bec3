"""The arm world (``world="arm"``, ROS 2): the turtle world with a 6-joint arm and a gripper on it.

* :mod:`.model`: the arm's joints, its URDF and SRDF, a joint's transform;
* :mod:`.motion`: trajectories checked and followed;
* :mod:`.controllers`: ``/controller_manager``'s controllers and services;
* :mod:`.world`: :class:`ArmWorld`, what it publishes and its action servers.
"""

from rosbridge_mcp_server.sim.nodes.arm.model import ARM_JOINTS, FINGER, HOME, NAMED_POSES
from rosbridge_mcp_server.sim.nodes.arm.world import ARM_FAULTS, ARM_NODES, ArmWorld

__all__ = ["ARM_FAULTS", "ARM_JOINTS", "ARM_NODES", "FINGER", "HOME", "NAMED_POSES", "ArmWorld"]
