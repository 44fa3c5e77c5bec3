"""The core every capability shares: configuration, name and type rules, topic routing, background tasks.

rosbridge_suite splits its server the same way: ``protocol.py`` (the input buffer and the dispatch of ops,
here :mod:`.protocol`) hands each op to the capability that owns it (``capabilities/``, here
:mod:`.capabilities`), and the capabilities share the ROS node's publishers, subscribers and services (here
:class:`BridgeCore`).
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable, Coroutine
from dataclasses import dataclass
from functools import partial
from typing import Any, Literal

from rosbridge_mcp_server.sim.connection import Connection, OutgoingMessage
from rosbridge_mcp_server.sim.graph import Graph, canonical_name, resolve_name, rostopic_type
from rosbridge_mcp_server.sim.interfaces import ConversionError, InterfaceError, InterfaceRegistry
from rosbridge_mcp_server.sim.world import World

__all__ = [
    "RS_NOT_IN_GRAPH",
    "BridgeConfig",
    "BridgeCore",
    "CallFailed",
    "Capability",
    "Dialect",
    "FieldSpec",
    "OpError",
    "OpHandler",
    "check_fields",
    "extract_id",
    "status_frame",
]

log = logging.getLogger("rosbridge_mcp_server.sim")

Dialect = Literal["ros1", "ros2"]

#: (mandatory, field name, accepted JSON types) for rosbridge's ``basic_type_check``.
FieldSpec = tuple[bool, str, tuple[type, ...]]

#: An op handler: runs the op; returns an awaitable when the op has to wait for something.
OpHandler = Callable[[Connection, dict[str, Any]], Awaitable[None] | None]


class OpError(Exception):
    """An op the real server rejects with a log line only (text as the server logs it)."""


class CallFailed(Exception):
    """A service call that ends in ``service_response`` with ``result: false``; ``str()`` is the wire text."""


@dataclass(frozen=True)
class BridgeConfig:
    """How this rosbridge behaves."""

    dialect: Dialect
    #: Humble 2.0.x defaults: every op of a connection in order, service calls and goals inline.
    in_order: bool
    #: Initial connection fragment size: ROS 2 ``max_message_size``; ROS 1 none.
    max_message_size: int | None
    #: Service timeout when the request has no ``timeout`` field; 0 = wait forever.
    default_service_timeout: float
    distro: str
    #: Whether ``call_service`` reads a ``timeout`` field (ROS 2; rosbridge_suite 2.1.0 ignores it).
    timeout_field: bool = True
    #: Whether ``compression: "cbor"`` is honoured; ``False`` is a bridge that ignores the key (JSON).
    cbor: bool = True
    #: Which server this is: ``rosbridge_suite``, or ``rs`` for rosbridge-server-rs 0.1.6 (an error
    #: ``status`` for every failed op, goals cancelled only by the connection that started them, a cancelled
    #: goal's result with ``result: false``, "type is required when interface is absent from ROS graph").
    server: Literal["rosbridge_suite", "rs"] = "rosbridge_suite"

    @property
    def rs(self) -> bool:
        """rosbridge-server-rs 0.1.6's behaviours (see :attr:`server`)."""
        return self.server == "rs"


#: rosbridge-server-rs 0.1.6's refusal of a name it needs the type of and cannot find in the graph.
RS_NOT_IN_GRAPH = "type is required when interface is absent from ROS graph"


def status_frame(msg: str, mid: Any) -> dict[str, Any]:
    """rosbridge-server-rs's answer to a failed op: ``{"op": "status", "level": "error", "msg", "id"}``."""
    frame: dict[str, Any] = {"op": "status", "level": "error", "msg": msg}
    if mid is not None:
        frame["id"] = mid
    return frame


def check_fields(msg: dict[str, Any], fields: list[FieldSpec]) -> None:
    """rosbridge's ``basic_type_check``: mandatory fields present, present fields of the right JSON type."""
    for mandatory, name, types in fields:
        if name not in msg:
            if mandatory:
                raise OpError(f"Expected a {name} field but none was found.")
            continue
        if not isinstance(msg[name], types):
            names = tuple(t.__name__ for t in types)
            raise OpError(f"Expected field {name} to be one of {names}. Invalid value: {msg[name]}")


