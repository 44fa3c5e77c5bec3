"""A ping the bridge answered in time is not a timeout because our own process did not run for a while.

A publish first pings the bridge (``robot/acting/topics.bridge_is_reading``) and refuses when no pong comes
within the limit. When this process is starved past the limit (a loaded machine), the pong already waits in
the socket when the loop runs again, and the loop reads it and fires the deadline's timer in the same turn:
the pong must count. The peer is a websockets server on a thread of its own, so it answers while this
process's loop is held.
"""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import Iterator

import pytest
from websockets.sync.server import Server, ServerConnection, serve

from rosbridge_mcp_server.client.transport import websocket_dial

LIMIT = 0.3


def _echo(ws: ServerConnection) -> None:
    for _ in ws:  # pings are answered by the connection itself
        pass


@pytest.fixture
def peer() -> Iterator[str]:
    server: Server = serve(_echo, "127.0.0.1", 0)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"ws://127.0.0.1:{server.socket.getsockname()[1]}"
    finally:
        server.shutdown()
        thread.join(10)


async def test_a_pong_read_in_the_turn_the_deadline_fires_counts(peer: str) -> None:
    transport = await websocket_dial(peer)(10.0)
    try:
        await transport.ping(10.0)  # the peer answers pings
        loop = asyncio.get_running_loop()
        ping = asyncio.create_task(transport.ping(LIMIT))
        # Runs right after the ping's first step has sent it: the loop is held past the limit while the
        # peer's thread answers (the hold is the attack, a starved process, not a wait for an event).
        loop.call_soon(time.sleep, LIMIT * 3)
        await asyncio.wait_for(ping, 10.0)
    finally:
        await transport.close()


async def test_a_peer_that_does_not_answer_is_still_a_timeout(peer: str) -> None:
    """The other side of the same rule: no pong at all within the limit stays a TimeoutError."""
    transport = await websocket_dial(peer)(10.0)
    try:
        # Stop reading on our side's peer: the frozen bridge. Its socket takes the ping but nothing answers.
        transport.ws.transport.pause_reading()  # type: ignore[attr-defined]
        with pytest.raises(TimeoutError):
            await transport.ping(LIMIT)
    finally:
        transport.abort()
