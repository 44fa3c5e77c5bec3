"""A deliberately dumb rosbridge client for protocol tests: raw JSON frames over a real WebSocket.

Silence is checked with a barrier, never a timer: after the frames under test, send a request that always
gets a reply (``/rosapi/get_time``) and collect what arrives before that reply. The server handles one
connection's frames in order, so anything the frames under test caused would come first.
"""

from __future__ import annotations

import asyncio
import itertools
import json
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

from websockets.asyncio.client import ClientConnection, connect

if TYPE_CHECKING:
    from rosbridge_mcp_server.sim import SimulatedRobot

__all__ = ["MakeSim", "RawClient"]

#: The ``make_sim`` fixture of ``tests/conftest.py``.
MakeSim = Callable[..., Awaitable["SimulatedRobot"]]

_ids = itertools.count(1)
WAIT = 30.0


class RawClient:
    """One WebSocket to the simulated robot, with helpers to send ops and await replies."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        #: Frames read while looking for something else (in arrival order).
        self.backlog: list[dict[str, Any]] = []

    @classmethod
    async def open(cls, url: str) -> RawClient:
        """Connect to ``url``."""
        return cls(await connect(url, max_size=None, open_timeout=30))

    async def close(self) -> None:
        """Close the socket."""
        await self.ws.close()

    async def __aenter__(self) -> RawClient:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def send(self, message: dict[str, Any] | str) -> None:
        """Send one op (a dict) or a raw text frame."""
        await self.ws.send(message if isinstance(message, str) else json.dumps(message))

    async def recv(self, wait: float = WAIT) -> dict[str, Any]:
        """The next frame as JSON (from the backlog first)."""
        if self.backlog:
            return self.backlog.pop(0)
        return dict(json.loads(await asyncio.wait_for(self.ws.recv(), wait)))

    async def recv_until(self, predicate: Any, wait: float = WAIT) -> dict[str, Any]:
        """The first frame matching ``predicate``; others are kept in the backlog."""
        skipped: list[dict[str, Any]] = []
        async with asyncio.timeout(wait):
            for index, frame in enumerate(self.backlog):
                if predicate(frame):
                    del self.backlog[index]
                    return frame
            while True:
                frame = dict(json.loads(await self.ws.recv()))
                if predicate(frame):
                    self.backlog.extend(skipped)
                    return frame
                skipped.append(frame)

    async def reply(self, request_id: str, *, op: str | None = None, wait: float = WAIT) -> dict[str, Any]:
        """The reply carrying ``request_id`` (``action_feedback`` is skipped unless ``op`` asks for it)."""
        return await self.recv_until(
            lambda f: (
                f.get("id") == request_id and (f.get("op") == op if op else f.get("op") != "action_feedback")
            ),
            wait,
        )

    async def call(
        self, service: str, args: Any = None, *, wait: float = WAIT, **extra: Any
    ) -> dict[str, Any]:
        """``call_service`` (``extra`` fields added to the op) and its ``service_response``."""
        request_id = f"call:{service}:{next(_ids)}"
        message: dict[str, Any] = {"op": "call_service", "id": request_id, "service": service, **extra}
        if args is not None:
            message["args"] = args
        await self.send(message)
        return await self.reply(request_id, wait=wait)

    async def values(self, service: str, args: Any = None) -> dict[str, Any]:
        """Call a service that must succeed; its response values."""
        response = await self.call(service, args)
        assert response["result"] is True, response
        return dict(response["values"])

    async def frames_before_barrier(self) -> list[dict[str, Any]]:
        """Every frame that arrives before the reply to a barrier request sent now."""
        barrier = f"barrier:{next(_ids)}"
        await self.send({"op": "call_service", "id": barrier, "service": "/rosapi/get_time"})
        before = list(self.backlog)
        self.backlog.clear()
        async with asyncio.timeout(WAIT):
            while True:
                frame = dict(json.loads(await self.ws.recv()))
                if frame.get("id") == barrier:
                    return before
                before.append(frame)

    async def next_publish(self, topic: str, wait: float = WAIT) -> dict[str, Any]:
        """The next ``publish`` frame on ``topic``."""
        return await self.recv_until(lambda f: f.get("op") == "publish" and f.get("topic") == topic, wait)
