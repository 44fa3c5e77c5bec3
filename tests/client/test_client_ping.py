"""A ping the bridge answered in time is not a timeout because our own process did not run for a while.

A publish first pings the bridge (``robot/acting/topics.bridge_is_reading``) and refuses when no pong comes
within the limit. When this process is starved past the limit (a loaded machine), the pong already waits in
the socket when the loop runs again, and the loop reads it and fires the deadline's timer in the same turn:
the pong must count. The peer is a websockets server on a thread of its own, so it answers while this
process's loop is held.
"""

from __future__ import annotations

import asyncio
import contextlib
import random
import socket
import threading
import time
from collections.abc import Iterator

import pytest
from websockets.sync.server import Server, ServerConnection, serve

from rosbridge_mcp_server.client.transport import websocket_dial

LIMIT = 0.3
#: The give-back test: a ping limit of 2 s, this process held for 3 s right after the ping, and a link that
#: holds each chunk 1.7 s each way: the pong comes at 3.4 s, after the hold, within 2 s of our running time.
GIVE_BACK_LIMIT = 2.0
HOLD = 3.0
SLOW_LINK = 1.7


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


def _pump(src: socket.socket, dst: socket.socket, slow: threading.Event) -> None:
    """Copy bytes from *src* to *dst*, once *slow* is set each chunk SLOW_LINK late, until *src* ends."""
    with contextlib.suppress(OSError):
        while chunk := src.recv(65536):
            if slow.is_set():
                time.sleep(SLOW_LINK)
            dst.sendall(chunk)
    with contextlib.suppress(OSError):
        dst.shutdown(socket.SHUT_WR)


@pytest.fixture
def slow_peer(peer: str) -> Iterator[tuple[str, threading.Event]]:
    """The peer behind a link (on threads) that holds every chunk SLOW_LINK seconds each way once the
    event is set."""
    slow = threading.Event()
    host, port = peer.removeprefix("ws://").split(":")
    listener = socket.create_server(("127.0.0.1", 0))
    sockets: list[socket.socket] = [listener]

    def accept() -> None:
        with contextlib.suppress(OSError):
            while True:
                ours, _ = listener.accept()
                theirs = socket.create_connection((host, int(port)))
                sockets.extend((ours, theirs))
                for a, b in ((ours, theirs), (theirs, ours)):
                    threading.Thread(target=_pump, args=(a, b, slow), daemon=True).start()

    threading.Thread(target=accept, daemon=True).start()
    try:
        yield f"ws://127.0.0.1:{listener.getsockname()[1]}", slow
    finally:
        for sock in sockets:
            sock.close()


async def test_seconds_this_process_did_not_run_are_not_the_peers(
    slow_peer: tuple[str, threading.Event],
) -> None:
    """The pong comes 2 × SLOW_LINK after the ping, past the limit in wall-clock time; but this process was
    held for most of that, so the peer had less than the limit of our running time, and the ping holds."""
    url, slow = slow_peer
    transport = await websocket_dial(url)(10.0)
    try:
        await transport.ping(10.0)
        slow.set()
        loop = asyncio.get_running_loop()
        ping = asyncio.create_task(transport.ping(GIVE_BACK_LIMIT))
        loop.call_soon(time.sleep, HOLD)  # held, then the pong comes while the loop runs again
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
        # Held past the limit too: the stall is given back, and still no pong is a timeout.
        asyncio.get_running_loop().call_soon(time.sleep, LIMIT * 2)
        with pytest.raises(TimeoutError):
            await transport.ping(LIMIT)
    finally:
        transport.abort()


async def test_no_ping_draws_from_the_shared_random_state(peer: str) -> None:
    """Ours and websockets' keepalive's (a ping without a payload) carry a count: the process's `random` is
    the host's, and a property test's strategies failed when a keepalive ping drew from it in the middle."""
    transport = await websocket_dial(peer)(10.0)
    try:
        before = random.getstate()
        await transport.ping(10.0)
        await asyncio.wait_for(await transport.ws.ping(), 10.0)  # type: ignore[attr-defined]  # the keepalive's way
        assert random.getstate() == before
    finally:
        await transport.close()
