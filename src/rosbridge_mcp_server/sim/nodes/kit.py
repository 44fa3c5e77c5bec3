"""What every world node uses: the dialect's type names, stamps and headers, and registering on the graph."""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Awaitable, Callable
from typing import Any, Literal

from rosbridge_mcp_server.sim.bridge import Bridge
from rosbridge_mcp_server.sim.graph import ServiceEntry
from rosbridge_mcp_server.sim.interfaces import InterfaceError

__all__ = ["Loop", "NodeKit", "ServiceFn", "quaternion_from_yaw"]

log = logging.getLogger("rosbridge_mcp_server.sim")

ServiceFn = Callable[[dict[str, Any]], Awaitable[dict[str, Any]]]
Loop = Callable[[], Awaitable[None]]


def quaternion_from_yaw(yaw: float) -> dict[str, float]:
    """A rotation about z as a ``geometry_msgs/Quaternion``."""
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}


class NodeKit:
    """The world's side of the bridge: type look-ups, registration, publishing, and the periodic loops."""

    def __init__(self, bridge: Bridge) -> None:
        self.bridge = bridge
        self.world = bridge.world
        self.graph = bridge.graph
        self.ros2 = bridge.config.dialect == "ros2"
        #: The type of every topic a world node publishes.
        self.types: dict[str, str] = {}
        #: Periodic publishers, started with the robot.
        self.loops: list[Loop] = []
        self._seq = 0

    def type(self, ros2_name: str, ros1_name: str, kind: Literal["msg", "srv", "action"]) -> str | None:
        """The dialect's canonical type name, or ``None`` (logged) when the registry lacks it."""
        name = ros2_name if self.ros2 else ros1_name
        try:
            return self.bridge.registry.resolve(name, kind)
        except InterfaceError as exc:
            log.warning("left out of the world (type %s unknown): %s", name, exc)
            return None

    def msg_type(self, package: str, name: str) -> str | None:
        """A message type spelled the same in both dialects but for ``/msg/``."""
        return self.type(f"{package}/msg/{name}", f"{package}/{name}", "msg")

    def stamp(self, seconds: float | None = None) -> dict[str, int]:
        now = time.time() if seconds is None else seconds
        sec = int(now)
        nsec = int((now - sec) * 1e9)
        return {"sec": sec, "nanosec": nsec} if self.ros2 else {"secs": sec, "nsecs": nsec}

    def header(self, frame_id: str, seconds: float | None = None) -> dict[str, Any]:
        header: dict[str, Any] = {"stamp": self.stamp(seconds), "frame_id": frame_id}
        if not self.ros2:
            self._seq += 1
            header = {"seq": self._seq, **header}
        return header

    def service(self, node: str, name: str, service_type: str | None, handler: ServiceFn) -> None:
        if service_type is None:
            return
        self.graph.add_service(ServiceEntry(name, service_type, node, handler))

    def publisher(self, node: str, topic: str, msg_type: str | None, *, latched: bool = False) -> bool:
        """Register ``node`` as a publisher of ``topic``; ``latched`` keeps the last message for late
        subscribers (ROS 1 latched, ROS 2 transient-local)."""
        if msg_type is None:
            return False
        self.graph.add_publisher(node, topic, msg_type)
        self.types[topic] = msg_type
        if latched:
            self.graph.latched.setdefault(topic, None)
        return True

    def publish(self, topic: str, partial: dict[str, Any], *, complete: bool = False) -> None:
        """Publish if anyone listens (a latched topic always: its last message waits for subscribers).

        ``complete`` messages (every field, wire form) skip the inbound conversion, which costs tens of
        milliseconds for a large image's byte list."""
        msg_type = self.types.get(topic)
        if msg_type is None:
            return
        if topic not in self.graph.latched and not self.bridge.has_subscribers(topic):
            return
        if complete:
            self.bridge.publish(topic, msg_type, partial)
        else:
            self.bridge.publish_json(topic, msg_type, partial)

    def wants(self, topic: str) -> bool:
        """Whether a message on ``topic`` would reach anyone (expensive publishers idle otherwise)."""
        return topic in self.types and self.bridge.has_subscribers(topic)
