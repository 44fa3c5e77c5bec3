"""The rosbridge side of the simulated robot: every op a client may send, handled as rosbridge_suite does.

Each handler follows the capability of the same name in rosbridge_suite (``rosbridge_library/capabilities``):
the same field checks, the same replies, and the same silences. Errors that the real server only logs are
logged here too (to stderr, logger ``rosbridge_mcp_server.sim``) and nothing is sent back; the only failures
a client ever sees on the wire are ``service_response``/``action_result`` with ``result: false``
(protocol file §3).
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import json
import logging
import time
from collections import OrderedDict
from collections.abc import Awaitable, Callable, Coroutine
from dataclasses import dataclass, field
from typing import Any, Literal

from websockets.asyncio.server import ServerConnection
from websockets.exceptions import ConnectionClosed

from rosbridge_mcp_server.sim.actions import GoalHandle, HostedActionServer
from rosbridge_mcp_server.sim.connection import (
    Connection,
    OutgoingMessage,
    SubscriptionOptions,
    TopicSubscription,
    dumps_standard,
    dumps_ujson,
)
from rosbridge_mcp_server.sim.graph import (
    ROSBRIDGE_NODE,
    Graph,
    HandlerReturnedNone,
    ServiceEntry,
    ServiceFailure,
    canonical_name,
    resolve_name,
    rostopic_type,
)
from rosbridge_mcp_server.sim.interfaces import ConversionError, InterfaceError, InterfaceRegistry
from rosbridge_mcp_server.sim.world import PublishedMessage, World

__all__ = ["Bridge", "BridgeConfig", "CallFailed", "OpError"]

log = logging.getLogger("rosbridge_mcp_server.sim")

Dialect = Literal["ros1", "ros2"]

#: rosbridge keeps incomplete fragment lists this long (``fragment_timeout``, 600 s).
FRAGMENT_TIMEOUT = 600.0
#: Our own bounds on incoming fragments, so that one client cannot grow the server without limit.
MAX_FRAGMENT_BUFFERS = 256
MAX_FRAGMENT_BYTES = 64 * 1024 * 1024
#: rosbridge (ROS 2, 2.0.5+/2.5.0+) waits this long for an action server before giving up.
ACTION_SERVER_WAIT = 1.0

#: 0.11.17 keeps a publisher this long after its last client unadvertised (``unregister_timeout``).
UNREGISTER_TIMEOUT = 10.0
#: 0.11.17 unadvertise_service: graceful_shutdown(timeout=1.0) busy-waits this long before the service goes.
UNADVERTISE_SERVICE_WAIT = 1.0
#: Our bound on a connection's unparsable input (the real buffer is unbounded); Tornado's frame limit.
MAX_INPUT_BUFFER = 10 * 1024 * 1024

_FieldSpec = tuple[bool, str, tuple[type, ...]]


class OpError(Exception):
    """An op the real server rejects with a log line only (text as the server logs it)."""


class _ReadingDied(Exception):
    """An input that raises outside rosbridge's per-op error handling: the connection's reading ends."""


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


@dataclass
class _HostedService:
    """One client advertisement of a service: its request counter and whether it is going away."""

    ids: itertools.count[int] = field(default_factory=lambda: itertools.count(1))
    closing: bool = False


@dataclass
class _FragmentBuffer:
    total: int
    parts: list[str] = field(default_factory=list)
    size: int = 0
    started: float = field(default_factory=time.monotonic)


def _check(msg: dict[str, Any], fields: list[_FieldSpec]) -> None:
    """rosbridge's ``basic_type_check``: mandatory fields present, present fields of the right JSON type."""
    for mandatory, name, types in fields:
        if name not in msg:
            if mandatory:
                raise OpError(f"Expected a {name} field but none was found.")
            continue
        if not isinstance(msg[name], types):
            names = tuple(t.__name__ for t in types)
            raise OpError(f"Expected field {name} to be one of {names}. Invalid value: {msg[name]}")


def _extract_id(name: str, cid: Any) -> tuple[str, Any]:
    """Legacy ids: ``/rosapi/topics#33`` means id ``33`` when no ``id`` is given."""
    if "#" in name:
        trimmed = name[: name.find("#")]
        return trimmed, cid if cid is not None else name[name.find("#") + 1 :]
    return name, cid


