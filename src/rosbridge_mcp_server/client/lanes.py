"""Pooled single-call lanes: extra WebSockets for bridges that handle one connection in order.

Humble's rosbridge (2.0.x defaults) runs a connection's service calls and goals inside its one
incoming thread, so a slow call on the shared connection would freeze every other caller. A lane
carries one call at a time; idle lanes are reused for a while, then closed. A lane whose call
timed out or was cancelled is closed, not reused: the bridge may still be busy with it.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable

from rosbridge_mcp_server.client.connection import Connection
from rosbridge_mcp_server.errors import RequestTimeoutError

__all__ = ["LanePool"]

logger = logging.getLogger("rosbridge_mcp_server.client")


class LanePool:
    """At most *cap* lanes in use at once; idle lanes close after *idle_seconds*."""

    def __init__(
        self,
        opener: Callable[[float], Awaitable[Connection]],
        closer: Callable[[Connection], None],
        *,
        cap: int = 16,
        idle_seconds: float = 30.0,
    ) -> None:
        self.cap = cap
        self.idle_seconds = idle_seconds
        self._opener = opener
        self._closer = closer
        self._semaphore = asyncio.Semaphore(cap)
        self._idle: list[tuple[Connection, asyncio.TimerHandle]] = []
        self._busy: set[Connection] = set()
        self.opened = 0
        self.closed = False

    async def acquire(self, deadline: float, what: str, total: float) -> Connection:
        """A lane for one call, waiting for a free one until *deadline* (loop time)."""
        loop = asyncio.get_running_loop()
        try:
            async with asyncio.timeout_at(deadline):
                await self._semaphore.acquire()
        except TimeoutError:
            raise RequestTimeoutError(
                what, total, f"All {self.cap} lanes to the bridge were busy with other calls."
            ) from None
        try:
            while self._idle:
                lane, handle = self._idle.pop()
                handle.cancel()
                if lane.is_open:
                    self._busy.add(lane)
                    return lane
            lane = await self._opener(max(deadline - loop.time(), 0.05))
            self.opened += 1
            self._busy.add(lane)
            return lane
        except BaseException:
            self._semaphore.release()
            raise

    def release(self, lane: Connection, reusable: bool) -> None:
        """Give a lane back; closed unless *reusable* and still open."""
        self._busy.discard(lane)
        self._semaphore.release()
        if reusable and lane.is_open and not self.closed:
            handle = asyncio.get_running_loop().call_later(self.idle_seconds, self._expire, lane)
            self._idle.append((lane, handle))
        else:
            self._closer(lane)

    def _expire(self, lane: Connection) -> None:
        for index, (idle, _handle) in enumerate(self._idle):
            if idle is lane:
                del self._idle[index]
                logger.debug("closing idle lane %s", lane.name)
                self._closer(lane)
                return

    def drop_idle(self) -> None:
        """Close every idle lane (the main connection dropped; they are likely stale)."""
        idle, self._idle = self._idle, []
        for lane, handle in idle:
            handle.cancel()
            self._closer(lane)

    def all_lanes(self) -> list[Connection]:
        """Every lane, idle or busy."""
        return [lane for lane, _ in self._idle] + list(self._busy)

    def close_all(self) -> list[Connection]:
        """Forget every lane and return them for closing."""
        self.closed = True
        lanes = self.all_lanes()
        for _lane, handle in self._idle:
            handle.cancel()
        self._idle = []
        self._busy.clear()
        return lanes
