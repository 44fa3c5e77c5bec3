"""Whether a slow service call holds up the next call on its connection, measured on the bridge.

rosbridge_suite 2.x runs a connection's calls in order or each in a thread of its own, as its launch
settings say (2.1.0's defaults and Humble's: in order); rosbridge-server-rs 0.1.6 never holds one up. The
settings of the node named ``/rosbridge_websocket`` are no guide: that node may be another bridge on the same
graph. So it is measured: one connection offers a short-lived ``std_srvs/Trigger`` service of its own, a
second calls it and then ``/rosapi/get_time`` (no other rosapi call); the service answers only after
``get_time`` did, or after *hold* seconds. When ``get_time`` had to wait, the bridge handles a connection's
calls in order. The service is taken away before its connection closes (rosbridge keeps a departed client's
services). Both connections are the client's own kind (:class:`Connection`, opened through the client's
transport), so replies are matched by id as everywhere else.
"""

from __future__ import annotations

import asyncio
import contextlib
import ssl
import uuid
from collections.abc import Sequence
from typing import Any, Final

from rosbridge_mcp_server.client.connection import Connection, GoalStream, open_connection
from rosbridge_mcp_server.client.dialect import Dialect
from rosbridge_mcp_server.client.transport import Dial, websocket_dial
from rosbridge_mcp_server.errors import RosbridgeError

__all__ = ["PROBE_SERVICE_PREFIX", "call_ordering"]

#: The probe service's name starts so (a person who sees it in the graph can tell whose it is).
PROBE_SERVICE_PREFIX: Final = "/rosbridge_mcp_check_"
#: How long the probe's service holds its caller by default: far above a rosapi round trip (3-100 ms on
#: the labs).
HOLD_SECONDS: Final = 1.0
#: How long the probe waits for the bridge to confirm its service is gone.
_UNADVERTISE_SECONDS: Final = 3.0
#: The same wait while the probe is being cancelled (the client is closing): a bridge that answers at all
#: answers within milliseconds, and close() must not wait long on one that does not.
_CANCELLED_UNADVERTISE_SECONDS: Final = 1.0
#: How often the probe calls its service before giving up (the bridge may not reach it at once).
_CALL_ATTEMPTS: Final = 20
_GET_TIME: Final = "/rosapi/get_time"
#: The probe's replies wait no deadline of their own: the whole probe's bounds them.
_UNBOUNDED: Final = 3600.0


async def call_ordering(
    url: str,
    version: int,
    timeout: float,
    *,
    hold: float = HOLD_SECONDS,
    ssl_context: ssl.SSLContext | None = None,
    headers: Sequence[tuple[str, str]] = (),
    dial: Dial | None = None,
) -> bool:
    """True when a slow call held up the next one on its connection (see the module's docstring).

    The connections open through *dial* (the client's transport), else as WebSockets to *url* with
    ``ssl_context`` and ``headers``. Raises :class:`RosbridgeError`, ``TimeoutError`` or ``LookupError`` when
    the probe cannot run (no ``std_srvs`` on the robot, a bridge that cannot host services, no rosapi).
    """
    name = f"{PROBE_SERVICE_PREFIX}{uuid.uuid4().hex[:8]}"
    srv_type = Dialect.for_version(version).service_type("std_srvs/Trigger")
    dial = dial or websocket_dial(url, ssl_context=ssl_context, headers=headers)
    deadline = asyncio.get_running_loop().time() + timeout
    failure: BaseException | None = None
    connections: list[Connection] = []
    try:
        async with asyncio.timeout_at(deadline):
            connections.append(await open_connection(dial, url, "ordering probe host", timeout))
            connections.append(await open_connection(dial, url, "ordering probe caller", timeout))
            host, caller = connections
            # Failures are caught inside, so both connections close politely (a socket dropped without a
            # close frame may be logged by the bridge as an error of its own).
            try:
                calls = host.host(name, f"calls of {name}")
                await host.send({"op": "advertise_service", "service": name, "type": srv_type})
                try:
                    async with asyncio.timeout_at(deadline - _UNADVERTISE_SECONDS / 3):
                        queued = await _measure(host, caller, calls, name, hold)
                finally:
                    await _unadvertise(host, name)
            except (TimeoutError, LookupError, ValueError, RosbridgeError) as exc:
                failure = exc
            await asyncio.gather(*(conn.aclose() for conn in connections))
    except BaseException:
        # Cancelled (the client is closing) or past the deadline: the connections go at once. A closing
        # handshake waits for the bridge's close frame, which a bridge that stopped reading never delivers.
        for conn in connections:
            conn.transport.abort()
        raise
    if failure is not None:
        raise failure
    return queued


