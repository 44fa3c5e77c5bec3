"""Nav2's lifecycle nodes: each node's state, the services that read and change it (``change_state``,
``get_state``, ...) with a ``transition_event`` on every change, and the lifecycle managers' ``manage_nodes``
and ``is_active`` (ROS 2 only)."""

from __future__ import annotations

import time
from typing import Any

from rosbridge_mcp_server.sim.nodes.kit import NodeKit, ServiceFn
from rosbridge_mcp_server.sim.nodes.nav2.robot import Nav2Robot

__all__ = ["Lifecycles"]

_LIFECYCLE_SERVICES = (
    ("change_state", "lifecycle_msgs/srv/ChangeState"),
    ("get_state", "lifecycle_msgs/srv/GetState"),
    ("get_available_states", "lifecycle_msgs/srv/GetAvailableStates"),
    ("get_available_transitions", "lifecycle_msgs/srv/GetAvailableTransitions"),
    ("get_transition_graph", "lifecycle_msgs/srv/GetAvailableTransitions"),
)
_STATE_LABELS = {1: "unconfigured", 2: "inactive", 3: "active", 4: "finalized"}
#: lifecycle transition id -> (from state, to state)
_TRANSITIONS = {1: (1, 2), 2: (2, 1), 3: (2, 3), 4: (3, 2), 5: (1, 4), 6: (2, 4), 7: (3, 4)}
_TRANSITION_LABELS = {
    1: "configure",
    2: "cleanup",
    3: "activate",
    4: "deactivate",
    5: "shutdown",
    6: "shutdown",
    7: "shutdown",
}


class Lifecycles:
    """The lifecycle nodes of every robot of one world, on its kit's bridge."""

    def __init__(self, kit: NodeKit) -> None:
        self.kit = kit

    def manage(self, robot: Nav2Robot, managed: list[str]) -> Any:
        """A manager's ``manage_nodes``: every node it manages to the state its command asks for."""

        async def manage(request: dict[str, Any]) -> dict[str, Any]:
            command = int(request.get("command", 0))
            target = {0: 3, 1: 2, 2: 3, 3: 1, 4: 4, 5: 2, 6: 1}.get(command, 3)
            for node in managed:
                self.set_state(robot, node, target)
            return {"success": True}

        return manage

    def is_active(self, robot: Nav2Robot, managed: list[str]) -> Any:
        """A manager's ``is_active``: whether every node it manages is active."""

        async def is_active(request: dict[str, Any]) -> dict[str, Any]:
            active = all(robot.states.get(node) == 3 for node in managed)
            return {"success": active, "message": ""}

        return is_active

    def set_state(self, robot: Nav2Robot, node: str, state: int) -> None:
        """Put *node* of *robot* in *state*, with a ``transition_event`` when that is a change."""
        before = robot.states.get(node, 1)
        robot.states[node] = state
        topic = f"{robot.namespace}/{node}/transition_event"
        if before != state:
            self.kit.publish(
                topic,
                {
                    "timestamp": time.time_ns(),
                    "start_state": {"id": before, "label": _STATE_LABELS.get(before, "")},
                    "goal_state": {"id": state, "label": _STATE_LABELS.get(state, "")},
                },
            )
        self.kit.world.notify()

    def handlers(self, robot: Nav2Robot, name: str) -> list[tuple[str, str, ServiceFn]]:
        """(service leaf, type, handler) of each lifecycle service of node *name* of *robot*."""

        async def change_state(request: dict[str, Any]) -> dict[str, Any]:
            transition = int(request.get("transition", {}).get("id", 0))
            move = _TRANSITIONS.get(transition)
            if move is None or robot.states.get(name) != move[0]:
                return {"success": False}
            self.set_state(robot, name, move[1])
            return {"success": True}

        async def get_state(request: dict[str, Any]) -> dict[str, Any]:
            state = robot.states.get(name, 1)
            return {"current_state": {"id": state, "label": _STATE_LABELS.get(state, "unknown")}}

        async def available_states(request: dict[str, Any]) -> dict[str, Any]:
            return {"available_states": [{"id": i, "label": label} for i, label in _STATE_LABELS.items()]}

        async def available_transitions(request: dict[str, Any]) -> dict[str, Any]:
            state = robot.states.get(name, 1)
            return {
                "available_transitions": [
                    {
                        "transition": {"id": tid, "label": _TRANSITION_LABELS[tid]},
                        "start_state": {"id": start, "label": _STATE_LABELS[start]},
                        "goal_state": {"id": goal, "label": _STATE_LABELS[goal]},
                    }
                    for tid, (start, goal) in _TRANSITIONS.items()
                    if start == state
                ]
            }

        handlers = {
            "change_state": change_state,
            "get_state": get_state,
            "get_available_states": available_states,
            "get_available_transitions": available_transitions,
            "get_transition_graph": available_transitions,
        }
        return [(leaf, srv, handlers[leaf]) for leaf, srv in _LIFECYCLE_SERVICES]
