"""Reading a ROS 1 goal's status/feedback/result messages as typed events, fed by hand (no socket)."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest

from rosbridge_mcp_server.client import GoalEnded, GoalFeedbackEvent
from rosbridge_mcp_server.client.actionlib import Progress, next_event


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is done with the answers is tested."""
    return True


def status(goal_id: str, code: int) -> dict[str, Any]:
    """An actionlib_msgs/GoalStatus for *goal_id*."""
    return {"goal_id": {"stamp": {"secs": 0, "nsecs": 0}, "id": goal_id}, "status": code, "text": ""}


def follower() -> tuple[asyncio.Queue[tuple[str, Any]], Progress]:
    """An empty queue and fresh progress (the goal is "g")."""
    return asyncio.Queue(), Progress()


async def test_messages_of_other_goals_are_ignored() -> None:
    """Feedback and results of other goal ids are skipped; ours come as feedback, then the end."""
    queue, seen = follower()
    queue.put_nowait(("feedback", {"status": status("other", 1), "feedback": {"sequence": [9]}}))
    queue.put_nowait(("result", {"status": status("other", 3), "result": {"sequence": [9]}}))
    queue.put_nowait(("feedback", {"status": status("g", 1), "feedback": {"sequence": [0, 1]}}))
    queue.put_nowait(("result", {"status": status("g", 3), "result": {"sequence": [0, 1, 1]}}))
    assert await next_event(queue, "g", seen) == GoalFeedbackEvent({"sequence": [0, 1]})
    assert await next_event(queue, "g", seen) == GoalEnded(3, {"sequence": [0, 1, 1]})


async def test_a_goal_the_status_says_ended_finishes_even_without_a_result() -> None:
    """If the status array says our goal ended and no result follows, the goal ends with that status."""
    queue, seen = follower()
    queue.put_nowait(("status", {"status_list": [status("other", 1), status("g", 4)]}))
    assert await asyncio.wait_for(next_event(queue, "g", seen), 5.0) == GoalEnded(4, None)


async def test_the_last_status_survives_a_timeout() -> None:
    """A wait cut short by a timeout still leaves the last status seen for the report."""
    queue, seen = follower()
    queue.put_nowait(("status", {"status_list": [status("g", 1)]}))
    with pytest.raises(TimeoutError):
        async with asyncio.timeout(0.1):
            await next_event(queue, "g", seen)
    assert seen.code == 1


async def test_an_error_from_a_subscription_ends_the_wait() -> None:
    """A connection loss reported by a subscription pump is raised."""
    queue, seen = follower()
    queue.put_nowait(("error", RuntimeError("lost")))
    with pytest.raises(RuntimeError, match="lost"):
        await next_event(queue, "g", seen)
