"""rosbridge's topic capabilities: ``advertise``/``unadvertise``, ``publish``, ``subscribe``/``unsubscribe``.

Every client's advertisements and subscriptions show in the graph as publishers and subscribers of the
rosbridge node; several subscriptions of one client to one topic share one delivery.
"""

from __future__ import annotations

import asyncio
import logging
import time
from typing import Any

from rosbridge_mcp_server.sim.bridge.core import (
    RS_NOT_IN_GRAPH,
    BridgeCore,
    Capability,
    FieldSpec,
    OpError,
    OpHandler,
    check_fields,
)
from rosbridge_mcp_server.sim.connection import (
    Connection,
    SubscriptionOptions,
    TopicSubscription,
)
from rosbridge_mcp_server.sim.graph import ROSBRIDGE_NODE
from rosbridge_mcp_server.sim.interfaces import ConversionError
from rosbridge_mcp_server.sim.world import PublishedMessage

__all__ = ["UNREGISTER_TIMEOUT", "Topics"]

log = logging.getLogger("rosbridge_mcp_server.sim")

#: 0.11.17 keeps a publisher this long after its last client unadvertised (``unregister_timeout``).
UNREGISTER_TIMEOUT = 10.0

_QOS_CHOICES = {
    "history": ("keep_last", "keep_all"),
    "reliability": ("reliable", "best_effort", "best_available"),
    "durability": ("transient_local", "volatile", "best_available"),
}