class Bridge:
    """The rosbridge server process: connections, ops, and the routing of topic messages."""

    def __init__(self, config: BridgeConfig, registry: InterfaceRegistry, world: World, graph: Graph) -> None:
        self.config = config
        self.registry = registry
        self.world = world
        self.graph = graph
        self.connections: dict[int, Connection] = {}
        self.connection_count = 0
        #: rosbridge's ``client_handler_list``: a class attribute, so shared by every connection (§7.2).
        self.goal_table: dict[Any, GoalHandle] = {}
        self._next_cid = 0
        self._fragments: OrderedDict[Any, _FragmentBuffer] = OrderedDict()
        self._fragment_bytes = 0
        self._service_requests: dict[str, tuple[asyncio.Future[dict[str, Any]], str, str]] = {}
        self._hosted_services: dict[str, _HostedService] = {}
        #: ROS 1 publishers without clients, waiting out unregister_timeout.
        self._lingering: dict[str, asyncio.TimerHandle] = {}
        self.unregister_timeout = UNREGISTER_TIMEOUT
        self._tasks: set[asyncio.Task[Any]] = set()
        self._readers: set[asyncio.Task[None]] = set()
        self._fragment_id: Any = "0" if config.dialect == "ros2" else 0
        #: rosbridge's ClientManager: (ip address, connection time) per connected client, in connect order.
        self._clients: dict[int, tuple[str, float]] = {}
        self._client_types: tuple[str, str] | None = None
        #: rospy's per-publisher header seq counters: (published by rosbridge?, topic) -> last seq.
        self._header_seq: dict[tuple[bool, str], int] = {}
        self._ops: dict[str, Callable[[Connection, dict[str, Any]], Awaitable[None] | None]] = {
            "fragment": self._op_fragment,
            "advertise": self._op_advertise,
            "unadvertise": self._op_unadvertise,
            "publish": self._op_publish,
            "subscribe": self._op_subscribe,
            "unsubscribe": self._op_unsubscribe,
            "call_service": self._op_call_service,
            "advertise_service": self._op_advertise_service,
            "unadvertise_service": self._op_unadvertise_service,
            "service_response": self._op_service_response,
        }
        if config.dialect == "ros2":
            self._ops.update(
                {
                    "send_action_goal": self._op_send_action_goal,
                    "cancel_action_goal": self._op_cancel_action_goal,
                    "advertise_action": self._op_advertise_action,
                    "unadvertise_action": self._op_unadvertise_action,
                    "action_feedback": self._op_action_feedback,
                    "action_result": self._op_action_result,
                }
            )

    # --- conversions --------------------------------------------------------------------------------------

    def json_form(self, msg_type: str, partial: dict[str, Any]) -> dict[str, Any]:
        """The wire form of a message given as (partial) JSON: defaults filled in, the dialect's spellings."""
        return self.registry.to_json(msg_type, self.registry.from_json(msg_type, partial))

    def name(self, raw: str) -> str:
        """A topic/service/action name as the dialect's client library resolves it.

        ROS 1: rospy's canonical form (``/add_two_ints/`` and ``//add_two_ints`` are ``/add_two_ints``).
        ROS 2: relative names go under ``/``; names rclpy would reject are kept as spelled (simplified).
        """
        return canonical_name(raw) if self.config.dialect == "ros1" else resolve_name(raw)

    def infer_type(self, spelled: str) -> str | None:
        """The graph's type for a topic as rosbridge infers it from the name as spelled.

        ROS 2 looks the name up exactly ('chatter' does not find '/chatter'); ROS 1 uses rostopic's rule,
        which also takes a field path ('/chatter/' finds '/chatter').
        """
        if self.config.dialect == "ros1":
            return rostopic_type(self.graph.known_types, spelled)
        return self.graph.topic_types.get(spelled)

    def established_type(self, topic: str) -> str | None:
        """The type a new publisher/subscriber of ``topic`` must have (ROS 1: also of a dead topic)."""
        types = self.graph.known_types if self.config.dialect == "ros1" else self.graph.topic_types
        return types.get(topic)

    def _args_dict(self, msg_type: str, args: Any) -> dict[str, Any]:
        """rosbridge's ``args_to_service_request_instance``: a list is values in field order, an object is
        used as it is, and anything else (null, a string, a number) is ignored, an empty request (both
        lines)."""
        if isinstance(args, list):
            names = self.registry.message_typedefs(msg_type)[0]["fieldnames"]
            return dict(zip(names, args, strict=False))
        if isinstance(args, dict):
            return args
        return {}

    # --- rosbridge's own topics --------------------------------------------------------------------------

    def add_client_topics(self) -> None:
        """rosbridge's ClientManager: latched ``/client_count`` and ``/connected_clients`` (both lines).

        0.11.17 publishes them latched, the ros2 branch with transient-local QoS; both republish on every
        connect and disconnect.
        """
        ros2 = self.config.dialect == "ros2"
        try:
            count_type = self.registry.resolve("std_msgs/msg/Int32" if ros2 else "std_msgs/Int32", "msg")
            clients_type = self.registry.resolve(
                "rosbridge_msgs/msg/ConnectedClients" if ros2 else "rosbridge_msgs/ConnectedClients", "msg"
            )
        except InterfaceError as exc:
            log.warning("rosbridge's client topics left out: %s", exc)
            return
        self._client_types = (count_type, clients_type)
        for topic, msg_type in (("/client_count", count_type), ("/connected_clients", clients_type)):
            self.graph.add_publisher(ROSBRIDGE_NODE, topic, msg_type)
            self.graph.latched.setdefault(topic, None)
        self._publish_clients()

    def _publish_clients(self) -> None:
        if self._client_types is None:
            return
        count_type, clients_type = self._client_types
        ros2 = self.config.dialect == "ros2"
        clients = []
        for address, since in self._clients.values():
            sec = int(since)
            nsec = int((since - sec) * 1e9)
            stamp = {"sec": sec, "nanosec": nsec} if ros2 else {"secs": sec, "nsecs": nsec}
            clients.append({"ip_address": address, "connection_time": stamp})
        self.publish_json("/connected_clients", clients_type, {"clients": clients})
        self.publish_json("/client_count", count_type, {"data": len(clients)})

    # --- topic traffic ------------------------------------------------------------------------------------

    def publish(self, topic: str, msg_type: str, msg: dict[str, Any], *, source: int = 0) -> None:
        """Route a converted message to the world's subscribers and every subscribed client.

        ROS 1: what subscribers get is what genpy packed and unpacked (see ``ros1_wire``), with the root
        header's ``seq`` set from the publisher's own counter (rospy overwrites it; world publishers and
        rosbridge's count apart, rosbridge's restarts when its publisher of the topic goes).
        """
        if self.config.dialect == "ros1":
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
        if topic in self.graph.latched:
            self.graph.latched[topic] = msg
        outgoing = OutgoingMessage(topic, msg_type, msg, self.registry.to_json)
        for conn in list(self.connections.values()):
            if topic in conn.subscriptions:
                try:
                    conn.deliver(outgoing, self._fragment_id)
                except (ConversionError, InterfaceError) as exc:
                    log.error("cannot send %s on %s: %s", msg_type, topic, exc)
                    return

    def publish_json(self, topic: str, msg_type: str, partial: dict[str, Any]) -> None:
        """Publish a world message given in JSON form (missing fields take defaults)."""
        self.publish(topic, msg_type, self.registry.from_json(msg_type, partial))

    def has_subscribers(self, topic: str) -> bool:
        """Whether any client or world node listens to ``topic`` (lets expensive publishers idle)."""
        return bool(self.graph.local_subscribers.get(topic)) or any(
            topic in c.subscriptions for c in self.connections.values()
        )

    # --- services (used by the op and by the world) -------------------------------------------------------

    async def call(self, name: str, args: Any, timeout_seconds: float) -> dict[str, Any]:
        """Call a service like rosbridge's ``ServiceCaller``; returns the response's wire form.

        ``timeout_seconds`` ≤ 0 waits forever. Raises :class:`CallFailed` with the real server's text.
        """
        # Both lines resolve the name first (rospy's resolve_name; rclpy's expand_topic_name), and the
        # error names the resolved service: 'nope' -> 'Service /nope does not exist'.
        resolved = self.name(name)
        entry = self.graph.services.get(resolved)
        if entry is None:
            raise CallFailed(f"Service {resolved} does not exist")
        try:
            request_type, response_type = self.registry.service_parts(entry.type)
            request = self.registry.from_json(request_type, self._args_dict(request_type, args))
            if self.config.dialect == "ros1":
                # The request travels over TCPROS too: float32 rounded, times canonical.
                request = self.registry.ros1_wire(request_type, request)
        except (InterfaceError, ConversionError) as exc:
            raise CallFailed(str(exc)) from exc
        self.world.count_call(entry.name)
        try:
            async with asyncio.timeout(timeout_seconds if timeout_seconds > 0 else None):
                try:
                    partial = await entry.handler(request)
                except ServiceFailure as exc:
                    if self.config.dialect == "ros1":
                        # Noetic's rospy formats the error bytes with %s, so the text shows b'...' (or
                        # b"..." when it holds a quote): Python's repr of the UTF-8 bytes.
                        if isinstance(exc, HandlerReturnedNone):
                            text = b"service cannot process request: service handler returned None"
                        else:
                            text = f"error processing request: {exc}".encode()
                        raise CallFailed(f"service [{entry.name}] responded with an error: {text!r}") from exc
                    # A ROS 2 service has no error channel: the caller just never hears back.
                    log.error("service %s failed: %s (the caller gets no response)", entry.name, exc)
                    await asyncio.Event().wait()
                    raise AssertionError("unreachable") from exc
        except TimeoutError as exc:
            raise CallFailed("Timeout exceeded while waiting for service response") from exc
        try:
            return self.json_form(response_type, partial)
        except ConversionError as exc:
            log.error("service %s returned a bad response: %s", entry.name, exc)
            raise CallFailed(str(exc)) from exc

    def _forwarding_handler(
        self, owner: int, service: str, service_type: str
    ) -> Callable[[dict[str, Any]], Coroutine[Any, Any, dict[str, Any]]]:
        """A service hosted by a client: forward each call as a server-initiated ``call_service``.

        Request ids count per advertisement (``service_request:/svc:1``, ...): rosbridge's handler class
        starts its ``id_counter`` at 1 and each instance counts on its own (both lines).
        """
        state = self._hosted_services[service] = _HostedService()

        async def forward(request: dict[str, Any]) -> dict[str, Any]:
            if state.closing:
                raise HandlerReturnedNone("the service is being unadvertised")
            request_type, response_type = self.registry.service_parts(service_type)
            request_id = f"service_request:{service}:{next(state.ids)}"
            future: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
            self._service_requests[request_id] = (future, response_type, service)
            try:
                conn = self.connections.get(owner)
                if conn is None:
                    # rosbridge keeps advertised services after their client left; nobody will ever answer.
                    log.warning("service %s: its client has gone; the call will never be answered", service)
                else:
                    args = self.registry.to_json(request_type, request)
                    conn.send({"op": "call_service", "id": request_id, "service": service, "args": args})
                return await future
            finally:
                self._service_requests.pop(request_id, None)

        return forward

    # --- connections --------------------------------------------------------------------------------------

    async def serve_connection(self, ws: ServerConnection) -> None:
        """Run one client connection until it closes, then clean up after it like rosbridge does."""
        self._next_cid += 1
        conn = Connection(
            ws,
            self._next_cid,
            fragment_size=self.config.max_message_size,
            fragment_id=self._fragment_id,
            dumps=dumps_ujson if self.config.dialect == "ros1" else dumps_standard,
        )
        self.connections[conn.id] = conn
        self.connection_count = len(self.connections)
        address = ws.remote_address[0] if ws.remote_address else ""
        self._clients[conn.id] = (str(address), time.time())
        self._publish_clients()
        self.world.notify()
        log.info("client %d connected from %s", conn.id, ws.remote_address)
        writer = asyncio.create_task(conn.writer())
        # The reader is a task of its own: like rosbridge's incoming thread it may sit inside an in-order
        # service call or goal, while the socket's close is noticed (and cleaned up after) at once, as
        # Tornado's on_close does. A reader still blocked finishes its call later; its reply goes nowhere.
        reader = asyncio.create_task(self._read(conn))
        self._readers.add(reader)
        reader.add_done_callback(self._readers.discard)
        closed = asyncio.create_task(ws.wait_closed())
        try:
            await asyncio.wait([reader, closed], return_when=asyncio.FIRST_COMPLETED)
        finally:
            conn.closed = True
            for task in (closed, writer):
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
            self._cleanup(conn)
            del self.connections[conn.id]
            self.connection_count = len(self.connections)
            self._clients.pop(conn.id, None)
            self._publish_clients()
            self.world.notify()
            log.info("client %d disconnected", conn.id)

    def _cleanup(self, conn: Connection) -> None:
        """What rosbridge's ``finish()`` does: drop the client's subscriptions and advertisements.

        Advertised services are kept (rosbridge 0.11 and 2.x do not remove them on disconnect), and goals
        the client sent keep running.
        """
        for topic in list(conn.subscriptions):
            conn.drop_subscription(topic)
            self.graph.remove_subscriber(ROSBRIDGE_NODE, topic)
        for topic in list(conn.advertisements):
            del conn.advertisements[topic]
            self._remove_rosbridge_publisher(topic)

    def _remove_rosbridge_publisher(self, topic: str) -> None:
        """One client's advertisement of ``topic`` is gone; rospy's publisher goes with the last one.

        0.11.17 unregisters that publisher only ``unregister_timeout`` (10 s) later, unless a client
        advertises the topic again meanwhile: until then the master still lists it.
        """
        last = self.graph.node(ROSBRIDGE_NODE).publishes.get(topic, 0) <= 1
        if last and self.config.dialect == "ros1":
            old = self._lingering.pop(topic, None)
            if old is not None:
                old.cancel()
            loop = asyncio.get_running_loop()
            self._lingering[topic] = loop.call_later(
                self.unregister_timeout, self._unregister_publisher, topic
            )
            return
        self.graph.remove_publisher(ROSBRIDGE_NODE, topic)
        if topic not in self.graph.node(ROSBRIDGE_NODE).publishes:
            self._header_seq.pop((True, topic), None)

    def _unregister_publisher(self, topic: str) -> None:
        if self._lingering.pop(topic, None) is None:
            return
        self.graph.remove_publisher(ROSBRIDGE_NODE, topic)
        self._header_seq.pop((True, topic), None)
        self.world.notify()

    def flush_lingering(self) -> None:
        """Unregister every lingering publisher now (the rosbridge process is stopping)."""
        for topic, handle in list(self._lingering.items()):
            handle.cancel()
            self._unregister_publisher(topic)
            self._lingering.pop(topic, None)

    async def _read(self, conn: Connection) -> None:
        try:
            async for raw in conn.ws:
                if conn.closed:
                    break  # cleaned up already: frames still buffered would register things nobody removes
                await self.incoming(conn, raw)
        except ConnectionClosed:
            pass

    def cancel_all(self) -> None:
        """Stop everything running for clients: readers (also those blocked in-order), calls, goals' waits."""
        for task in [*self._readers, *self._tasks]:
            task.cancel()
        for future, _, _ in list(self._service_requests.values()):
            future.cancel()
        self.flush_lingering()

    async def incoming(self, conn: Connection, raw: str | bytes = "") -> None:
        """One frame (or a joined fragment message) from a client, through rosbridge's input buffer.

        ``protocol.incoming`` (identical in 0.11.17 and on the ros2 branch) appends the frame to a
        per-connection buffer, takes the whole buffer if it parses as JSON, else the first ``{...}`` in it
        that parses and has an ``op`` (the text before it is thrown away, the rest kept), and calls itself
        again while something is left that differs from what was left last time. So several objects in one
        frame are all handled, one object split over frames is handled once complete, and garbage waits in
        the buffer until a later frame completes something.
        """
        if conn.dead:
            log.debug("client %d: frame ignored (this connection's reading died earlier)", conn.id)
            conn.frames_ignored += 1
            self.world.notify()
            return
        if isinstance(raw, bytes):
            if self.config.dialect == "ros1":
                # 0.11.17 appends str(payload) of a binary frame, "b'{...}'"; the brace scan finds the object.
                raw = str(raw)
            else:
                try:
                    raw = raw.decode("utf-8")
                except UnicodeDecodeError:
                    log.error("client %d: a binary frame that is not UTF-8 text; ignored", conn.id)
                    return
        conn.buffer += raw
        if len(conn.buffer) > MAX_INPUT_BUFFER:
            # Our own bound: the real buffer grows without limit (and its scan gets slower and slower).
            log.error("client %d: %d characters of unparsable input dropped", conn.id, len(conn.buffer))
            conn.buffer = ""
            return
        while True:
            found, msg = self._take_message(conn)
            if not found:
                return
            try:
                handled = await self.dispatch(conn, msg)
            except _ReadingDied as exc:
                conn.dead = True
                log.error(
                    "client %d: %s - the real server's reading thread dies here; every later frame of this "
                    "connection is ignored (the socket stays open)",
                    conn.id,
                    exc,
                )
                return
            if conn.dead or not handled or not conn.buffer or conn.buffer == conn.old_buffer:
                return
            conn.old_buffer = conn.buffer

    @staticmethod
    def _take_message(conn: Connection) -> tuple[bool, Any]:
        """rosbridge's buffer parse: (whether a message was taken, the message)."""
        text = conn.buffer
        try:
            msg = json.loads(text)
        except ValueError:
            pass
        else:
            conn.buffer = ""
            return msg is not None, msg
        decoder = json.JSONDecoder()
        start = text.find("{")
        while start >= 0:
            # The real server tries every '{' with every '}' after it; the only slice that can parse is the
            # one ending where the object that starts here ends, which is what raw_decode finds.
            try:
                obj, end = decoder.raw_decode(text, start)
            except ValueError:
                start = text.find("{", start + 1)
                continue
            if obj.get("op") is not None:
                conn.buffer = text[end:]
            # An object without an op is handled (and logged) but stays in the buffer, as on the real server.
            return True, obj
        return False, None

    async def dispatch(self, conn: Connection, msg: Any) -> bool:
        """rosbridge's ``protocol.incoming`` after parsing: returns False where it returns early.

        The checks before the op runs are outside the server's error handling: what raises there (a JSON
        value that is not an object, ``png`` without ``msg``, ``message_intervall: null``...) ends the
        connection's reading, modelled by :class:`_ReadingDied`.
        """
        if not isinstance(msg, str | list | dict):
            raise _ReadingDied(f"argument of type {type(msg).__name__!r} is not iterable: {msg!r}")
        mid = None
        if "id" in msg:
            if not isinstance(msg, dict):
                raise _ReadingDied(f"{type(msg).__name__} indices must be integers, got 'id' in {msg!r:.200}")
            mid = msg["id"]
        if "op" not in msg:
            log.error(
                "client %d: Received a message without an op.  All messages require 'op' field with value "
                "one of: %s.  Original message was: %.200s",
                conn.id,
                list(self._ops),
                json.dumps(msg),
            )
            return False
        if not isinstance(msg, dict):
            raise _ReadingDied(f"{type(msg).__name__} indices must be integers, got 'op' in {msg!r:.200}")
        op = msg["op"]
        try:
            handler = self._ops.get(op)
        except TypeError as exc:
            raise _ReadingDied(f"unhashable op {op!r:.200}") from exc
        if handler is None:
            log.error(
                "client %d: Unknown operation: %s.  Allowed operations: %s", conn.id, op, list(self._ops)
            )
            return False
        if "fragment_size" in msg:
            self._set_fragment_size(conn, msg["fragment_size"])
        if "message_intervall" in msg:
            value = msg["message_intervall"]
            # is_number() is float() catching only ValueError: None, lists and objects raise TypeError.
            if value is None or isinstance(value, list | dict):
                raise _ReadingDied(f"float() argument must be a string or a real number: {value!r}")
        if "png" in msg and "msg" not in msg:
            raise _ReadingDied("KeyError: 'msg' (a 'png' key without 'msg')")
        detached = op in ("call_service", "send_action_goal") and not self.config.in_order
        try:
            result = handler(conn, msg)
            if result is None:
                return True
            if detached:
                self._spawn(self._guarded(conn, op, mid, result))
            else:
                await result
        except Exception as exc:
            self._log_failure(conn, op, mid, exc)
        return True

    async def _guarded(self, conn: Connection, op: str, mid: Any, work: Awaitable[None]) -> None:
        try:
            await work
        except Exception as exc:
            self._log_failure(conn, op, mid, exc)

    @staticmethod
    def _log_failure(conn: Connection, op: str, mid: Any, exc: Exception) -> None:
        """rosbridge's protocol catches every exception of an op and only logs ``"<op>: <error>"``."""
        log.error("client %d: %s: %s (id %s)", conn.id, op, exc, mid)
        if not isinstance(exc, OpError):
            log.debug("traceback of that failure", exc_info=exc)

    def _spawn(self, coro: Coroutine[Any, Any, Any]) -> None:
        task = asyncio.create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    def _set_fragment_size(self, conn: Connection, value: Any) -> None:
        """Any message carrying ``fragment_size`` sets it for the whole connection (§4.2).

        The value is kept as sent; :meth:`Connection._fragments` gives it Python's semantics (a string
        breaks every later send on 0.11.17).
        """
        if self.config.dialect == "ros1":
            conn.fragment_size = value
            return
        if value is None or not isinstance(value, int | float):
            # ROS 2 ≥ 2.0.2 / 2.4.0 / 3.0.0 compare it with max_message_size outside the error handling.
            raise _ReadingDied(f"fragment_size must be a number, got {value!r}")
        limit = self.config.max_message_size
        conn.fragment_size = min(value, limit) if limit is not None else value

    def _check_qos(self, msg: dict[str, Any]) -> None:
        """The ROS 2 ``qos`` object (protocol v2.1.0, §5.6): checked, not modelled."""
        qos = msg.get("qos")
        if qos is None or self.config.dialect != "ros2":
            return  # ROS 1 has no qos field: it is ignored like any unknown key
        choices = {
            "history": ("keep_last", "keep_all"),
            "reliability": ("reliable", "best_effort", "best_available"),
            "durability": ("transient_local", "volatile", "best_available"),
        }
        for key, value in qos.items():
            if key in choices and value not in choices[key]:
                raise OpError(f"Invalid QoS {key}: {value!r}")
            if key == "depth" and (not isinstance(value, int) or isinstance(value, bool) or value < 0):
                raise OpError(f"Invalid QoS depth: {value!r}")
            if value == "best_available" and self.config.in_order:
                # Humble's rmw has no best_available policies.
                raise OpError(f"QoS {key} 'best_available' is not supported on Humble")

    def _resolve(self, name: str, kind: Literal["msg", "srv", "action"]) -> str:
        try:
            return self.registry.resolve(name, kind)
        except InterfaceError as exc:
            raise OpError(str(exc)) from exc

    # --- ops ------------------------------------------------------------------------------------------------

    def _hosted(self, conn: Connection, action: str) -> HostedActionServer:
        server = self.graph.actions.get(resolve_name(action))
        if not isinstance(server, HostedActionServer) or server.owner != conn.id:
            raise OpError(f"Action {action} has not been advertised via rosbridge.")
        return server

    def _op_advertise_action(self, conn: Connection, msg: dict[str, Any]) -> None:
        _check(msg, [(True, "action", (str,)), (True, "type", (str,))])
        name = self.name(msg["action"])
        action_type = self._resolve(msg["type"], "action")
        old = self.graph.actions.get(name)
        if old is not None:
            old.remove()
        HostedActionServer(self, name, action_type, conn.id, ROSBRIDGE_NODE)
        self.world.notify()

    def _op_unadvertise_action(self, conn: Connection, msg: dict[str, Any]) -> None:
        _check(msg, [(True, "action", (str,))])
        # Goals still running end ABORTED, as rosbridge's unadvertise_action does.
        self._hosted(conn, msg["action"]).remove()
        self.world.notify()

    def _op_action_feedback(self, conn: Connection, msg: dict[str, Any]) -> None:
        _check(msg, [(True, "action", (str,)), (True, "id", (str,)), (True, "values", (dict,))])
        server = self._hosted(conn, msg["action"])
        _, _, feedback_type = self.registry.action_parts(server.type)
        try:
            self.registry.from_json(feedback_type, msg["values"])
        except ConversionError as exc:
            raise OpError(str(exc)) from exc
        if not server.feedback_from_client(msg["id"], msg["values"]):
            raise OpError(f"Action goal {msg['id']} not found")

    def _op_action_result(self, conn: Connection, msg: dict[str, Any]) -> None:
        _check(
            msg,
            [
                (True, "action", (str,)),
                (True, "id", (str,)),
                (True, "status", (int,)),
                (True, "result", (bool,)),
            ],
        )
        server = self._hosted(conn, msg["action"])
        values = msg.get("values", {})
        if msg["result"]:
            _, result_type, _ = self.registry.action_parts(server.type)
            try:
                self.registry.from_json(result_type, values)
            except ConversionError as exc:
                raise OpError(str(exc)) from exc
        if not server.result_from_client(msg["id"], msg["status"], msg["result"], values):
            raise OpError(f"Action goal {msg['id']} not found")

    def _op_fragment(self, conn: Connection, msg: dict[str, Any]) -> Awaitable[None] | None:
        _check(
            msg,
            [
                (True, "id", (str, int)),
                (True, "data", (str,)),
                (True, "num", (int,)),
                (True, "total", (int,)),
            ],
        )
        now = time.monotonic()
        while self._fragments:
            oldest = next(iter(self._fragments.values()))
            if now - oldest.started < FRAGMENT_TIMEOUT and len(self._fragments) < MAX_FRAGMENT_BUFFERS:
                break
            _, dropped = self._fragments.popitem(last=False)
            self._fragment_bytes -= dropped.size
            log.warning("fragments of an incomplete message dropped (expired or too many)")
        fid = msg["id"]
        buffer = self._fragments.get(fid)
        if buffer is None or msg["num"] == 0:
            if buffer is not None:
                self._fragment_bytes -= buffer.size
            buffer = self._fragments[fid] = _FragmentBuffer(total=msg["total"])
        data: str = msg["data"]
        if self._fragment_bytes + len(data) > MAX_FRAGMENT_BYTES:
            raise OpError("too much fragment data pending; fragment dropped")
        buffer.parts.append(data)
        buffer.size += len(data)
        self._fragment_bytes += len(data)
        if len(buffer.parts) < buffer.total:
            return None
        del self._fragments[fid]
        self._fragment_bytes -= buffer.size
        # Joined in arrival order, as the real server does.
        return self.incoming(conn, "".join(buffer.parts))

    def _op_advertise(self, conn: Connection, msg: dict[str, Any]) -> None:
        fields: list[_FieldSpec] = [
            (True, "topic", (str,)),
            (True, "type", (str,)),
            (False, "latch", (bool,)),
            (False, "queue_size", (int,)),
        ]
        if self.config.dialect == "ros2":
            fields.append((False, "qos", (dict,)))
        _check(msg, fields)
        self._check_qos(msg)
        topic = self.name(msg["topic"])
        msg_type = self._resolve(msg["type"], "msg")
        self._register_publisher(conn, topic, msg_type, msg.get("id"), latch=bool(msg.get("latch", False)))

    def _register_publisher(
        self, conn: Connection, topic: str, msg_type: str, aid: Any, *, latch: bool
    ) -> None:
        existing = self.established_type(topic)
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
                self.graph.add_publisher(ROSBRIDGE_NODE, topic, msg_type)
        if aid not in ids:
            ids.append(aid)
        conn.advertised_types[topic] = msg_type
        if latch:
            self.graph.latched.setdefault(topic, None)

    def _op_unadvertise(self, conn: Connection, msg: dict[str, Any]) -> None:
        _check(msg, [(True, "topic", (str,))])
        topic = self.name(msg["topic"])
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

    def _op_publish(self, conn: Connection, msg: dict[str, Any]) -> None:
        fields: list[_FieldSpec] = [
            (True, "topic", (str,)),
            (False, "latch", (bool,)),
            (False, "queue_size", (int,)),
        ]
        if self.config.dialect == "ros2":
            fields += [(False, "type", (str,)), (False, "qos", (dict,))]
        _check(msg, fields)
        topic = self.name(msg["topic"])
        if topic in conn.advertisements:
            msg_type = conn.advertised_types[topic]
        else:
            graph_type = self.infer_type(msg["topic"])
            if graph_type is not None:
                msg_type = graph_type
            elif self.config.dialect == "ros2" and "type" in msg:
                # ROS 2 2.0.6/2.6.0/3.2.0/4.1.0+ register the topic from the publish's own type.
                msg_type = self._resolve(msg["type"], "msg")
            else:
                raise OpError(f"Cannot infer topic type for topic {msg['topic']} as it is not yet advertised")
            self._register_publisher(
                conn, topic, msg_type, msg.get("id"), latch=bool(msg.get("latch", False))
            )
        if msg.get("latch") is True and self.config.dialect == "ros1":
            # 0.11.17 registers the publisher again with the publish's latch flag: the topic latches.
            self.graph.latched.setdefault(topic, None)
        values = msg.get("msg", {})
        try:
            converted = self.registry.from_json(msg_type, values)
        except ConversionError as exc:
            raise OpError(str(exc)) from exc
        self.world.record_published(PublishedMessage(topic, msg_type, converted, time.monotonic(), conn.id))
        try:
            self.publish(topic, msg_type, converted, source=conn.id)
        except ConversionError as exc:
            raise OpError(str(exc)) from exc

    def _op_subscribe(self, conn: Connection, msg: dict[str, Any]) -> None:
        fields: list[_FieldSpec] = [
            (True, "topic", (str,)),
            (False, "type", (str,)),
            (False, "throttle_rate", (int,)),
            (False, "fragment_size", (int,)),
            (False, "queue_length", (int,)),
            (False, "compression", (str,)),
        ]
        if self.config.dialect == "ros2":
            fields.append((False, "qos", (dict,)))
        _check(msg, fields)
        self._check_qos(msg)
        topic = self.name(msg["topic"])
        graph_type = self.established_type(topic)
        if "type" in msg:
            msg_type = self._resolve(msg["type"], "msg")
            if graph_type is not None and graph_type != msg_type:
                raise OpError(
                    f"Tried to register topic {topic} with type {msg_type} but it is already established "
                    f"with type {graph_type}"
                )
        elif (inferred := self.infer_type(msg["topic"])) is not None:
            msg_type = inferred
        else:
            raise OpError(f"Cannot infer topic type for topic {msg['topic']} as it is not yet advertised")
        compression = msg.get("compression", "none")
        if compression in ("cbor", "cbor-raw"):
            log.warning(
                "client %d: compression %r is not simulated; sending JSON on %s", conn.id, compression, topic
            )
        sid = msg.get("id")
        hash(sid)  # an unhashable id fails here, before anything is registered
        sub = conn.subscriptions.get(topic)
        if sub is None:
            sub = conn.subscriptions[topic] = TopicSubscription(topic, msg["topic"], msg_type)
            self.graph.add_subscriber(ROSBRIDGE_NODE, topic, msg_type)
        sub.by_id[sid] = SubscriptionOptions(
            msg.get("throttle_rate", 0), msg.get("queue_length", 0), compression
        )
        latched = self.graph.latched.get(topic)
        if latched is not None:
            conn.deliver(OutgoingMessage(topic, msg_type, latched, self.registry.to_json), self._fragment_id)

    def _op_unsubscribe(self, conn: Connection, msg: dict[str, Any]) -> None:
        _check(msg, [(True, "topic", (str,))])
        topic = self.name(msg["topic"])
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
            self.graph.remove_subscriber(ROSBRIDGE_NODE, topic)

    async def _op_call_service(self, conn: Connection, msg: dict[str, Any]) -> None:
        fields: list[_FieldSpec] = [
            (True, "service", (str,)),
            (False, "fragment_size", (int, type(None))),
            (False, "compression", (str,)),
        ]
        if self.config.dialect == "ros2":
            fields.append((False, "timeout", (int, float)))
        _check(msg, fields)
        service = msg["service"]
        name, cid = _extract_id(service, msg.get("id"))
        timeout = self.config.default_service_timeout
        if self.config.dialect == "ros2" and "timeout" in msg:
            timeout = float(msg["timeout"])
        reply: dict[str, Any] = {"op": "service_response", "service": service}
        try:
            reply["values"] = await self.call(name, msg.get("args", {}), timeout)
            reply["result"] = True
        except CallFailed as exc:
            log.error("client %d: call_service %s failed: %s", conn.id, service, exc)
            reply["values"] = str(exc)
            reply["result"] = False
        if cid is not None:
            reply["id"] = cid
        conn.send(reply)

    def _op_advertise_service(self, conn: Connection, msg: dict[str, Any]) -> None:
        _check(msg, [(True, "service", (str,)), (True, "type", (str,))])
        name = self.name(msg["service"])
        service_type = self._resolve(msg["type"], "srv")
        self.graph.add_service(
            ServiceEntry(
                name,
                service_type,
                ROSBRIDGE_NODE,
                self._forwarding_handler(conn.id, name, service_type),
                conn.id,
            )
        )
        self.world.notify()

    def _op_unadvertise_service(self, conn: Connection, msg: dict[str, Any]) -> Awaitable[None] | None:
        _check(msg, [(True, "service", (str,))])
        name = self.name(msg["service"])
        entry = self.graph.services.get(name)
        if entry is None or entry.owner != conn.id:
            raise OpError(f"Service {msg['service']} has not been advertised via rosbridge.")
        if self.config.dialect == "ros1":
            return self._unadvertise_service_ros1(name, entry)
        self.graph.remove_service(name)
        # ROS 2 aborts the calls in flight: their callers get an empty (default) response.
        for request_id, (future, _, service) in list(self._service_requests.items()):
            if service == name and not future.done():
                future.set_result({})
                del self._service_requests[request_id]
        self.world.notify()
        return None

    async def _unadvertise_service_ros1(self, name: str, entry: ServiceEntry) -> None:
        """0.11.17's graceful_shutdown: pending and new calls get no response (rospy's 'service handler
        returned None') while the connection's reading busy-waits 1 s; then the service goes."""
        state = self._hosted_services.get(name)
        if state is not None:
            state.closing = True
        for request_id, (future, _, service) in list(self._service_requests.items()):
            if service == name and not future.done():
                future.set_exception(HandlerReturnedNone("the service was unadvertised"))
                del self._service_requests[request_id]
        await asyncio.sleep(UNADVERTISE_SERVICE_WAIT)
        if self.graph.services.get(name) is entry:
            self.graph.remove_service(name)
        self.world.notify()

    def _op_service_response(self, conn: Connection, msg: dict[str, Any]) -> None:
        _check(msg, [(True, "service", (str,)), (False, "id", (str,)), (True, "result", (bool,))])
        pending = self._service_requests.get(msg.get("id", ""))
        if pending is None:
            log.warning(
                "client %d: service_response for an unknown request %r; ignored", conn.id, msg.get("id")
            )
            return
        future, response_type, _ = pending
        values = msg.get("values")
        if not isinstance(values, dict):
            # rosbridge ignores `result` and builds the response from `values`; without them the caller waits.
            raise OpError(f"service_response without a values object; the caller of {msg['service']} waits")
        try:
            self.registry.from_json(response_type, values)
        except ConversionError as exc:
            raise OpError(str(exc)) from exc
        if not future.done():
            future.set_result(values)

    async def _op_send_action_goal(self, conn: Connection, msg: dict[str, Any]) -> None:
        _check(
            msg,
            [
                (True, "action", (str,)),
                (True, "action_type", (str,)),
                (False, "fragment_size", (int, type(None))),
                (False, "compression", (str,)),
            ],
        )
        action = msg["action"]
        name, cid = _extract_id(action, msg.get("id"))
        hash(cid)  # the goal table is keyed by id: an unhashable id fails before anything starts

        def finish(values: Any, status: int, result: bool) -> None:
            reply: dict[str, Any] = {
                "op": "action_result",
                "action": action,
                "values": values,
                "status": status,
                "result": result,
            }
            if cid is not None:
                reply["id"] = cid
            conn.send(reply)

        try:
            action_type = self.registry.resolve(msg["action_type"], "action")
            goal_type, result_type, feedback_type = self.registry.action_parts(action_type)
            goal = self.registry.from_json(goal_type, self._args_dict(goal_type, msg.get("args", {})))
        except (InterfaceError, ConversionError) as exc:
            log.error("client %d: send_action_goal %s: %s", conn.id, action, exc)
            finish(str(exc), 0, False)
            return
        server = self.graph.actions.get(resolve_name(name))
        if server is None or server.type != action_type:
            await asyncio.sleep(ACTION_SERVER_WAIT)
            finish("No action server available", 0, False)
            return

        def on_feedback(partial: dict[str, Any]) -> None:
            reply = {
                "op": "action_feedback",
                "action": action,
                "values": self.json_form(feedback_type, partial),
            }
            if cid is not None:
                reply["id"] = cid
            conn.send(reply)

        handle = server.submit(goal, key=cid, on_feedback=on_feedback if msg.get("feedback", False) else None)
        if handle is None:
            finish("Action goal was rejected", 0, False)
            return
        self.goal_table[cid] = handle
        try:
            status, partial_result = await handle.outcome()
        finally:
            if self.goal_table.get(cid) is handle:
                del self.goal_table[cid]
        finish(self.json_form(result_type, partial_result), status, True)

    def _op_cancel_action_goal(self, conn: Connection, msg: dict[str, Any]) -> None:
        _check(msg, [(True, "action", (str,))])
        _, cid = _extract_id(msg["action"], msg.get("id"))
        handle = self.goal_table.get(cid)
        if handle is not None:
            handle.request_cancel()