async def _measure(host: Connection, caller: Connection, calls: GoalStream, name: str, hold: float) -> bool:
    # A reply on the host's own connection says its advertisement was handled (both lines handle a
    # connection's ops in turn); the caller may still find the service missing for a moment: then again.
    barrier = _call("advertised", _GET_TIME)
    await host.request("advertised", barrier, "the advertisement's barrier", _UNBOUNDED)
    for attempt in range(_CALL_ATTEMPTS):
        slow, fast = f"slow-{attempt}", f"fast-{attempt}"
        slow_reply = caller.expect(slow, f"the probe's call of {name}", _UNBOUNDED)
        fast_reply = caller.expect(fast, "the probe's get_time", _UNBOUNDED)
        try:
            await caller.send(_call(slow, name))
            await caller.send(_call(fast, _GET_TIME))
            hosted = asyncio.ensure_future(calls.next())
            either: set[asyncio.Future[Any]] = {hosted, slow_reply}
            try:
                done, _ = await asyncio.wait(either, return_when=asyncio.FIRST_COMPLETED)
            finally:
                if not hosted.done():
                    hosted.cancel()
                    with contextlib.suppress(asyncio.CancelledError):
                        await hosted
            if hosted in done:
                return await _answer(host, name, hosted.result()[1], (slow_reply, fast_reply), hold)
            await fast_reply
        finally:
            caller.forget(slow)
            caller.forget(fast)
        await asyncio.sleep(0.05)
    raise LookupError(f"the bridge never reached the probe's service {name}")


async def _answer(
    host: Connection,
    name: str,
    request: dict[str, Any],
    replies: tuple[asyncio.Future[dict[str, Any]], asyncio.Future[dict[str, Any]]],
    hold: float,
) -> bool:
    """The service holds its caller: did ``get_time`` answer meanwhile? Then answer the held call."""
    slow_reply, fast_reply = replies
    done, _ = await asyncio.wait({fast_reply}, timeout=hold)
    queued = not done
    answer = {"success": True, "message": "rosbridge-mcp-server probe"}
    response = {"op": "service_response", "id": request.get("id"), "service": name, "result": True}
    await host.send({**response, "values": answer})
    await slow_reply
    return queued


async def _unadvertise(host: Connection, name: str) -> None:
    """Take the probe's service away for good before the connection closes.

    Both rosbridge 0.11.17 and 2.1.0 keep a client's advertised services after it disconnects (a call to one
    never gets an answer), and both drop the frames of a connection they have not handled yet when it
    closes: an ``unadvertise_service`` sent just before the close can be lost on a busy bridge (0.11.17's
    takes 1 s, so one is always busy there). A reply to a call sent after it on the same connection proves
    it was handled. While the probe is being cancelled (the client is closing) that reply is awaited only
    briefly: without it, a real Jazzy 2.1.0 kept the service of a probe cancelled mid-way.
    """
    task = asyncio.current_task()
    cancelled = task is not None and task.cancelling() > 0
    wait = _CANCELLED_UNADVERTISE_SECONDS if cancelled else _UNADVERTISE_SECONDS
    try:
        await host.send({"op": "unadvertise_service", "service": name})
        barrier = _call("unadvertised", _GET_TIME)
        await host.request("unadvertised", barrier, "the unadvertise's barrier", wait)
    except (TimeoutError, RosbridgeError):
        pass  # the probe's own outcome (or failure, or cancellation) is what matters


def _call(rid: str, service: str) -> dict[str, Any]:
    return {"op": "call_service", "id": rid, "service": service}
