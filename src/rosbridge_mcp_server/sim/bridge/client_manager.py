"""rosbridge's ClientManager: the latched ``/client_count`` and ``/connected_clients`` topics (both lines)."""

from __future__ import annotations

import logging

from rosbridge_mcp_server.sim.bridge.core import BridgeCore
from rosbridge_mcp_server.sim.graph import ROSBRIDGE_NODE
from rosbridge_mcp_server.sim.interfaces import InterfaceError

__all__ = ["ClientManager"]

log = logging.getLogger("rosbridge_mcp_server.sim")


class ClientManager:
    """Who is connected, published on every connect and disconnect.

    0.11.17 publishes both topics latched, the ros2 branch with transient-local QoS.
    """

    def __init__(self, core: BridgeCore) -> None:
        self.core = core
        #: (ip address, connection time) per connected client, in connect order.
        self._clients: dict[int, tuple[str, float]] = {}
        self._types: tuple[str, str] | None = None

    def add_topics(self) -> None:
        """Put the two topics in the graph (the world calls this while it builds itself)."""
        ros2 = self.core.ros2
        registry = self.core.registry
        try:
            count_type = registry.resolve("std_msgs/msg/Int32" if ros2 else "std_msgs/Int32", "msg")
            clients_type = registry.resolve(
                "rosbridge_msgs/msg/ConnectedClients" if ros2 else "rosbridge_msgs/ConnectedClients", "msg"
            )
        except InterfaceError as exc:
            log.warning("rosbridge's client topics left out: %s", exc)
            return
        self._types = (count_type, clients_type)
        graph = self.core.graph
        for topic, msg_type in (("/client_count", count_type), ("/connected_clients", clients_type)):
            graph.add_publisher(ROSBRIDGE_NODE, topic, msg_type)
            graph.latched.setdefault(topic, None)
        self._publish()

    def connected(self, client: int, address: str, since: float) -> None:
        self._clients[client] = (address, since)
        self._publish()

    def disconnected(self, client: int) -> None:
        self._clients.pop(client, None)
        self._publish()

    def _publish(self) -> None:
        if self._types is None:
            return
        count_type, clients_type = self._types
        clients = []
        for address, since in self._clients.values():
            sec = int(since)
            nsec = int((since - sec) * 1e9)
            stamp = {"sec": sec, "nanosec": nsec} if self.core.ros2 else {"secs": sec, "nsecs": nsec}
            clients.append({"ip_address": address, "connection_time": stamp})
        self.core.publish_json("/connected_clients", clients_type, {"clients": clients})
        self.core.publish_json("/client_count", count_type, {"data": len(clients)})
