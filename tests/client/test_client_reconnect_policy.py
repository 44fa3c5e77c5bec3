"""Reconnecting: short backoff for local bridges, a call prompts an attempt, a silent port costs one wait."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator

import pytest
from client_harness import MakeClient, MakeSim

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.client.reconnect import LOCAL_RECONNECT_MAX, PROMPT_SPACING, reconnect_cap
from rosbridge_mcp_server.errors import NotConnectedError


@pytest.mark.parametrize(
    ("url", "local"),
    [
        ("ws://127.0.0.1:9090", True),
        ("ws://localhost:9090", True),
        ("ws://[::1]:9090", True),
        ("ws://192.168.1.20:9090", True),
        ("ws://10.0.0.5:9090", True),
        ("ws://169.254.3.4:9090", True),
        ("ws://turtlebot:9090", True),
        ("ws://robot.local:9090", True),
        ("wss://robot.example.com:443", False),
        ("ws://8.8.8.8:9090", False),
    ],
)
def test_the_backoff_ceiling_is_short_on_this_machine_and_the_local_network(url: str, local: bool) -> None:
    """Local bridges are retried at least twice a second; remote ones on the configured maximum."""
    assert reconnect_cap(url, 5.0) == (LOCAL_RECONNECT_MAX if local else 5.0)
    assert reconnect_cap(url, 0.2) == 0.2


async def test_a_call_between_attempts_prompts_one_at_once(
    make_sim: MakeSim, make_client: MakeClient
) -> None:
    """With a long backoff, a call after the bridge's return connects now instead of failing for seconds.

    The loop's next attempt is 15 s away at the earliest (a backoff from 30 s): a call that waited for it
    could not be answered within its 10 s, however loaded the machine."""
    robot = await make_sim()
    client = await make_client(robot, reconnect_min=30.0, reconnect_max=60.0)
    await robot.stop()
    await client.wait_disconnected(5.0)
    await robot.start()
    await asyncio.wait_for(client.call_service("/rosapi/topics", timeout=10.0), 10.0)
    assert client.connections_made == 2


async def test_a_local_bridge_is_retried_on_the_short_ceiling_and_is_back_after_a_long_outage(
    make_sim: MakeSim, make_client: MakeClient
) -> None:
    """Down for 2.5 s with the default backoff (0.2 s doubling to 5 s): the local bridge's ceiling is half a
    second, and the client is back by itself (no call prompting it). How soon after the return is the
    benchmark's figure (scripts/bench.py), not a bound here."""
    robot = await make_sim()
    client = await make_client(robot, reconnect_min=0.2, reconnect_max=5.0)
    assert client.reconnect_cap == LOCAL_RECONNECT_MAX
    await robot.stop()
    await client.wait_disconnected(5.0)
    # The outage itself, not a synchronisation: the backoff grows while the bridge is away.
    await asyncio.sleep(2.5)
    await robot.start()
    await client.wait_connected(30.0)
    assert client.connections_made == 2


@pytest.fixture
async def silent_port() -> AsyncIterator[str]:
    """A TCP port that accepts connections and never answers the WebSocket handshake."""
    held: list[asyncio.StreamWriter] = []

    async def accept(_reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        held.append(writer)

    server = await asyncio.start_server(accept, "127.0.0.1", 0)
    port = server.sockets[0].getsockname()[1]
    try:
        yield f"ws://127.0.0.1:{port}"
    finally:
        for writer in held:
            writer.close()
        server.close()
        await server.wait_closed()


async def test_a_port_that_never_completes_the_handshake_costs_one_wait_not_one_per_call(
    silent_port: str,
) -> None:
    """The first call waits for the attempt under way (the connect timeout); later calls fail at once.

    "At once" is held as "well before another connect timeout": a call that waited for the next attempt would
    need the whole 2 s, so the 1 s bound cannot be met by waiting, however loaded the machine.
    """
    loop = asyncio.get_running_loop()
    async with RosbridgeClient(
        silent_port, connect_timeout=2.0, reconnect_min=0.05, reconnect_max=0.2
    ) as client:
        start = loop.time()
        with pytest.raises(NotConnectedError, match=r"no WebSocket answer within 2 s"):
            await client.call_service("/rosapi/topics", timeout=5.0)
        assert loop.time() - start >= 1.5
        with pytest.raises(NotConnectedError, match=r"no WebSocket answer within 2 s"):
            await asyncio.wait_for(client.call_service("/rosapi/topics", timeout=5.0), 1.0)


async def test_after_a_silent_port_a_call_still_prompts_the_next_attempt(make_sim: MakeSim) -> None:
    """After a timed-out attempt a call fails at once but wakes the loop, which finds the answering bridge."""
    held: list[asyncio.StreamWriter] = []

    async def accept(_reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        held.append(writer)

    silent = await asyncio.start_server(accept, "127.0.0.1", 0)
    port = silent.sockets[0].getsockname()[1]
    url = f"ws://127.0.0.1:{port}"
    async with RosbridgeClient(url, connect_timeout=0.3, reconnect_min=6.0, reconnect_max=30.0) as client:
        with pytest.raises(NotConnectedError, match="no WebSocket answer"):
            await client.call_service("/rosapi/topics", timeout=5.0)
        for writer in held:
            writer.close()
        silent.close()
        await silent.wait_closed()
        await make_sim(port=port)
        # The rule under test, not a synchronisation: prompts are spaced at least this far after an attempt.
        await asyncio.sleep(PROMPT_SPACING)
        with pytest.raises(NotConnectedError):
            await client.call_service("/rosapi/topics", timeout=5.0)
        await client.wait_connected(2.0)


async def test_a_call_right_after_a_refused_attempt_waits_out_the_spacing_and_connects(
    make_sim: MakeSim, make_client: MakeClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A call that comes within the prompt spacing of a refused attempt, when the bridge is back, connects.

    It used to fail at once (bench row 16f: the first call after a bridge restart failed whenever the loop's
    last refused attempt was under 0.1 s old). The spacing is made 2 s here so that the call surely comes
    within it, however loaded the machine; the loop's own next attempt is 15 s away at the earliest."""
    monkeypatch.setattr("rosbridge_mcp_server.client.reconnect.PROMPT_SPACING", 2.0)
    robot = await make_sim()
    client = await make_client(robot, reconnect_min=30.0, reconnect_max=60.0)
    await robot.stop()
    await client.wait_disconnected(5.0)
    with pytest.raises(NotConnectedError):
        await client.call_service("/rosapi/topics", timeout=5.0)  # prompts an attempt, refused
    await robot.start()
    await asyncio.wait_for(client.call_service("/rosapi/topics", timeout=10.0), 10.0)
    assert client.connections_made == 2
