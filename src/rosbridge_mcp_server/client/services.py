"""Service calls: the one request path, and the pool of single-call lanes for in-order bridges."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from rosbridge_mcp_server.client.connection import Connection
from rosbridge_mcp_server.client.lanes import LanePool
from rosbridge_mcp_server.errors import RequestTimeoutError, ServiceError
from rosbridge_mcp_server.wire import protocol

__all__ = ["bridge_timeout", "call_on", "call_on_lane"]

Args = dict[str, Any] | list[Any] | None


async def call_on(
    conn: Connection,
    ids: protocol.IdMinter,
    service: str,
    args: Args,
    timeout: float,
    *,
    bridge_timeout: float | None,
) -> Any:
    """Call *service* on *conn*; its response fields, or :class:`ServiceError` with the bridge's text.

    Every service call goes through here. It is the hot path a benchmark holds to a raw websockets round trip,
    so it stays flat: one coroutine frame above ``Connection.request``.
    """
    rid = ids.mint("call_service", service)
    op = protocol.call_service(service, args, id=rid, timeout=bridge_timeout)
    reply = await conn.request(rid, op, "service " + service, timeout)
    if reply.get("result") is not True:
        if reply.get("op") == "status":
            # rosbridge-server-rs refuses a call with an error status rather than a service_response.
            raise ServiceError(service, str(reply.get("msg")))
        if reply.get("result") is False:
            values = reply.get("values")
            raise ServiceError(service, values if isinstance(values, str) else repr(values))
    return reply.get("values")


async def call_on_lane(
    lanes: LanePool,
    ids: protocol.IdMinter,
    service: str,
    args: Args,
    timeout: float,
    *,
    send_timeout: bool,
    check: Callable[[], None] | None = None,
) -> Any:
    """Call *service* on a lane of its own (a bridge that handles one connection in order, or on request);
    *check* is called once the lane is there, right before the call is written."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    what = f"service {service}"
    lane = await lanes.acquire(deadline, what, timeout)
    reusable = False
    try:
        if check is not None:
            reusable = True  # nothing was sent on it
            check()
            reusable = False
        remaining = max(deadline - loop.time(), 0.001)
        try:
            values = await call_on(
                lane,
                ids,
                service,
                args,
                remaining,
                bridge_timeout=bridge_timeout(remaining) if send_timeout else None,
            )
        except RequestTimeoutError:
            raise RequestTimeoutError(what, timeout, "The bridge answers many errors with silence.") from None
        except ServiceError:
            reusable = True
            raise
        reusable = True
    finally:
        lanes.release(lane, reusable)
    return values


def bridge_timeout(deadline_in: float) -> float:
    """The ``timeout`` field for a call we give up on after *deadline_in* seconds.

    Slightly shorter than our own deadline, so a ROS 2 bridge (Humble 2.0.1+, Jazzy 2.2.0+) gives up
    first and its own text ("Timeout exceeded while waiting for service response") reaches the
    user, telling them the bridge is alive and the service is what is slow.
    """
    return max(deadline_in - min(0.25, deadline_in * 0.1), 0.001)
