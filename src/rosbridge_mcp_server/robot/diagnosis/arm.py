"""The ``arm`` area, where ros2_control's ``…/list_controllers`` is served: a controller not active is a
problem, a joint at a limit of the URDF (``/robot_description``, fingers left out) a warning
(``robot/arm/health.py`` words both); a silent ``/joint_states`` is the streams area's."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Final, TypeAlias

from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.diagnosis.findings import Finding, Look, Step

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.arm.controllers import Controller
    from rosbridge_mcp_server.robot.diagnosis.streams import Heard
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["ARM_TOPICS", "Controllers", "arm_findings", "read_controllers"]

#: What the arm area listens to: the URDF (latched) and the joint state.
ARM_TOPICS: Final = ("/robot_description", "/joint_states")
#: (the controller manager, its controllers or why they could not be read), or ``None`` without one.
#: A string: the arm's modules are imported only where a robot has an arm area to look at.
Controllers: TypeAlias = "tuple[str, tuple[Controller, ...] | str] | None"


async def read_controllers(client: RosbridgeClient, graph: RosGraph, window: float) -> Controllers:
    """(the manager, its controllers or why they could not be read); ``None`` without a controller manager."""
    services = [s for s in await graph.service_names() if s.endswith("/list_controllers")]
    if not services:
        return None
    manager = min(services, key=lambda s: (s != "/controller_manager/list_controllers", s))
    manager = manager.removesuffix("/list_controllers")
    from rosbridge_mcp_server.robot.arm.controllers import list_controllers  # noqa: PLC0415 - arm robots only

    try:
        return manager, await list_controllers(client, manager, timeout=window + 1.0)
    except RosbridgeError as exc:
        return manager, f"list_controllers failed ({str(exc)[:120]})"


def arm_findings(
    arm: Controllers,
    heard: Mapping[str, Heard],
    checked: dict[str, str],
    unavailable: dict[str, str],
    *,
    asked: bool,
) -> list[Finding]:
    description, states = (
        heard[t].messages[-1] if t in heard and heard[t].messages else None for t in ARM_TOPICS
    )
    if arm is None and states is None:
        if asked:
            unavailable["arm"] = "no controller manager (…/list_controllers) and no /joint_states"
        return []
    from rosbridge_mcp_server.robot.arm.health import controller_faults, limit_faults  # noqa: PLC0415 - arm robots only

    out: list[Finding] = []
    parts = []
    if arm is not None:
        manager, controllers = arm
        if isinstance(controllers, str):
            parts.append(controllers)
        else:
            active = sum(1 for c in controllers if c.active)
            parts.append(f"{active} of {len(controllers)} controllers active")
            for fault in controller_faults(manager, controllers):
                steps = (Step(Look.ACTIVATE_CONTROLLER, (manager, fault.subject)), Step(Look.ARM))
                out.append(
                    Finding("problem", "arm", fault.subject, fault.summary, steps, (manager,), fault.details)
                )
    limits, what = limit_faults(description.get("data") if isinstance(description, dict) else None, states)
    parts.append(what)
    out += [Finding("warning", "arm", f.subject, f.summary, (Step(Look.ARM),), (), f.details) for f in limits]
    checked["arm"] = "; ".join(parts)
    return out
