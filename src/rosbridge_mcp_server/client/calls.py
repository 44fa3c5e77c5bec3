"""What a caller does on the bridge through :class:`RosbridgeClient`: services (and whether one call holds up
the next, measured), topics, a ping, a barrier.

Split from ``client.py`` (the lifecycle and the connect loop) by concern: :class:`BridgeCalls` is the client's
base class, given the current session, the lanes and the topics the client keeps (no accessor left for the
subclass to fill in).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from typing import Any, Final, Literal

from rosbridge_mcp_server.client.current import CurrentSession
from rosbridge_mcp_server.client.lanes import LanePool
from rosbridge_mcp_server.client.ordering import call_ordering
from rosbridge_mcp_server.client.services import bridge_timeout, call_on, call_on_lane
from rosbridge_mcp_server.client.session import BridgeSession
from rosbridge_mcp_server.client.subscription import Subscription
from rosbridge_mcp_server.client.topics import Topics
from rosbridge_mcp_server.client.transport import Dial
from rosbridge_mcp_server.wire import protocol

__all__ = ["BridgeCalls"]

logger = logging.getLogger("rosbridge_mcp_server.client")

#: How long the ordering probe's service holds its caller: above a slow rosapi call on 2.1.0 (85-100 ms).
_ORDERING_HOLD_SECONDS: Final = 0.5
#: The ordering probe gives up after this long (then every call keeps a connection of its own).
_ORDERING_LIMIT_SECONDS: Final = 5.0


class BridgeCalls:
    """Service calls, advertisements, publishes, subscriptions, a ping: :class:`RosbridgeClient`'s calls.

    Given what they run on: the current session (:class:`CurrentSession`, which the client's connect loop
    sets), the pool of lanes, the topics, the id minter and the transport the ordering probe dials through.
    """

    def __init__(
        self,
        url: str,
        current: CurrentSession,
        *,
        transport: Dial,
        ids: protocol.IdMinter,
        lanes: LanePool,
        topics: Topics,
        request_timeout: float,
    ) -> None:
        self.url = url
        self.request_timeout = request_timeout
        self.topics = topics
        #: Something that acts (a publish, a goal cancel) went out on the main connection, and the bridge may
        #: not have handled it yet: ``close()`` waits for it first.
        self.unhandled_acts = False
        self._current = current
        self._transport = transport
        self._ids = ids
        self._lanes = lanes

    async def ordering_known(self, timeout: float) -> bool:
        """Wait (at most *timeout*; no error) until it is known whether the bridge holds one connection's
        calls up behind each other (told by its answers, measured, or given up on); at once when not
        connected. Whether it is known now: False when not connected, or still unknown after *timeout*."""
        session = self._current.session
        if session is None:
            return False
        if not session.ordering_known.is_set():
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(session.ordering_known.wait(), timeout)
        return session.ordering_known.is_set()

    @property
    def calls_share_connection(self) -> bool:
        """Service calls run side by side on the shared connection now (False while down, or while calls get a
        connection of their own: a bridge that may hold them up behind each other)."""
        session = self._current.session
        return session is not None and not session.lanes_by_default

    async def _measure_ordering(self, session: BridgeSession) -> None:
        """Measure whether the bridge holds a connection's calls up behind each other; lanes stay until then.

        Only where the bridge's answers did not tell (see :mod:`.ordering`); a failed measurement keeps the
        safe assumption, in order.
        """
        try:
            queued = await call_ordering(
                self.url,
                session.info.version,
                min(max(self.request_timeout, 2.0), _ORDERING_LIMIT_SECONDS),
                hold=_ORDERING_HOLD_SECONDS,
                dial=self._transport,
            )
        except asyncio.CancelledError:
            raise
        except Exception as exc:
            logger.info(
                "Could not measure whether %s holds calls up behind each other (%s: %s); every call gets a "
                "connection of its own",
                self.url,
                type(exc).__name__,
                exc,
            )
        else:
            session.lanes_by_default = queued
            logger.info(
                "rosbridge at %s %s",
                self.url,
                "holds a connection's calls up behind a slow one: every call gets a connection of its own"
                if queued
                else "runs a connection's calls side by side (measured)",
            )
        finally:
            session.ordering_known.set()

    # --- services -----------------------------------------------------------------------------------

    async def call_service(
        self,
        service: str,
        args: dict[str, Any] | list[Any] | None = None,
        *,
        timeout: float | None = None,
        isolated: bool | None = None,
        check: Callable[[], None] | None = None,
    ) -> Any:
        """Call a ROS service and return its response fields (``values``).

        Time fields in *args* are respelled for ROS 1, which ignores ``sec``/``nanosec``. Runs on the shared
        connection, or on a lane of its own when the bridge may handle one
        connection in order, when another call is in flight on a ROS 1 connection (see
        :attr:`RosInfo.one_call_per_connection`), or when *isolated* is true. Raises :class:`ServiceError`
        with the bridge's text, :class:`RequestTimeoutError`, :class:`ConnectionLostError`,
        :class:`NotConnectedError`. *check* (the send gate) is called right before the call's frame is
        written, after a lane is opened for it; what it raises ends the call unsent.
        """
        t = self.request_timeout if timeout is None else timeout
        session = self._current.held
        if session is None or not session.is_open:
            session = await self._current.wait(asyncio.get_running_loop().time() + t)
        args = session.dialect.outgoing(args)
        if isolated or (
            isolated is None
            and (session.lanes_by_default or (session.spread_calls and session.connection.pending))
        ):
            return await call_on_lane(
                self._lanes,
                self._ids,
                service,
                args,
                t,
                send_timeout=session.send_service_timeout,
                check=check,
            )
        if check is not None:
            check()
        return await call_on(
            session.connection,
            self._ids,
            service,
            args,
            t,
            bridge_timeout=bridge_timeout(t) if session.send_service_timeout else None,
        )

    # --- topics -------------------------------------------------------------------------------------

    async def advertise(
        self, topic: str, msg_type: str, *, latch: bool = False, queue_size: int = 10
    ) -> None:
        """Advertise *topic* now (``publish`` does this on first use); restored after reconnects."""
        await self.topics.advertise(
            self._current.require(), topic, msg_type, latch=latch, queue_size=queue_size
        )

    async def publish(
        self,
        topic: str,
        msg_type: str,
        msg: dict[str, Any],
        *,
        latch: bool = False,
        queue_size: int = 10,
        session: BridgeSession | None = None,
    ) -> None:
        """Publish one message now, or raise :class:`NotConnectedError`. Never queued, never replayed.

        The topic is advertised once (per topic and type) and the advertisement reused; time
        fields are respelled for ROS 1, which ignores ``sec``/``nanosec``. With *session*, only on that
        session (:class:`NotConnectedError` if it is gone).
        """
        await self.topics.publish(
            session or self._current.require(), topic, msg_type, msg, latch=latch, queue_size=queue_size
        )
        self.unhandled_acts = True

    async def unadvertise(self, topic: str) -> None:
        """Stop advertising *topic* (our advertisement only)."""
        await self.topics.unadvertise(topic)

    def subscribe(
        self,
        topic: str,
        msg_type: str | None = None,
        *,
        throttle_rate: int = 0,
        queue_length: int = 0,
        max_queue: int = 1000,
        qos: dict[str, Any] | None = None,
        compression: Literal["cbor"] | None = None,
    ) -> Subscription:
        """A :class:`Subscription` (``async with client.subscribe("/chatter") as sub: ...``).

        ``qos`` is sent as the ROS 2 ``qos`` object (read by rosbridge 2.0.7 / 2.7.0 / 3.3.0 and later).
        ``compression="cbor"`` asks for binary CBOR frames: numeric arrays then arrive as ``array.array``
        and ``uint8[]`` as bytes (far faster for large maps); a bridge that ignores it sends JSON.
        """
        return self.topics.subscribe(
            topic,
            msg_type,
            throttle_rate=throttle_rate,
            queue_length=queue_length,
            max_queue=max_queue,
            qos=qos,
            compression=compression,
        )

    async def ping(self, timeout: float | None = None) -> float:
        """Round-trip a WebSocket ping on the main connection; returns the seconds it took.

        Proves the bridge reads the connection now: a frozen bridge, or a link that died without a close,
        still takes frames into the socket buffer and would act on them whenever it wakes up.
        :class:`RequestTimeoutError` if no pong within *timeout* (default ``request_timeout``),
        :class:`NotConnectedError` when there is no connection.
        """
        session = self._current.require()
        return await session.connection.ping(self.request_timeout if timeout is None else timeout)

    async def handled(self, timeout: float) -> bool:
        """Whether the bridge has handled everything sent so far on the main connection (one call's round
        trip, within *timeout*); ``False`` when there is no connection or no answer in time."""
        session = self._current.session
        return session is not None and await session.handled(timeout)
