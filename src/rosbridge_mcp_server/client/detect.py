"""What the bridge is: ROS version and distro, asked once per connection through rosapi."""

from __future__ import annotations

import logging
from typing import Any

from rosbridge_mcp_server.client.connection import Connection
from rosbridge_mcp_server.client.services import call_on
from rosbridge_mcp_server.errors import RequestTimeoutError, ServiceError
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.dialect import RosInfo

__all__ = ["ROS1_BRIDGE_NODE", "detect"]

logger = logging.getLogger("rosbridge_mcp_server.client")

#: rosbridge's node name in rosbridge_websocket.launch (ROS 1 0.11); used to tell ROS 1 without rosapi.
ROS1_BRIDGE_NODE = "rosbridge_websocket"
#: The node name rosbridge's launch files (ROS 1 and 2) and `ros2 run` give the bridge.
BRIDGE_NODE = "rosbridge_websocket"


async def detect(conn: Connection, ids: protocol.IdMinter, url: str, timeout: float) -> RosInfo:
    """Ask the bridge on *conn* what it is."""

    async def call(service: str) -> Any:
        return await call_on(conn, ids, service, None, timeout, bridge_timeout=None)

    try:
        values = await call("/rosapi/get_ros_version")
    except ServiceError:
        # ROS 1 (0.11.x) and ROS 2 before rosbridge 1.2.0 answer "Service /rosapi/get_ros_version
        # does not exist"; the type names tell them apart.
        pass
    except RequestTimeoutError:
        logger.warning("rosbridge at %s did not answer /rosapi/get_ros_version; assuming ROS 2", url)
        return RosInfo(2, None)
    else:
        version = values.get("version") if isinstance(values, dict) else None
        distro = values.get("distro") if isinstance(values, dict) else None
        if version == 1:
            return RosInfo(1, distro or None)
        calls, goals = await _threading(conn, ids, timeout)
        return RosInfo(2, str(distro) if distro else None, calls_threaded=calls, goals_threaded=goals)
    try:
        values = await call("/rosapi/topics")
    except ServiceError as exc:
        # No rosapi. Every rospy node offers <node>/get_loggers; ROS 2 nodes never do. Without this, a
        # real 0.11.17 bridge without rosapi was taken for ROS 2 and publish_action sent it action ops it
        # ignores, waiting out the whole timeout.
        if await _answers(call, f"/{ROS1_BRIDGE_NODE}/get_loggers"):
            logger.warning("No rosapi at %s; its rosbridge node is a ROS 1 (rospy) node", url)
            return RosInfo(1, None)
        logger.warning("Cannot tell the ROS version of %s (no rosapi? %s); assuming ROS 2", url, exc)
        return RosInfo(2, None)
    except RequestTimeoutError as exc:
        logger.warning("Cannot tell the ROS version of %s (no rosapi? %s); assuming ROS 2", url, exc)
        return RosInfo(2, None)
    types = values.get("types", []) if isinstance(values, dict) else []
    if any(isinstance(t, str) and "/msg/" in t for t in types):
        return RosInfo(2, None)
    return RosInfo(1, None)


async def _threading(
    conn: Connection, ids: protocol.IdMinter, timeout: float
) -> tuple[bool | None, bool | None]:
    """Whether a ROS 2 bridge runs each call and each goal in a thread of its own, as its node says.

    rosbridge 2.x reads ``call_services_in_new_thread`` and ``send_action_goals_in_new_thread``; 2.1.0's
    launch file sets both false, on Jazzy and Kilted alike. They are asked of the bridge node's own
    ``get_parameters`` service: one call of ~6-10 ms on 2.1.0, where rosapi's ``get_param`` takes 60-180 ms
    per parameter (and 5 s, serving nobody else, for a node that does not exist). ``None`` where the bridge
    did not tell: a node of another name, or a parameter it does not declare.
    """
    service = f"/{BRIDGE_NODE}/get_parameters"
    args = {"names": ["call_services_in_new_thread", "send_action_goals_in_new_thread"]}
    try:
        values = await call_on(conn, ids, service, args, timeout, bridge_timeout=None)
    except (ServiceError, RequestTimeoutError):
        return None, None
    listed = values.get("values") if isinstance(values, dict) else None
    if not isinstance(listed, list) or len(listed) != 2:
        return None, None
    return _bool_parameter(listed[0]), _bool_parameter(listed[1])


def _bool_parameter(value: Any) -> bool | None:
    """A boolean ``rcl_interfaces/ParameterValue`` (type 1), else ``None`` (not set, or another type)."""
    if isinstance(value, dict) and value.get("type") == 1 and isinstance(value.get("bool_value"), bool):
        return bool(value["bool_value"])
    return None


async def _answers(call: Any, service: str) -> bool:
    """Whether *service* answers a call with an empty request."""
    try:
        await call(service)
    except (ServiceError, RequestTimeoutError):
        return False
    return True
