"""Whether a slow service call holds up the next call on its connection, measured on the bridge.

rosbridge_suite 2.x runs a connection's calls in order or each in a thread of its own, as its launch
settings say (2.1.0's defaults and Humble's: in order); rosbridge-server-rs 0.1.6 never holds one up. The
settings of the node named ``/rosbridge_websocket`` are no guide: that node may be another bridge on the same
graph. So it is measured: one connection offers a short-lived ``std_srvs/Trigger`` service of its own, a
second calls it and then ``/rosapi/get_time`` (no other rosapi call); the service answers only after
``get_time`` did, or after *hold* seconds. When ``get_time`` had to wait, the bridge handles a connection's
calls in order. The service is taken away before its connection closes (rosbridge keeps a departed client's
services).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import ssl
import uuid
from collections.abc import Callable, Sequence
from typing import Any, Final

from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import WebSocketException

from rosbridge_mcp_server.client.dialect import Dialect

__all__ = ["PROBE_SERVICE_PREFIX", "call_ordering"]

#: The probe service's name starts so (a person who sees it in the graph can tell whose it is).
PROBE_SERVICE_PREFIX: Final = "/rosbridge_mcp_check_"
#: How long the probe's service holds its caller by default: far above a rosapi round trip (3-100 ms on
#: the labs).
HOLD_SECONDS: Final = 1.0
#: How long the probe waits for the bridge to confirm its service is gone.
_UNADVERTISE_SECONDS: Final = 3.0
#: At most this many unawaited frames are kept per connection (the bridge may publish; ours are few).
_KEPT_FRAMES: Final = 64
#: How often the probe calls its service before giving up (the bridge may not reach it at once).
_CALL_ATTEMPTS: Final = 20


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
    srv_type = Dialect.for_version(version).service_type("std_srvs/Trigger")
    options: dict[str, Any] = {"compression": None, "proxy": None, "open_timeout": timeout}
    if ssl_context is not None:
        options["ssl"] = ssl_context
    if headers:
        options["additional_headers"] = list(headers)
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    failure: BaseException | None = None
    async with asyncio.timeout_at(deadline):
        async with connect(url, **options) as host_ws, connect(url, **options) as caller_ws:
            host, caller = _Frames(host_ws), _Frames(caller_ws)
            # Failures are caught inside, so both sockets close politely (an exception leaving `async with`
            # closes them with 1011, which a bridge may log as an error of its own).
            try:
                await host.send({"op": "advertise_service", "service": name, "type": srv_type})
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


async def _measure(host: _Frames, caller: _Frames, name: str, hold: float) -> bool:
    # A reply on the host's own connection says its advertisement was handled (both lines handle a
    # connection's ops in turn); the caller may still find the service missing for a moment: then again.
    await host.send({"op": "call_service", "id": "advertised", "service": "/rosapi/get_time"})
    await host.next(_with_id("advertised"))
    for attempt in range(_CALL_ATTEMPTS):
        slow, fast = f"slow-{attempt}", f"fast-{attempt}"
        for rid, service in ((slow, name), (fast, "/rosapi/get_time")):
            await caller.send({"op": "call_service", "id": rid, "service": service})
        hosted = asyncio.ensure_future(host.next(lambda f: f.get("op") == "call_service"))
        refused = asyncio.ensure_future(caller.next(_with_id(slow)))
        done, _ = await asyncio.wait({hosted, refused}, return_when=asyncio.FIRST_COMPLETED)
        # Cancelling recv() loses no frame (websockets keeps it for the next recv()).
        for task in (hosted, refused):
            if task not in done:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
        if hosted in done:
            request = hosted.result()
            break
        await caller.next(_with_id(fast))
        await asyncio.sleep(0.05)
    else:
        raise LookupError(f"the bridge never reached the probe's service {name}")
    try:
        async with asyncio.timeout(hold):
            await caller.next(_with_id(fast))
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
    await host.send(response)
    await caller.next(_with_id(slow))
    return queued


async def _unadvertise(host: _Frames, name: str) -> None:
    """Take the probe's service away for good before the connection closes.

    Both rosbridge 0.11.17 and 2.1.0 keep a client's advertised services after it disconnects (a call to one
    never gets an answer), and both drop the frames of a connection they have not handled yet when it
    closes: an ``unadvertise_service`` sent just before the close can be lost on a busy bridge (0.11.17's
    takes 1 s, so one is always busy there). A reply to a call sent after it on the same connection proves
    it was handled.
    """
    try:
        await host.send({"op": "unadvertise_service", "service": name})
        barrier = {"op": "call_service", "id": "unadvertised", "service": "/rosapi/get_time"}
        await host.send(barrier)
        async with asyncio.timeout(_UNADVERTISE_SECONDS):
            await host.next(_with_id("unadvertised"))
    except (TimeoutError, WebSocketException, OSError):
        pass  # the probe's own outcome (or failure) is what matters


class _Frames:
    """One probe socket: frames read while waiting for another one are kept for a later wait, not lost."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        self._kept: list[dict[str, Any]] = []

    async def send(self, op: dict[str, Any]) -> None:
        await self.ws.send(json.dumps(op))

    async def next(self, wanted: Callable[[dict[str, Any]], bool]) -> dict[str, Any]:
        """The next frame that ``wanted`` accepts."""
        for index, frame in enumerate(self._kept):
            if wanted(frame):
                del self._kept[index]
                return frame
        while True:
            frame = json.loads(await self.ws.recv())
            if not isinstance(frame, dict):
                continue
            if wanted(frame):
                return frame
            if len(self._kept) < _KEPT_FRAMES:
                self._kept.append(frame)


def _with_id(rid: str) -> Callable[[dict[str, Any]], bool]:
    return lambda frame: frame.get("id") == rid
