"""Whether a slow service call holds up the next call on its connection, measured on the bridge.

rosbridge_suite 2.x runs a connection's calls in order or each in a thread of its own, as its launch
settings say (2.1.0's defaults and Humble's: in order); rosbridge-server-rs 0.1.6 never holds one up. The
settings of the node named ``/rosbridge_websocket`` are no guide: that node may be another bridge on the same
graph. So it is measured: one connection offers a short-lived ``std_srvs/Trigger`` service of its own, a
second calls it and then ``/rosapi/get_time``; the service answers only after ``get_time`` did, or after
*hold* seconds. When ``get_time`` had to wait, the bridge handles a connection's calls in order. The service
is taken away before its connection closes (rosbridge keeps a departed client's services).
"""

from __future__ import annotations

import asyncio
import json
import ssl
import uuid
from collections.abc import Callable, Sequence
from typing import Any, Final

from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import WebSocketException

from rosbridge_mcp_server.wire.dialect import normalize_type

__all__ = ["PROBE_SERVICE_PREFIX", "call_ordering"]

#: The probe service's name starts so (a person who sees it in the graph can tell whose it is).
PROBE_SERVICE_PREFIX: Final = "/rosbridge_mcp_check_"
#: How long the probe's service holds its caller by default: far above a rosapi round trip (3-100 ms on
#: the labs).
HOLD_SECONDS: Final = 1.0
#: How long the probe waits for the bridge to confirm its service is gone.
_UNADVERTISE_SECONDS: Final = 3.0
#: How often the probe asks rosapi whether its service is listed yet (every 50 ms).
_LISTED_ATTEMPTS: Final = 40


async def call_ordering(
    url: str,
    version: int,
    timeout: float,
    *,
    hold: float = HOLD_SECONDS,
    ssl_context: ssl.SSLContext | None = None,
    headers: Sequence[tuple[str, str]] = (),
) -> bool:
    """True when a slow call held up the next one on its connection (see the module's docstring).

    Raises :class:`WebSocketException`, ``TimeoutError`` or ``OSError`` when the probe cannot run (no
    ``std_srvs`` on the robot, a bridge that cannot host services, no rosapi).
    """
    name = f"{PROBE_SERVICE_PREFIX}{uuid.uuid4().hex[:8]}"
    srv_type = normalize_type("std_srvs/Trigger", version, "srv")
    options: dict[str, Any] = {"compression": None, "proxy": None, "open_timeout": timeout}
    if ssl_context is not None:
        options["ssl"] = ssl_context
    if headers:
        options["additional_headers"] = list(headers)
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    failure: BaseException | None = None
    async with asyncio.timeout_at(deadline):
        async with connect(url, **options) as host, connect(url, **options) as caller:
            # Failures are caught inside, so both sockets close politely (an exception leaving `async with`
            # closes them with 1011, which a bridge may log as an error of its own).
            try:
                await host.send(json.dumps({"op": "advertise_service", "service": name, "type": srv_type}))
                try:
                    async with asyncio.timeout_at(deadline - _UNADVERTISE_SECONDS / 3):
                        queued = await _measure(host, caller, name, hold)
                finally:
                    await _unadvertise(host, name)
            except (TimeoutError, LookupError, ValueError, WebSocketException) as exc:
                failure = exc
    if failure is not None:
        raise failure
    return queued


async def _measure(host: ClientConnection, caller: ClientConnection, name: str, hold: float) -> bool:
    await _wait_listed(caller, name)
    for rid, service in (("slow", name), ("fast", "/rosapi/get_time")):
        await caller.send(json.dumps({"op": "call_service", "id": rid, "service": service}))
    request = await _next(host, lambda f: f.get("op") == "call_service")
    try:
        async with asyncio.timeout(hold):
            await _next(caller, _with_id("fast"))
        queued = False
    except TimeoutError:
        queued = True
    answer = {"success": True, "message": "rosbridge-mcp-server probe"}
    response = {
        "op": "service_response",
        "id": request.get("id"),
        "service": name,
        "result": True,
        "values": answer,
    }
    await host.send(json.dumps(response))
    await _next(caller, _with_id("slow"))
    return queued


async def _unadvertise(host: ClientConnection, name: str) -> None:
    """Take the probe's service away for good before the connection closes.

    Both rosbridge 0.11.17 and 2.1.0 keep a client's advertised services after it disconnects (a call to one
    never gets an answer), and both drop the frames of a connection they have not handled yet when it
    closes: an ``unadvertise_service`` sent just before the close can be lost on a busy bridge (0.11.17's
    takes 1 s, so one is always busy there). A reply to a call sent after it on the same connection proves
    it was handled.
    """
    try:
        await host.send(json.dumps({"op": "unadvertise_service", "service": name}))
        barrier = {"op": "call_service", "id": "unadvertised", "service": "/rosapi/get_time"}
        await host.send(json.dumps(barrier))
        async with asyncio.timeout(_UNADVERTISE_SECONDS):
            await _next(host, _with_id("unadvertised"))
    except (TimeoutError, WebSocketException, OSError):
        pass  # the probe's own outcome (or failure) is what matters


async def _next(ws: ClientConnection, wanted: Callable[[dict[str, Any]], bool]) -> dict[str, Any]:
    """The next frame on ``ws`` that ``wanted`` accepts (others are skipped)."""
    while True:
        frame = json.loads(await ws.recv())
        if isinstance(frame, dict) and wanted(frame):
            return frame


def _with_id(rid: str) -> Callable[[dict[str, Any]], bool]:
    return lambda frame: frame.get("id") == rid


async def _wait_listed(ws: ClientConnection, service: str) -> None:
    """Until rosapi lists ``service`` (the bridge registers an advertised service with the graph first)."""
    for attempt in range(_LISTED_ATTEMPTS):
        rid = f"listed-{attempt}"
        args = {"service": service}
        await ws.send(
            json.dumps({"op": "call_service", "id": rid, "service": "/rosapi/service_type", "args": args})
        )
        reply = await _next(ws, _with_id(rid))
        values = reply.get("values")
        if isinstance(values, dict) and values.get("type"):
            return
        await asyncio.sleep(0.05)
    raise LookupError(f"the bridge never listed the probe's service {service}")
