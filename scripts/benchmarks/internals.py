"""The only module of the benchmark that imports rosbridge_mcp_server's internals, and why each is needed.

Every other figure goes through the package's public ways in (the console script, the simulated robot's
``python -m`` entry, MCP over stdio or HTTP, the rosbridge protocol on a raw WebSocket). These figures measure
a part on its own, so they need the part itself:

* :class:`RosbridgeClient`: rows 2a (our client's ``call_service`` against the raw floor), 4· (100 calls
  at once through our client) and 5a (1,000 messages of the 1 kHz topic through our client's
  ``subscribe``). They hold the client to the floor, below any tool, which no public entry shows on its own.
* :func:`infrastructure_types`: the floor of row 8b, a fresh raw client asking the types of the services our
  server asks about on a connection's first ``list_services``: which ones it can tell from their names is the
  server's own knowledge.

* :class:`Chain`, :func:`parse_urdf` and the arm's answer (:func:`arm_answer_text`): row 19a (forward
  kinematics and joint limits along a 100-point path, the kinematics part of a joint goal's check, p50 ≤ 5 ms)
  and 19c (``view_arm``'s text for a 7-joint arm with a gripper, which the simulated arm (6 joints) cannot
  show through the public way in).
* the arm judge (:func:`arm_refusal`, the :class:`Act` and :class:`ArmScene` it reads, the policy it reads
  ``[arm]`` from, and the simulated arm's robot description): row 19d, one joint goal's check along its path,
  which no tool shows on its own (a refusal or a send buries it in the bridge's round trips).

When one of these moves, this is the one file to change.
"""

from __future__ import annotations

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.robot.approval import Act
from rosbridge_mcp_server.robot.arm.controllers import parse_controllers
from rosbridge_mcp_server.robot.arm.kinematics import Chain
from rosbridge_mcp_server.robot.arm.reading import ArmReading, JointStateNow
from rosbridge_mcp_server.robot.arm.urdf import parse_urdf
from rosbridge_mcp_server.robot.arm_scene import ArmScene
from rosbridge_mcp_server.robot.known_types import infrastructure_types
from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.safety.arm import arm_refusal
from rosbridge_mcp_server.sim.nodes.arm.model import HOME, arm_urdf
from rosbridge_mcp_server.tools.view_arm import build_answer, render

__all__ = [
    "Act",
    "ArmScene",
    "Chain",
    "RosbridgeClient",
    "arm_answer_text",
    "arm_refusal",
    "arm_urdf",
    "infrastructure_types",
    "parse_policy",
    "parse_urdf",
    "sim_arm_home",
]


def sim_arm_home() -> dict[str, float]:
    """The simulated arm's joints at home (radians, metres)."""
    return dict(HOME)


def arm_answer_text(urdf: str, controllers: dict[str, object]) -> str:
    """``view_arm``'s text for *urdf* with every joint at 0.3, moving, and *controllers* (a list_controllers
    reply)."""
    robot = parse_urdf(urdf)
    names = [joint.name for joint in robot.movable_joints]
    state = JointStateNow(
        dict.fromkeys(names, 0.3), dict.fromkeys(names, 0.1), dict.fromkeys(names, 1.5), 0.01
    )
    reading = ArmReading(
        robot, "topic /robot_description", state, parse_controllers(controllers), "/controller_manager"
    )
    return render(build_answer(reading, None, None))
