"""Topics: our advertisements and subscriptions, kept across reconnects, and the routing of incoming messages.

Advertisements and subscriptions still wanted are restored on every new session (advertise/subscribe only,
never a publish: a stale velocity command is a safety bug), with type names spelled for the bridge that came
back. Each :class:`Subscription` has its own rosbridge id, so closing one never removes another listener.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Any, Literal

from rosbridge_mcp_server.client.session import BridgeSession, send_quietly
from rosbridge_mcp_server.client.subscription import Subscription
from rosbridge_mcp_server.errors import NotSentError
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.cbor import json_shaped

__all__ = ["Advert", "Topics"]

logger = logging.getLogger("rosbridge_mcp_server.client")


@dataclass(slots=True)
class Advert:
    """One topic we advertise: its id, its type as given and as sent to the current bridge."""

    id: str
    msg_type: str
    wire_type: str
    latch: bool
    queue_size: int


class Topics:
    """Advertisements and subscriptions of one client (the client hands in its session as needed)."""

    def __init__(
        self,
        url: str,
        ids: protocol.IdMinter,
        current: Callable[[], BridgeSession | None],
        wait_for_session: Callable[[], Awaitable[BridgeSession]],
    ) -> None:
        self.url = url
        self._ids = ids
        self._current = current
        self._wait_for_session = wait_for_session
        #: topic → advertisement still wanted
        self.adverts: dict[str, Advert] = {}
        #: topic → subscription id → open subscription
        self.subscriptions: dict[str, dict[str, Subscription]] = {}

    # --- publishing -------------------------------------------------------------------------------------

    async def advertise(
        self, session: BridgeSession, topic: str, msg_type: str, *, latch: bool, queue_size: int
    ) -> None:
        """Advertise *topic* on *session* unless it already is, with this type and latching."""
        conn = session.connection
        wire_type = session.dialect.message_type(msg_type)
        advert = self.adverts.get(topic)
        if advert is not None and (advert.wire_type != wire_type or advert.latch != latch):
            conn.advertised.discard(topic)
            del self.adverts[topic]
            await conn.send(protocol.unadvertise(topic, id=advert.id))
            advert = None
        if advert is None:
            advert = Advert(self._ids.mint("advertise", topic), msg_type, wire_type, latch, queue_size)
        if topic not in conn.advertised:
            conn.advertised.add(topic)
            try:
                await conn.send(
                    protocol.advertise(
                        topic, wire_type, id=advert.id, latch=latch, queue_size=advert.queue_size
                    )
                )
            except BaseException:
                conn.advertised.discard(topic)
                raise
        # Kept for restoring after a reconnect only once a bridge has taken it: an advertisement that could
        # not be sent (too large, say) would otherwise be re-sent on every reconnect.
        self.adverts[topic] = advert

    async def publish(
        self,
        session: BridgeSession,
        topic: str,
        msg_type: str,
        msg: dict[str, Any],
        *,
        latch: bool,
        queue_size: int,
    ) -> None:
        """Publish one message on *session*, advertising first when needed."""
        conn, dialect = session.connection, session.dialect
        advert = self.adverts.get(topic)
        if (
            advert is None
            or topic not in conn.advertised
            or advert.latch != latch
            or (advert.msg_type != msg_type and advert.wire_type != dialect.message_type(msg_type))
        ):
            await self.advertise(session, topic, msg_type, latch=latch, queue_size=queue_size)
        await conn.send(protocol.publish(topic, dialect.outgoing(msg), latch=latch))

    async def unadvertise(self, topic: str) -> None:
        """Stop advertising *topic* (our advertisement only)."""
        advert = self.adverts.pop(topic, None)
        session = self._current()
        if advert is not None and session is not None and topic in session.connection.advertised:
            session.connection.advertised.discard(topic)
            await session.try_send(protocol.unadvertise(topic, id=advert.id))

    async def unadvertise_all(self, session: BridgeSession) -> None:
        """Unadvertise everything on *session* (the client is closing)."""
        for topic, advert in list(self.adverts.items()):
            if topic in session.connection.advertised:
                await session.try_send(protocol.unadvertise(topic, id=advert.id))

    # --- subscriptions ----------------------------------------------------------------------------------

    def subscribe(
        self,
        topic: str,
        msg_type: str | None,
        *,
        throttle_rate: int,
        queue_length: int,
        max_queue: int,
        qos: dict[str, Any] | None = None,
        compression: Literal["cbor"] | None = None,
    ) -> Subscription:
        """A new, not yet opened :class:`Subscription`."""
        return Subscription(
            self,
            topic,
            msg_type,
            sub_id=self._ids.mint("subscribe", topic),
            throttle_rate=throttle_rate,
            queue_length=queue_length,
            max_queue=max_queue,
            qos=qos,
            compression=compression,
        )

    async def open_subscription(self, sub: Subscription) -> None:
        """Send *sub*'s ``subscribe`` on the current session (waiting only for an attempt under way)."""
        session = await self._wait_for_session()
        sub.wire_type = session.dialect.message_type(sub.msg_type) if sub.msg_type else None
        self.subscriptions.setdefault(sub.topic, {})[sub.id] = sub
        try:
            await session.send(_subscribe_op(sub))
        except BaseException:
            self._forget(sub)
            raise

    async def close_subscription(self, sub: Subscription) -> None:
        """Forget *sub* and send its ``unsubscribe`` if a session is up."""
        self._forget(sub)
        session = self._current()
        if session is not None and session.is_open:
            # Shielded: this runs in `finally`/`__aexit__`, often while the caller is being cancelled.
            await asyncio.shield(send_quietly(session.connection, protocol.unsubscribe(sub.topic, id=sub.id)))

    def _forget(self, sub: Subscription) -> None:
        subs = self.subscriptions.get(sub.topic)
        if subs is not None:
            subs.pop(sub.id, None)
            if not subs:
                del self.subscriptions[sub.topic]

    def deliver(self, event: protocol.PublishEvent) -> None:
        """Route an incoming message to every local listener of its topic."""
        subs = self.subscriptions.get(event.topic)
        if subs:
            as_json: dict[str, Any] | None = None
            for sub in subs.values():
                if event.binary and sub.compression is None:
                    # Another listener's CBOR reached this one too (one subscription per topic per
                    # connection, the strongest compression wins): it gets the JSON form it asked for.
                    if as_json is None:
                        as_json = json_shaped(event.msg)
                    sub.deliver(as_json)
                else:
                    sub.deliver(event.msg)

    def fail_all(self, exc: BaseException) -> None:
        """Raise *exc* in every consumer waiting on a subscription (the connection dropped)."""
        for subs in self.subscriptions.values():
            for sub in subs.values():
                sub.fail(exc)

    def close_all(self, exc: BaseException) -> None:
        """Close every subscription with *exc* and forget every advertisement (the client is closing)."""
        for subs in list(self.subscriptions.values()):
            for sub in list(subs.values()):
                sub.is_open = False
                sub.is_closed = True
                sub.fail(exc)
        self.subscriptions.clear()
        self.adverts.clear()

    # --- reconnects -------------------------------------------------------------------------------------

    async def restore(self, session: BridgeSession) -> None:
        """Re-advertise and re-subscribe what is still wanted. Never re-sends a publish.

        Type names are spelled again for this session's bridge: the robot may have come back with another
        ROS version behind the same address.
        """
        dialect = session.dialect
        for topic, advert in list(self.adverts.items()):
            advert.wire_type = dialect.message_type(advert.msg_type)
            try:
                await session.send(
                    protocol.advertise(
                        topic,
                        advert.wire_type,
                        id=advert.id,
                        latch=advert.latch,
                        queue_size=advert.queue_size,
                    )
                )
            except NotSentError as exc:
                # Nothing restored may be able to cost the connection: such an advertisement is forgotten.
                self.adverts.pop(topic, None)
                logger.warning("Not advertising %.100s again after the reconnect: %s", topic, exc)
                continue
            session.connection.advertised.add(topic)
        for subs in list(self.subscriptions.values()):
            for sub in list(subs.values()):
                sub.wire_type = dialect.message_type(sub.msg_type) if sub.msg_type else None
                try:
                    await session.send(_subscribe_op(sub))
                except NotSentError as exc:
                    self._forget(sub)
                    sub.fail(exc)
                    logger.warning("Not subscribing to %.100s again after the reconnect: %s", sub.topic, exc)


def _subscribe_op(sub: Subscription) -> dict[str, Any]:
    return protocol.subscribe(
        sub.topic,
        sub.wire_type,
        id=sub.id,
        throttle_rate=sub.throttle_rate,
        queue_length=sub.queue_length,
        qos=sub.qos,
        compression=sub.compression,
    )
