"""One listener on a topic: its own rosbridge subscription id and a bounded local queue."""

from __future__ import annotations

import asyncio
from collections import deque
from types import TracebackType
from typing import Any, Literal, Protocol, Self

from rosbridge_mcp_server.errors import NotConnectedError, RequestTimeoutError

__all__ = ["Subscription", "SubscriptionHost"]


class SubscriptionHost(Protocol):
    """What a subscription needs from the client's topics: send its ``subscribe`` and ``unsubscribe``."""

    @property
    def url(self) -> str: ...

    async def open_subscription(self, sub: Subscription) -> None: ...

    async def close_subscription(self, sub: Subscription) -> None: ...


class Subscription:
    """Messages of one topic, for one listener.

    Use as ``async with client.subscribe("/chatter") as sub:`` then ``await sub.get(timeout)`` or
    ``async for msg in sub``. Each subscription has its own rosbridge id, so closing it never
    removes another listener of the same topic. When the consumer is slow the oldest messages are
    dropped (counted in :attr:`dropped`). It is restored after a reconnect while open; a drop while
    a consumer waits in :meth:`get` raises :class:`ConnectionLostError` there. One task consumes a
    subscription; open another subscription for another consumer.
    """

    def __init__(
        self,
        host: SubscriptionHost,
        topic: str,
        msg_type: str | None,
        *,
        sub_id: str,
        throttle_rate: int,
        queue_length: int,
        max_queue: int,
        qos: dict[str, Any] | None = None,
        compression: Literal["cbor"] | None = None,
    ) -> None:
        if max_queue < 1:
            raise ValueError("max_queue must be at least 1")
        self.topic = topic
        self.msg_type = msg_type
        self.id = sub_id
        self.throttle_rate = int(throttle_rate)
        self.queue_length = int(queue_length)
        self.max_queue = max_queue
        self.qos = qos
        #: ``"cbor"``: ask for binary CBOR frames (typed arrays arrive as ``array.array``); JSON otherwise.
        self.compression = compression
        self.dropped = 0
        self.received = 0
        self.wire_type: str | None = None
        self._host = host
        self._queue: deque[dict[str, Any]] = deque()
        self._waiter: asyncio.Future[None] | None = None
        self.is_open = False
        self.is_closed = False

    # --- fed by the client's topics ------------------------------------------------------------

    def deliver(self, msg: dict[str, Any]) -> None:
        """A message arrived on the topic: queue it (dropping the oldest beyond ``max_queue``)."""
        self.received += 1
        if len(self._queue) >= self.max_queue:
            self._queue.popleft()
            self.dropped += 1
        self._queue.append(msg)
        waiter = self._waiter
        if waiter is not None and not waiter.done():
            waiter.set_result(None)

    def fail(self, exc: BaseException) -> None:
        """Raise *exc* in the consumer waiting in :meth:`get`, if any (the subscription stays usable)."""
        waiter = self._waiter
        if waiter is not None and not waiter.done():
            waiter.set_exception(exc)

    # --- public ---------------------------------------------------------------------------------

    async def open(self) -> Self:
        """Send the ``subscribe``; raises :class:`NotConnectedError` if there is no connection."""
        if self.is_closed:
            raise NotConnectedError(self._host.url, f"the subscription to {self.topic} was closed")
        if not self.is_open:
            await self._host.open_subscription(self)
            self.is_open = True
        return self

    async def close(self) -> None:
        """Send ``unsubscribe`` for this id only; idempotent and safe during cancellation."""
        if self.is_closed:
            return
        self.is_closed = True
        was_open = self.is_open
        self.is_open = False
        self.fail(NotConnectedError(self._host.url, f"the subscription to {self.topic} was closed"))
        if was_open:
            await self._host.close_subscription(self)

    async def __aenter__(self) -> Self:
        return await self.open()

    async def __aexit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.close()

    def pending(self) -> int:
        """Messages received and not yet taken."""
        return len(self._queue)

    def get_nowait(self) -> dict[str, Any] | None:
        """The oldest queued message, or None."""
        return self._queue.popleft() if self._queue else None

    async def get(self, timeout: float | None = None) -> dict[str, Any]:
        """The next message; waits up to *timeout* seconds (forever if None)."""
        if self._queue:
            return self._queue.popleft()
        if self.is_closed:
            raise NotConnectedError(self._host.url, f"the subscription to {self.topic} was closed")
        if self._waiter is not None and not self._waiter.done():
            # One consumer per subscription: a second waiter would silently starve the first.
            raise RuntimeError(f"another task is already waiting on this subscription to {self.topic}")
        loop = asyncio.get_running_loop()
        waiter: asyncio.Future[None] = loop.create_future()
        self._waiter = waiter
        try:
            if timeout is None:
                await waiter
            else:
                async with asyncio.timeout(timeout):
                    await waiter
        except TimeoutError:
            raise RequestTimeoutError(
                f"a message on {self.topic}",
                timeout if timeout is not None else 0.0,
                "Is anything publishing on it? Check the topic name and type.",
            ) from None
        finally:
            if self._waiter is waiter:
                self._waiter = None
        return self._queue.popleft()

    def __aiter__(self) -> Self:
        return self

    async def __anext__(self) -> dict[str, Any]:
        if not self._queue and self.is_closed:
            raise StopAsyncIteration
        try:
            return await self.get()
        except NotConnectedError:
            if self.is_closed:
                raise StopAsyncIteration from None
            raise