def extract_id(name: str, cid: Any) -> tuple[str, Any]:
    """Legacy ids: ``/rosapi/topics#33`` means id ``33`` when no ``id`` is given."""
    if "#" in name:
        trimmed = name[: name.find("#")]
        return trimmed, cid if cid is not None else name[name.find("#") + 1 :]
    return name, cid


class BridgeCore:
    """What the capabilities share: the rosbridge node's view of the graph, and its clients."""

    def __init__(self, config: BridgeConfig, registry: InterfaceRegistry, world: World, graph: Graph) -> None:
        self.config = config
        self.registry = registry
        self.world = world
        self.graph = graph
        self.ros2 = config.dialect == "ros2"
        self.connections: dict[int, Connection] = {}
        #: The id of messages too long for one frame that have no id of their own (``"0"`` / ``0``).
        self.fragment_id: Any = "0" if self.ros2 else 0
        self._tasks: set[asyncio.Task[Any]] = set()
        #: rospy's per-publisher header seq counters: (published by rosbridge?, topic) -> last seq.
        self._header_seq: dict[tuple[bool, str], int] = {}
        #: The last latched message of each topic with its frames, serialised once for every late subscriber
        #: (a 2000² map is ~1 s of JSON conversion per subscribe otherwise).
        self._latched_out: dict[str, OutgoingMessage] = {}
        #: rosbridge-server-rs sends fixed-size arrays as CBOR lists; rosbridge_suite fails on them.
        self._to_cbor = partial(registry.to_cbor, fixed_lists=config.rs)

    # --- names and types ----------------------------------------------------------------------------------

    def json_form(self, msg_type: str, partial: dict[str, Any]) -> dict[str, Any]:
        """The wire form of a message given as (partial) JSON: defaults filled in, the dialect's spellings."""
        return self.registry.to_json(msg_type, self.registry.from_json(msg_type, partial))

    def name(self, raw: str) -> str:
        """A topic/service/action name as the dialect's client library resolves it.

        ROS 1: rospy's canonical form (``/add_two_ints/`` and ``//add_two_ints`` are ``/add_two_ints``).
        ROS 2: relative names go under ``/``; names rclpy would reject are kept as spelled (simplified).
        """
        return resolve_name(raw) if self.ros2 else canonical_name(raw)

    def infer_type(self, spelled: str) -> str | None:
        """The graph's type for a topic as rosbridge infers it from the name as spelled.

        ROS 2 looks the name up exactly ('chatter' does not find '/chatter'); ROS 1 uses rostopic's rule,
        which also takes a field path ('/chatter/' finds '/chatter').
        """
        if self.ros2:
            return self.graph.topic_types.get(spelled)
        return rostopic_type(self.graph.known_types, spelled)

    def established_type(self, topic: str) -> str | None:
        """The type a new publisher/subscriber of ``topic`` must have (ROS 1: also of a dead topic)."""
        types = self.graph.topic_types if self.ros2 else self.graph.known_types
        return types.get(topic)

    def resolve_type(self, name: str, kind: Literal["msg", "srv", "action"]) -> str:
        """A type name from a client, or :class:`OpError` with the loader's text."""
        try:
            return self.registry.resolve(name, kind)
        except InterfaceError as exc:
            raise OpError(str(exc)) from exc

    def args_dict(self, msg_type: str, args: Any) -> dict[str, Any]:
        """rosbridge's ``args_to_service_request_instance``: a list is values in field order, an object is
        used as it is, and anything else (null, a string, a number) is ignored, an empty request (both
        lines)."""
        if isinstance(args, list):
            names = self.registry.field_names(msg_type)
            return dict(zip(names, args, strict=False))
        if isinstance(args, dict):
            return args
        return {}

    # --- topic traffic ------------------------------------------------------------------------------------

    def publish(self, topic: str, msg_type: str, msg: dict[str, Any], *, source: int = 0) -> None:
        """Route a converted message to the world's subscribers and every subscribed client.

        ROS 1: what subscribers get is what genpy packed and unpacked (see ``ros1_wire``), with the root
        header's ``seq`` set from the publisher's own counter (rospy overwrites it; world publishers and
        rosbridge's count apart, rosbridge's restarts when its publisher of the topic goes).
        """
        if not self.ros2:
            try:
                msg = self.registry.ros1_wire(msg_type, msg)
            except ConversionError as exc:
                log.error("publish on %s: %s (message lost)", topic, exc)
                raise
            if self.registry.has_header(msg_type):
                key = (source != 0, topic)
                seq = self._header_seq[key] = self._header_seq.get(key, 0) + 1
                msg = {**msg, "header": {**msg["header"], "seq": seq}}
        for callback in list(self.graph.local_subscribers.get(topic, ())):
            try:
                callback(msg, source)
            except Exception:
                log.exception("subscriber of %s failed", topic)
        outgoing = OutgoingMessage(topic, msg_type, msg, self.registry.to_json, self._to_cbor)
        if topic in self.graph.latched:
            self.graph.latched[topic] = msg
            self._latched_out[topic] = outgoing
        for conn in list(self.connections.values()):
            if topic in conn.subscriptions:
                try:
                    conn.deliver(outgoing, self.fragment_id)
                except (ConversionError, InterfaceError) as exc:
                    log.error("cannot send %s on %s: %s", msg_type, topic, exc)
                    return

    def latched_message(self, topic: str, msg_type: str) -> OutgoingMessage | None:
        """The topic's latched message for a new subscriber (its frames made once), if it has one."""
        latched = self.graph.latched.get(topic)
        if latched is None:
            return None
        outgoing = self._latched_out.get(topic)
        if outgoing is None or outgoing.msg is not latched or outgoing.type != msg_type:
            outgoing = self._latched_out[topic] = OutgoingMessage(
                topic, msg_type, latched, self.registry.to_json, self._to_cbor
            )
        return outgoing

    def publish_json(self, topic: str, msg_type: str, partial: dict[str, Any]) -> None:
        """Publish a world message given in JSON form (missing fields take defaults)."""
        self.publish(topic, msg_type, self.registry.from_json(msg_type, partial))

    def has_subscribers(self, topic: str) -> bool:
        """Whether any client or world node listens to ``topic`` (lets expensive publishers idle)."""
        return bool(self.graph.local_subscribers.get(topic)) or any(
            topic in c.subscriptions for c in self.connections.values()
        )

    def forget_header_seq(self, topic: str) -> None:
        """rosbridge's publisher of ``topic`` is gone: its header seq counter restarts with the next one."""
        self._header_seq.pop((True, topic), None)

    def send_to_client(self, client: int, message: dict[str, Any]) -> bool:
        """Send one reply-like frame to a client; ``False`` if it has gone."""
        conn = self.connections.get(client)
        if conn is None:
            return False
        conn.send(message)
        return True

    # --- background work ----------------------------------------------------------------------------------

    def spawn(self, coro: Coroutine[Any, Any, Any]) -> None:
        """Run ``coro`` as a task of the bridge (cancelled by :meth:`cancel_tasks`)."""
        task = asyncio.create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    def cancel_tasks(self) -> None:
        for task in list(self._tasks):
            task.cancel()


class Capability:
    """One group of ops (rosbridge's ``Capability``): registers its handlers, cleans up after clients."""

    def __init__(self, core: BridgeCore) -> None:
        self.core = core

    def ops(self) -> dict[str, OpHandler]:
        """The ops this capability handles in this dialect, by name."""
        return {}

    def client_gone(self, conn: Connection) -> None:
        """What rosbridge's ``finish()`` does for this capability when a client disconnects."""

    def shutdown(self) -> None:
        """The rosbridge process is stopping: stop everything still waiting."""
