"""rosbridge's service capabilities: ``call_service`` (its ``ServiceCaller``), and services hosted by clients
(``advertise_service``, ``unadvertise_service``, ``service_response``)."""

from __future__ import annotations

import asyncio
import itertools
import logging
from collections.abc import Awaitable, Callable, Coroutine
from dataclasses import dataclass, field
from typing import Any

from rosbridge_mcp_server.sim.bridge.core import (
    RS_NOT_IN_GRAPH,
    BridgeCore,
    CallFailed,
    Capability,
    FieldSpec,
    OpError,
    OpHandler,
    check_fields,
    extract_id,
)
from rosbridge_mcp_server.sim.connection import Connection
from rosbridge_mcp_server.sim.graph import ROSBRIDGE_NODE, HandlerReturnedNone, ServiceEntry, ServiceFailure
from rosbridge_mcp_server.sim.interfaces import ConversionError, InterfaceError

__all__ = ["UNADVERTISE_SERVICE_WAIT", "Services"]

log = logging.getLogger("rosbridge_mcp_server.sim")

#: 0.11.17 unadvertise_service: graceful_shutdown(timeout=1.0) busy-waits this long before the service goes.
UNADVERTISE_SERVICE_WAIT = 1.0


@dataclass
class _HostedService:
    """One client advertisement of a service: its request counter and whether it is going away."""

    ids: itertools.count[int] = field(default_factory=lambda: itertools.count(1))
    closing: bool = False