class Topics(Capability):
    """Advertise, publish, subscribe: rosbridge's publisher and subscriber managers."""

    def __init__(self, core: BridgeCore) -> None:
        super().__init__(core)
        #: ROS 1 publishers without clients, waiting out unregister_timeout.
        self._lingering: dict[str, asyncio.TimerHandle] = {}
        self.unregister_timeout = UNREGISTER_TIMEOUT
        #: Topics a client registered latched (the publisher manager's ``latched_client_id``).
        self._latched_by_client: set[str] = set()

    def ops(self) -> dict[str, OpHandler]:
        return {
            "advertise": self.advertise,
            "unadvertise": self.unadvertise,
            "publish": self.publish,
            "subscribe": self.subscribe,
            "unsubscribe": self.unsubscribe,
        }

    # --- advertise ----------------------------------------------------------------------------------------

    def advertise(self, conn: Connection, msg: dict[str, Any]) -> None:
        fields: list[FieldSpec] = [
            (True, "topic", (str,)),
            (True, "type", (str,)),
            (False, "latch", (bool,)),
            (False, "queue_size", (int,)),
        ]
        if self.core.ros2:
            fields.append((False, "qos", (dict,)))
        check_fields(msg, fields)
        self._check_qos(msg)
        topic = self.core.name(msg["topic"])
        msg_type = self.core.resolve_type(msg["type"], "msg")
        self._register_publisher(conn, topic, msg_type, msg.get("id"), latch=bool(msg.get("latch", False)))

    def _register_publisher(
        self, conn: Connection, topic: str, msg_type: str, aid: Any, *, latch: bool
    ) -> None:
        existing = self.core.established_type(topic)
        if existing is not None and existing != msg_type:
            raise OpError(
                f"Tried to register topic {topic} with type {msg_type} but it is already established with "
                f"type {existing}"
            )
        ids = conn.advertisements.get(topic)
        if ids is None:
            ids = conn.advertisements[topic] = []
            lingering = self._lingering.pop(topic, None)
            if lingering is not None:
                lingering.cancel()  # the publisher still exists: this client takes it over
            else:
                self.core.graph.add_publisher(ROSBRIDGE_NODE, topic, msg_type)
        if aid not in ids:
            ids.append(aid)
        conn.advertised_types[topic] = msg_type
        if latch:
            self.core.graph.latched.setdefault(topic, None)
            self._latched_by_client.add(topic)

    def unadvertise(self, conn: Connection, msg: dict[str, Any]) -> None:
        check_fields(msg, [(True, "topic", (str,))])
        topic = self.core.name(msg["topic"])
        ids = conn.advertisements.get(topic)
        if ids is None:
            return
        if "id" in msg:
            if msg["id"] in ids:
                ids.remove(msg["id"])
        else:
            ids.clear()
        if not ids:
            del conn.advertisements[topic]
            self._remove_rosbridge_publisher(topic)

    def _remove_rosbridge_publisher(self, topic: str) -> None:
        """One client's advertisement of ``topic`` is gone; rospy's publisher goes with the last one.

        0.11.17 unregisters that publisher only ``unregister_timeout`` (10 s) later, unless a client
        advertises the topic again meanwhile: until then the master still lists it.
        """
        graph = self.core.graph
        last = graph.node(ROSBRIDGE_NODE).publishes.get(topic, 0) <= 1
        if last and not self.core.ros2:
            old = self._lingering.pop(topic, None)
            if old is not None:
                old.cancel()
            loop = asyncio.get_running_loop()
            self._lingering[topic] = loop.call_later(
                self.unregister_timeout, self._unregister_publisher, topic
            )
            return
        graph.remove_publisher(ROSBRIDGE_NODE, topic)
        if topic not in graph.node(ROSBRIDGE_NODE).publishes:
            self.core.forget_header_seq(topic)
            self._latched_by_client.discard(topic)

    def _unregister_publisher(self, topic: str) -> None:
        if self._lingering.pop(topic, None) is None:
            return
        self.core.graph.remove_publisher(ROSBRIDGE_NODE, topic)
        self.core.forget_header_seq(topic)
        self._latched_by_client.discard(topic)
        self.core.world.notify()

    # --- publish ------------------------------------------------------------------------------------------

    def publish(self, conn: Connection, msg: dict[str, Any]) -> None:
        core = self.core
        fields: list[FieldSpec] = [
            (True, "topic", (str,)),
            (False, "latch", (bool,)),
            (False, "queue_size", (int,)),
        ]
        if core.ros2:
            fields += [(False, "type", (str,)), (False, "qos", (dict,))]
        check_fields(msg, fields)
        topic = core.name(msg["topic"])
        if topic in conn.advertisements:
            msg_type = conn.advertised_types[topic]
        else:
            graph_type = core.infer_type(msg["topic"])
            if graph_type is not None:
                msg_type = graph_type
            elif core.ros2 and "type" in msg:
                # ROS 2 2.0.6/2.6.0/3.2.0/4.1.0+ register the topic from the publish's own type.
                msg_type = core.resolve_type(msg["type"], "msg")
            elif core.config.rs:
                raise OpError(RS_NOT_IN_GRAPH)
            else:
                raise OpError(f"Cannot infer topic type for topic {msg['topic']} as it is not yet advertised")
            self._register_publisher(
                conn, topic, msg_type, msg.get("id"), latch=bool(msg.get("latch", False))
            )
        if topic in self._latched_by_client and msg.get("latch") is not True:
            # Both lines register the publisher again with the publish's own latch flag, and say so.
            log.warning(
                "New non-latched publisher registration for topic [%s] which is already registered as "
                "latched. but this topic was previously registered.",
                topic,
            )
        if msg.get("latch") is True and not core.ros2:
            # 0.11.17 registers the publisher again with the publish's latch flag: the topic latches.
            core.graph.latched.setdefault(topic, None)
        values = msg.get("msg", {})
        try:
            converted = core.registry.from_json(msg_type, values)
        except ConversionError as exc:
            raise OpError(str(exc)) from exc
        core.world.record_published(PublishedMessage(topic, msg_type, converted, time.monotonic(), conn.id))
        try:
            core.publish(topic, msg_type, converted, source=conn.id)
        except ConversionError as exc:
            raise OpError(str(exc)) from exc

    # --- subscribe ----------------------------------------------------------------------------------------

    def subscribe(self, conn: Connection, msg: dict[str, Any]) -> None:
        core = self.core
        fields: list[FieldSpec] = [
            (True, "topic", (str,)),
            (False, "type", (str,)),
            (False, "throttle_rate", (int,)),
            (False, "fragment_size", (int,)),
            (False, "queue_length", (int,)),
            (False, "compression", (str,)),
        ]
        if core.ros2:
            fields.append((False, "qos", (dict,)))
        check_fields(msg, fields)
        self._check_qos(msg)
        topic = core.name(msg["topic"])
        graph_type = core.established_type(topic)
        if "type" in msg:
            msg_type = core.resolve_type(msg["type"], "msg")
            if graph_type is not None and graph_type != msg_type:
                raise OpError(
                    f"Tried to register topic {topic} with type {msg_type} but it is already established "
                    f"with type {graph_type}"
                )
        elif (inferred := core.infer_type(msg["topic"])) is not None:
            msg_type = inferred
        elif core.config.rs:
            raise OpError(RS_NOT_IN_GRAPH)
        else:
            raise OpError(f"Cannot infer topic type for topic {msg['topic']} as it is not yet advertised")
        compression = msg.get("compression", "none")
        if compression == "cbor" and not core.config.cbor:
            compression = "none"  # a bridge without CBOR that ignores the key
        if compression == "cbor-raw":
            log.warning(
                "client %d: compression %r is not simulated; sending JSON on %s", conn.id, compression, topic
            )
        sid = msg.get("id")
        hash(sid)  # an unhashable id fails here, before anything is registered
        sub = conn.subscriptions.get(topic)
        if sub is None:
            sub = conn.subscriptions[topic] = TopicSubscription(topic, msg["topic"], msg_type)
            core.graph.add_subscriber(ROSBRIDGE_NODE, topic, msg_type)
        sub.by_id[sid] = SubscriptionOptions(
            msg.get("throttle_rate", 0), msg.get("queue_length", 0), compression
        )
        latched = core.latched_message(topic, msg_type)
        if latched is not None:
            try:
                conn.deliver(latched, core.fragment_id)
            except ConversionError as exc:  # rosbridge's CBOR converter (fixed-size arrays): logged, not sent
                log.error("cannot send %s on %s: %s", msg_type, topic, exc)

    def unsubscribe(self, conn: Connection, msg: dict[str, Any]) -> None:
        check_fields(msg, [(True, "topic", (str,))])
        topic = self.core.name(msg["topic"])
        sid = msg.get("id")
        hash(sid)  # an unhashable id fails here, before anything is registered
        sub = conn.subscriptions.get(topic)
        if sub is None:
            return
        if "id" in msg:
            sub.by_id.pop(msg["id"], None)
        else:
            sub.by_id.clear()
        if not sub.by_id:
            conn.drop_subscription(topic)
            self.core.graph.remove_subscriber(ROSBRIDGE_NODE, topic)

    def _check_qos(self, msg: dict[str, Any]) -> None:
        """The ROS 2 ``qos`` object (protocol v2.1.0): checked, not modelled."""
        qos = msg.get("qos")
        if qos is None or not self.core.ros2:
            return  # ROS 1 has no qos field: it is ignored like any unknown key
        for key, value in qos.items():
            if key in _QOS_CHOICES and value not in _QOS_CHOICES[key]:
                raise OpError(f"Invalid QoS {key}: {value!r}")
            if key == "depth" and (not isinstance(value, int) or isinstance(value, bool) or value < 0):
                raise OpError(f"Invalid QoS depth: {value!r}")
            if value == "best_available" and self.core.config.in_order:
                # Humble's rmw has no best_available policies.
                raise OpError(f"QoS {key} 'best_available' is not supported on Humble")

    # --- clients ------------------------------------------------------------------------------------------

    def client_gone(self, conn: Connection) -> None:
        """rosbridge's ``finish()``: the client's subscriptions and advertisements go."""
        for topic in list(conn.subscriptions):
            conn.drop_subscription(topic)
            self.core.graph.remove_subscriber(ROSBRIDGE_NODE, topic)
        for topic in list(conn.advertisements):
            del conn.advertisements[topic]
            self._remove_rosbridge_publisher(topic)

    def shutdown(self) -> None:
        """Unregister every lingering publisher now (the rosbridge process is stopping)."""
        for topic, handle in list(self._lingering.items()):
            handle.cancel()
            self._unregister_publisher(topic)
            self._lingering.pop(topic, None)
