"""The asyncio rosbridge client.

``RosbridgeClient`` keeps one shared WebSocket to the bridge (reconnecting in the background), plus
short-lived lanes for goals and, on bridges that handle a connection in order (Humble), for service
calls. By job: ``client.py`` (lifecycle, the connect loop, the current ``BridgeSession``), ``calls.py``
(services and their ordering, topics, a ping: the client's calls), ``reconnect.py`` (when to try: backoff,
attempts prompted by calls), ``session.py`` (``BridgeSession``: one connection and what was learnt on it,
opened whole), ``goals.py`` (a ``GoalHandle`` per goal, every goal cancel, the goals a drop cut off;
``cut_off.py`` their ledger's entries), ``actionlib.py`` (a ROS 1 goal over actionlib's topics), ``detect.py``
(ROS version detection), ``capabilities.py`` (what the bridge can do, named: the one place that tells bridges
apart), ``dialect.py`` (the bridge's spelling of types and time fields, one ``Dialect`` per session),
``services.py`` (service calls), ``topics.py`` and ``subscription.py`` (advertisements, subscriptions),
``lanes.py`` and ``goal_lane.py`` (extra connections: a ROS 2 goal's own), ``connection.py`` (one WebSocket
and its reader), ``frame_limits.py`` (what one frame may hold: size, text, nesting).

Only this face is for the layers above: the connections (``BridgeSession``, the lanes) stay inside.
"""

from __future__ import annotations

from rosbridge_mcp_server.client.capabilities import BridgeCapabilities
from rosbridge_mcp_server.client.client import RosbridgeClient, SessionFacts, SessionWatcher
from rosbridge_mcp_server.client.dialect import Dialect
from rosbridge_mcp_server.client.goals import GoalCancel, GoalHandle, OthersCancel
from rosbridge_mcp_server.client.subscription import Subscription
from rosbridge_mcp_server.wire.goals import (
    GoalEnded,
    GoalEvent,
    GoalFeedbackEvent,
    GoalNeverRan,
    GoalStatusRefusal,
)
from rosbridge_mcp_server.wire.ros_versions import RosInfo

__all__ = [
    "BridgeCapabilities",
    "Dialect",
    "GoalCancel",
    "GoalEnded",
    "GoalEvent",
    "GoalFeedbackEvent",
    "GoalHandle",
    "GoalNeverRan",
    "GoalStatusRefusal",
    "OthersCancel",
    "RosInfo",
    "RosbridgeClient",
    "SessionFacts",
    "SessionWatcher",
    "Subscription",
]
