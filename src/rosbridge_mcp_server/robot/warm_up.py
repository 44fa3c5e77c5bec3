"""Learning the service types in the background when a connection opens, before the model asks.

A service's type cannot change while it exists, so a listing only needs a look-up for a service it has not
seen on this connection. The first listing of a connection would make every one of them while the model
waits (on a real graph, dozens of round trips; on rosbridge 2.1.0 about a quarter of rosapi calls take
~90 ms). A model's first tool call comes seconds after the server connected, so those look-ups are made
then, one at a time.
"""

from __future__ import annotations

import asyncio
import logging
from typing import TYPE_CHECKING, Final

from rosbridge_mcp_server.errors import RosbridgeError

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient, SessionFacts
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["ServiceTypeWarmUp"]

_log = logging.getLogger(__name__)
#: Longest wait for the client's measurement of the bridge's call ordering before learning anyway.
_ORDERING_WAIT_SECONDS: Final = 6.0


class ServiceTypeWarmUp:
    """A session watcher that runs :meth:`RosGraph.learn_service_types` after every (re)connect."""

    def __init__(self, client: RosbridgeClient, graph: RosGraph) -> None:
        self._client = client
        self._graph = graph
        self._task: asyncio.Task[None] | None = None
        #: Set when the latest run has ended, however it ended (tests and diagnostics wait on it).
        self.done = asyncio.Event()

    def session_started(self, session: SessionFacts) -> None:
        """Start learning on the new connection (what the old one learnt was dropped with it)."""
        if self._task is not None:
            self._task.cancel()
        self.done.clear()
        self._task = self._client.run_in_background(self._learn(session), "learn service types")

    async def client_closing(self, session: SessionFacts | None) -> None:
        """Stop learning: the client is closing."""
        if self._task is not None:
            self._task.cancel()

    async def _learn(self, session: SessionFacts) -> None:
        loop = asyncio.get_running_loop()
        began = loop.time()
        # After the client's measurement of the bridge's call ordering: its short-lived probe service is
        # gone from the graph by then (nothing to learn about it), and rosapi answers one call at a time.
        await self._client.ordering_known(_ORDERING_WAIT_SECONDS)
        try:
            learnt = await self._graph.learn_service_types()
        except RosbridgeError as exc:
            _log.debug("stopped learning service types on connection %d: %s", session.number, exc)
        else:
            _log.debug(
                "learnt %d service types on connection %d in %.0f ms",
                learnt,
                session.number,
                (loop.time() - began) * 1e3,
            )
        finally:
            # A run cancelled by a newer connection's does not speak for that one.
            if self._task is asyncio.current_task():
                self.done.set()
