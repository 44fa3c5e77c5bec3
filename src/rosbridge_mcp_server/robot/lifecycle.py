"""ROS 2 lifecycle nodes: a node's state as its ``<node>/get_state`` service tells it
(``lifecycle_msgs/srv/GetState``), read into plain data. ROS 1 has no lifecycle nodes. No MCP."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from rosbridge_mcp_server.errors import RosbridgeError

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["ACTIVE", "LifecycleState", "get_state_service", "inactive_reason", "node_state", "read_state"]

#: ``lifecycle_msgs/msg/State.PRIMARY_STATE_ACTIVE``.
ACTIVE = 3


@dataclass(frozen=True)
class LifecycleState:
    """A node's lifecycle state as ``get_state`` answered: its id and label (robot text: each ``None`` when
    the answer did not hold it)."""

    id: object
    label: object

    @property
    def active(self) -> bool:
        return self.id == ACTIVE

    @property
    def told(self) -> bool:
        """Whether the answer named a state id at all."""
        return self.id is not None


def read_state(answer: object) -> LifecycleState | None:
    """A ``GetState`` answer's ``current_state``, or ``None`` when it holds none."""
    state = answer.get("current_state") if isinstance(answer, dict) else None
    if not isinstance(state, dict):
        return None
    return LifecycleState(state.get("id"), state.get("label"))


def get_state_service(node: str) -> str:
    """The service that tells *node*'s lifecycle state."""
    return f"{node}/get_state"


async def node_state(client: RosbridgeClient, node: str, *, timeout: float) -> LifecycleState | None:
    """*node*'s lifecycle state (``None``: the answer held none); :class:`RosbridgeError` when the call
    failed."""
    return read_state(await client.call_service(get_state_service(node), {}, timeout=timeout))


async def inactive_reason(
    client: RosbridgeClient, graph: RosGraph, node: str, *, timeout: float = 3.0
) -> str | None:
    """Why *node* is not active (its lifecycle state in words), or ``None``: active, not a lifecycle node,
    or not told (no ``get_state`` in the graph, no answer, no state in it)."""
    try:
        names = await graph.service_names()
    except RosbridgeError:
        return None
    if get_state_service(node) not in names:
        return None
    try:
        state = await node_state(client, node, timeout=timeout)
    except RosbridgeError:
        return None
    if state is None or not state.told or state.active:
        return None
    return f"{node} is {state.label or state.id}, not active"
