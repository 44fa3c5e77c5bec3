"""The asyncio rosbridge client.

``RosbridgeClient`` keeps one shared WebSocket to the bridge (reconnecting in the background), plus
short-lived lanes for goals and, on bridges that handle a connection in order (Humble), for service
calls. ``Subscription`` is one listener on a topic.
"""

from __future__ import annotations

from rosbridge_mcp_server.client._client import ActionResult, GoalHandle, OrphanedGoal, RosbridgeClient
from rosbridge_mcp_server.client._subscription import Subscription
from rosbridge_mcp_server.wire.dialect import RosInfo

__all__ = ["ActionResult", "GoalHandle", "OrphanedGoal", "RosInfo", "RosbridgeClient", "Subscription"]
