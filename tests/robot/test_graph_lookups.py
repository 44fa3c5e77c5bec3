"""Many graph look-ups side by side: results in order, and one failure reaches the caller as itself."""

from __future__ import annotations

import asyncio

import pytest

from rosbridge_mcp_server.errors import NotConnectedError
from rosbridge_mcp_server.robot.graph.rosapi import bounded_map


async def test_look_ups_side_by_side_answer_in_the_items_order() -> None:
    """Results come back in the order of the items, whatever order the look-ups finish in."""

    async def slow_for_small(n: int) -> int:
        await asyncio.sleep(0.001 * (5 - n))
        return n * 10

    assert await bounded_map(slow_for_small, range(5), limit=2) == [0, 10, 20, 30, 40]


async def test_a_failed_look_up_reaches_the_caller_as_its_own_error_not_a_group() -> None:
    """A connection dropped during one look-up is the NotConnectedError a tool answers, not a group."""
    started = asyncio.Event()

    async def look_up(n: int) -> int:
        if n == 3:
            await started.wait()
            raise NotConnectedError("ws://127.0.0.1:9090", "the connection dropped")
        started.set()
        await asyncio.Event().wait()  # the others are still waiting when the failure comes
        return n

    with pytest.raises(NotConnectedError, match="dropped"):
        await asyncio.wait_for(bounded_map(look_up, range(6), limit=4), timeout=5)
