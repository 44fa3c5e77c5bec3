"""What an act needs (:class:`Acting`, :class:`Timeouts`) and what every checked send shares: the caller's
name kept for the audit (:func:`given_name`), a message checked as the bridge will read it (:func:`as_read`),
and the scene a motion goal is judged against (:func:`motion_scene`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

from rosbridge_mcp_server.robot.approval import Approving
from rosbridge_mcp_server.robot.arm_goals import carried_arm
from rosbridge_mcp_server.robot.motion_goals import carried_goal, read_motion
from rosbridge_mcp_server.robot.navigation import Scene, survey

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import Dialect, RosbridgeClient
    from rosbridge_mcp_server.robot.activity import SessionActivity
    from rosbridge_mcp_server.robot.arm_scene import ArmScene
    from rosbridge_mcp_server.robot.gate import SendGate
    from rosbridge_mcp_server.robot.goals import GoalRegistry
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["SCENE_TIMEOUT", "Acting", "Timeouts", "as_read", "given_name", "motion_scene"]


class Timeouts(Protocol):
    """The one setting an act reads (the server's ``Config`` is one)."""

    @property
    def request_timeout(self) -> float: ...


class Acting(Approving, Protocol):
    """What an act needs: what the seam reads to approve it (the guard, who to ask, the caller), the robot
    session's parts and the call's own (a tool's ``ToolContext`` is one)."""

    @property
    def client(self) -> RosbridgeClient: ...
    @property
    def config(self) -> Timeouts: ...
    @property
    def graph(self) -> RosGraph: ...
    @property
    def activity(self) -> SessionActivity: ...
    @property
    def goals(self) -> GoalRegistry: ...
    @property
    def gate(self) -> SendGate: ...


def given_name(written: str, canonical: str) -> str | None:
    """The name as the caller wrote it, for the audit, when it is not the canonical one."""
    return written if written != canonical else None


def as_read(dialect: Dialect, message: dict[str, Any]) -> Any:
    """*message* as the bridge will read it (ROS 1 time fields respelled), for checking only: the client
    respells what it sends itself, so the message that goes on stays as the caller wrote it."""
    return dialect.outgoing(message)


#: How long a motion goal not sent by navigate_to waits for the map and /tf before it is judged.
SCENE_TIMEOUT = 3.0


async def motion_scene(
    ctx: Acting, kind: str, name: str, type_name: str, payload: Any
) -> Scene | ArmScene | None:
    """The map (``<namespace>/map``) and the robot (``base_link``) a motion goal the act carries is judged
    against, whichever carrier (``robot/motion_goals.py``); for an arm's trajectory or gripper goal
    (``robot/arm_goals.py``) the arm's description and joint positions; ``None`` when it carries none, or one
    the fence cannot read or place (the guard says why)."""
    from rosbridge_mcp_server.robot.arm_scene import learn_arm  # noqa: PLC0415 - arm acts only

    arm = carried_arm(kind, name, type_name, payload)
    if arm is not None:
        if arm.kind == "switch" or isinstance(arm.body, str):
            return None
        return await learn_arm(ctx.client, ctx.graph, timeout=min(SCENE_TIMEOUT, ctx.config.request_timeout))
    carried = carried_goal(kind, name, type_name, payload)
    if carried is None:
        return None
    motion = read_motion(carried)
    if isinstance(motion, str) or motion.unplaceable is not None:
        return None
    return await survey(
        ctx.client,
        ctx.graph,
        map_topic=f"{carried.namespace}/map",
        base_frame="base_link",
        namespace=carried.namespace,
        poses=motion.poses,
        along=motion.along,
        timeout=min(SCENE_TIMEOUT, ctx.config.request_timeout),
    )
