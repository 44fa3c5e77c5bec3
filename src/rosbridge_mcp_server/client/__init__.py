"""The asyncio rosbridge client.

``RosbridgeClient`` keeps one shared WebSocket to the bridge (reconnecting in the background), plus
short-lived lanes for goals and, on bridges that handle a connection in order (Humble), for service
calls. By job: ``client.py`` (lifecycle, the connect loop, the current ``Session``), ``reconnect.py``
(when to try: backoff, attempts prompted by calls), ``session.py`` (one connection and what was learnt on
it, opened whole), ``detect.py`` (ROS version detection), ``capabilities.py`` (what the bridge can do,
named: the one place that tells bridges apart), ``dialect.py`` (the bridge's spelling of
types and time fields, one ``Dialect`` per session), ``services.py``
(service calls), ``topics.py`` and ``subscription.py`` (advertisements, subscriptions), ``lanes.py`` and
``goal_lane.py`` (extra connections), ``connection.py`` (one WebSocket and its reader), ``frames.py``
(what one frame may hold: size, text, nesting).
"""

from __future__ import annotations

from rosbridge_mcp_server.client.capabilities import BridgeCapabilities
from rosbridge_mcp_server.client.client import GoalCancel, RosbridgeClient, SessionWatcher
from rosbridge_mcp_server.client.dialect import Dialect
from rosbridge_mcp_server.client.goal_lane import GoalLane
from rosbridge_mcp_server.client.session import Session
from rosbridge_mcp_server.client.subscription import Subscription
from rosbridge_mcp_server.wire.dialect import RosInfo
from rosbridge_mcp_server.wire.goals import (
    GoalEnded,
    GoalEvent,
    GoalFeedbackEvent,
    GoalNeverRan,
    GoalStatusRefusal,
)

__all__ = [
    "BridgeCapabilities",
    "Dialect",
    "GoalCancel",
    "GoalEnded",
    "GoalEvent",
    "GoalFeedbackEvent",
    "GoalLane",
    "GoalNeverRan",
    "GoalStatusRefusal",
    "RosInfo",
    "RosbridgeClient",
    "Session",
    "SessionWatcher",
    "Subscription",
]