class Services(Capability):
    """Calls into the graph, and the services clients host through the bridge."""

    def __init__(self, core: BridgeCore) -> None:
        super().__init__(core)
        #: request id -> (the caller's future, response type, service name)
        self._requests: dict[str, tuple[asyncio.Future[dict[str, Any]], str, str]] = {}
        self._hosted: dict[str, _HostedService] = {}

    def ops(self) -> dict[str, OpHandler]:
        return {
            "call_service": self.call_service,
            "advertise_service": self.advertise_service,
            "unadvertise_service": self.unadvertise_service,
            "service_response": self.service_response,
        }

    # --- calling ------------------------------------------------------------------------------------------

    async def call(self, name: str, args: Any, timeout_seconds: float) -> dict[str, Any]:
        """Call a service like rosbridge's ``ServiceCaller``; returns the response's wire form.

        ``timeout_seconds`` ≤ 0 waits forever. Raises :class:`CallFailed` with the real server's text.
        """
        core = self.core
        # Both lines resolve the name first (rospy's resolve_name; rclpy's expand_topic_name), and the
        # error names the resolved service: 'nope' -> 'Service /nope does not exist'.
        resolved = core.name(name)
        entry = core.graph.services.get(resolved)
        if entry is None:
            raise CallFailed(RS_NOT_IN_GRAPH if core.config.rs else f"Service {resolved} does not exist")
        try:
            request_type, response_type = core.registry.service_parts(entry.type)
            request = core.registry.from_json(request_type, core.args_dict(request_type, args))
            if not core.ros2:
                # The request travels over TCPROS too: float32 rounded, times canonical.
                request = core.registry.ros1_wire(request_type, request)
        except (InterfaceError, ConversionError) as exc:
            core.world.count_refused(entry.name)
            raise CallFailed(str(exc)) from exc
        core.world.count_call(entry.name)
        try:
            async with asyncio.timeout(timeout_seconds if timeout_seconds > 0 else None):
                try:
                    partial = await entry.handler(request)
                except ServiceFailure as exc:
                    if not core.ros2:
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
            return core.json_form(response_type, partial)
        except ConversionError as exc:
            log.error("service %s returned a bad response: %s", entry.name, exc)
            raise CallFailed(str(exc)) from exc

    async def call_service(self, conn: Connection, msg: dict[str, Any]) -> None:
        fields: list[FieldSpec] = [
            (True, "service", (str,)),
            (False, "fragment_size", (int, type(None))),
            (False, "compression", (str,)),
        ]
        honours_timeout = self.core.ros2 and self.core.config.timeout_field
        if honours_timeout:
            fields.append((False, "timeout", (int, float)))
        check_fields(msg, fields)
        service = msg["service"]
        name, cid = extract_id(service, msg.get("id"))
        timeout = self.core.config.default_service_timeout
        if honours_timeout and "timeout" in msg:
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

    # --- services hosted by clients -----------------------------------------------------------------------

    def advertise_service(self, conn: Connection, msg: dict[str, Any]) -> None:
        check_fields(msg, [(True, "service", (str,)), (True, "type", (str,))])
        name = self.core.name(msg["service"])
        service_type = self.core.resolve_type(msg["type"], "srv")
        handler = self._forwarding_handler(conn.id, name, service_type)
        self.core.graph.add_service(ServiceEntry(name, service_type, ROSBRIDGE_NODE, handler, conn.id))
        self.core.world.notify()

    def _forwarding_handler(
        self, owner: int, service: str, service_type: str
    ) -> Callable[[dict[str, Any]], Coroutine[Any, Any, dict[str, Any]]]:
        """A service hosted by a client: forward each call as a server-initiated ``call_service``.

        Request ids count per advertisement (``service_request:/svc:1``, ...): rosbridge's handler class
        starts its ``id_counter`` at 1 and each instance counts on its own (both lines).
        """
        state = self._hosted[service] = _HostedService()
        core = self.core

        async def forward(request: dict[str, Any]) -> dict[str, Any]:
            if state.closing:
                raise HandlerReturnedNone("the service is being unadvertised")
            request_type, response_type = core.registry.service_parts(service_type)
            request_id = f"service_request:{service}:{next(state.ids)}"
            future: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
            self._requests[request_id] = (future, response_type, service)
            try:
                args = core.registry.to_json(request_type, request)
                frame = {"op": "call_service", "id": request_id, "service": service, "args": args}
                if not core.send_to_client(owner, frame):
                    # rosbridge keeps advertised services after their client left; nobody will ever answer.
                    log.warning("service %s: its client has gone; the call will never be answered", service)
                return await future
            finally:
                self._requests.pop(request_id, None)

        return forward

    def unadvertise_service(self, conn: Connection, msg: dict[str, Any]) -> Awaitable[None] | None:
        check_fields(msg, [(True, "service", (str,))])
        name = self.core.name(msg["service"])
        entry = self.core.graph.services.get(name)
        if entry is None or entry.owner != conn.id:
            raise OpError(f"Service {msg['service']} has not been advertised via rosbridge.")
        if not self.core.ros2:
            return self._unadvertise_ros1(name, entry)
        self.core.graph.remove_service(name)
        # ROS 2 aborts the calls in flight: their callers get an empty (default) response.
        for request_id, (future, _, service) in list(self._requests.items()):
            if service == name and not future.done():
                future.set_result({})
                del self._requests[request_id]
        self.core.world.notify()
        return None

    async def _unadvertise_ros1(self, name: str, entry: ServiceEntry) -> None:
        """0.11.17's graceful_shutdown: pending and new calls get no response (rospy's 'service handler
        returned None') while the connection's reading busy-waits 1 s; then the service goes."""
        state = self._hosted.get(name)
        if state is not None:
            state.closing = True
        for request_id, (future, _, service) in list(self._requests.items()):
            if service == name and not future.done():
                future.set_exception(HandlerReturnedNone("the service was unadvertised"))
                del self._requests[request_id]
        await asyncio.sleep(UNADVERTISE_SERVICE_WAIT)
        if self.core.graph.services.get(name) is entry:
            self.core.graph.remove_service(name)
        self.core.world.notify()

    def service_response(self, conn: Connection, msg: dict[str, Any]) -> None:
        check_fields(msg, [(True, "service", (str,)), (False, "id", (str,)), (True, "result", (bool,))])
        pending = self._requests.get(msg.get("id", ""))
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
            self.core.registry.from_json(response_type, values)
        except ConversionError as exc:
            raise OpError(str(exc)) from exc
        if not future.done():
            future.set_result(values)

    def shutdown(self) -> None:
        for future, _, _ in list(self._requests.values()):
            future.cancel()
