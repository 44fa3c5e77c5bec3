"""The client's current session, and the one way a call waits for one.

``RosbridgeClient``'s connect loop sets and clears it; its calls (:class:`~.calls.BridgeCalls`) and its topics
read it. A call that finds no connection prompts an attempt at once and waits for that one attempt
only: nothing is queued, the caller sends its request itself, now, or gets :class:`NotConnectedError`.
"""

from __future__ import annotations

from rosbridge_mcp_server.client.reconnect import Attempts
from rosbridge_mcp_server.client.session import BridgeSession
from rosbridge_mcp_server.errors import NotConnectedError

__all__ = ["CurrentSession"]


class CurrentSession:
    """The main session now (``held``: the last one the connect loop set, until its connection is gone)."""

    __slots__ = ("attempts", "closed", "connect_timeout", "held", "url")

    def __init__(self, url: str, attempts: Attempts, connect_timeout: float) -> None:
        self.url = url
        self.attempts = attempts
        self.connect_timeout = connect_timeout
        self.held: BridgeSession | None = None
        #: The client was closed: no session will come.
        self.closed = False

    @property
    def session(self) -> BridgeSession | None:
        """The open session, or None while down."""
        session = self.held
        return session if session is not None and session.is_open else None

    def require(self) -> BridgeSession:
        """The open session, or :class:`NotConnectedError` at once (for sends that must never wait)."""
        session = self.session
        if session is None:
            raise NotConnectedError(self.url, self.attempts.last_reason)
        return session

    async def wait(self, deadline: float | None = None) -> BridgeSession:
        """The open session, waiting only for a connection attempt under way (or prompted now).

        Between attempts, a call prompts one at once rather than failing until the backoff runs out; it waits
        for that attempt (bounded by the connect timeout and *deadline*), never for a later one.
        """
        session = self.session
        if session is not None:
            return session
        if self.closed:
            raise NotConnectedError(self.url, "the client is closed")
        if self.attempts.timed_out:
            # Waiting out another handshake would cost every call the whole connect timeout: the attempt is
            # prompted, not awaited, so a later call finds the connection if the bridge answers again.
            self.attempts.prompt()
            raise NotConnectedError(self.url, self.attempts.last_reason)
        await self.attempts.wait_for_one(self.connect_timeout, deadline)
        session = self.session
        if session is not None:
            return session
        raise NotConnectedError(self.url, self.attempts.last_reason)
