"""What the bridge is: ROS version and distro (asked of rosapi) and how it behaves (judged from its answers),
once per connection."""

from __future__ import annotations

import contextlib
import logging
from typing import Any

from rosbridge_mcp_server.client.connection import Connection
from rosbridge_mcp_server.client.services import call_on
from rosbridge_mcp_server.errors import RequestTimeoutError, ServiceError
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.ros_versions import RosInfo

__all__ = ["ROS1_BRIDGE_NODE", "detect"]

logger = logging.getLogger("rosbridge_mcp_server.client")

#: rosbridge's node name in rosbridge_websocket.launch (ROS 1 0.11); used to tell ROS 1 without rosapi.
ROS1_BRIDGE_NODE = "rosbridge_websocket"


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
        told = await _answers_with_status(conn, ids, timeout)
        return RosInfo(
            2,
            str(distro) if distro else None,
            calls_threaded=True if told else None,
            goals_threaded=True if told else None,
            status_replies=told,
        )
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


#: The action a connection's probe cancel names: a goal nobody can have started.
PROBE_ACTION = "/rosbridge_mcp_server/probe"


async def _answers_with_status(conn: Connection, ids: protocol.IdMinter, timeout: float) -> bool:
    """Whether the bridge answers a refused op with an error ``status`` (judged from its answer).

    A cancel of a goal nobody started is sent, then a call: rosbridge_suite (every release) ignores the cancel
    without a word; rosbridge-server-rs 0.1.6 answers it with an error ``status`` ("unknown active goal")
    before the call's reply. Such a bridge runs each op as a task of its own (calls are never held up behind
    each other on a connection, measured on 0.1.6) and lets only the connection that started a goal cancel
    it. Nothing acts: no goal has this id. The bridge node's parameters are not read: the node called
    ``/rosbridge_websocket`` may be another bridge on the same graph.
    """
    gid = ids.goal_id(PROBE_ACTION)
    heard = conn.expect(gid, "a refusal of the probe cancel", timeout)
    try:
        await conn.send(protocol.cancel_action_goal(PROBE_ACTION, id=gid))
        if not heard.done():
            with contextlib.suppress(ServiceError, RequestTimeoutError):
                await call_on(conn, ids, "/rosapi/get_time", None, timeout, bridge_timeout=None)
        return heard.done() and not heard.cancelled() and heard.exception() is None
    finally:
        conn.forget(gid)


async def _answers(call: Any, service: str) -> bool:
    """Whether *service* answers a call with an empty request."""
    try:
        await call(service)
    except (ServiceError, RequestTimeoutError):
        return False
    return True
