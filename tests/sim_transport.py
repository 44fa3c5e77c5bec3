"""How a test reaches a simulated robot: on a real socket, or in memory where a port adds nothing.

``make_sim`` (``tests/conftest.py``) starts robots without a port when the test's module says so::

    @pytest.fixture
    def sim_in_memory() -> bool:
        \"\"\"This module's robots are reached in memory (no port).\"\"\"
        return True

(or per robot: ``await make_sim(in_memory=True)``). A client for such a robot is made with :func:`client_for`
(or ``RosbridgeClient(robot.url, **transport_options(robot))``); ``make_client`` in ``tests/client`` does it
itself. Which to pick: a test of the client's own socket handling (reconnects, outages, TLS, headers, flow
control, frames that no socket would pass, the handshake) or one that watches the robot on a raw socket keeps
the port; a test of what the client or the domain does with the bridge's answers goes in memory.
"""

from __future__ import annotations

from typing import Any

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.sim import SimulatedRobot

__all__ = ["client_for", "transport_options"]


def transport_options(robot: SimulatedRobot) -> dict[str, Any]:
    """The client option that reaches *robot*: its in-memory dial when it opened no port, else nothing (its
    URL's WebSocket)."""
    return {} if robot.listening else {"transport": robot.dial_in_memory}


def client_for(robot: SimulatedRobot, **options: Any) -> RosbridgeClient:
    """A client of *robot* (not started), reaching it as the robot was started."""
    return RosbridgeClient(robot.url, **{**transport_options(robot), **options})
