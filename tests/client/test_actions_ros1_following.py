"""Following a ROS 1 goal through its status/feedback/result messages, fed by hand (no socket)."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest

from rosbridge_mcp_server.robot.goals import Goal
from rosbridge_mcp_server.robot.goals.ros1 import Progress, follow


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is done with the answers is tested."""
    return True


def status(goal_id: str, code: int) -> dict[str, Any]:
    """An actionlib_msgs/GoalStatus for *goal_id*."""
    return {"goal_id": {"stamp": {"secs": 0, "nsecs": 0}, "id": goal_id}, "status": code, "text": ""}


def follower() -> tuple[asyncio.Queue[tuple[str, Any]], Goal, Progress]:
    """An empty queue, goal "g" (which counts its feedback) and fresh progress."""
    goal = Goal("g", "/fibonacci", "actionlib_tutorials/FibonacciAction", 1)
    return asyncio.Queue(), goal, Progress()


async def test_messages_of_other_goals_are_ignored() -> None:
    """Feedback and results of other goal ids do not count; ours ends the wait."""
    queue, goal, seen = follower()
    queue.put_nowait(("feedback", {"status": status("other", 1), "feedback": {"sequence": [9]}}))
    queue.put_nowait(("result", {"status": status("other", 3), "result": {"sequence": [9]}}))
    queue.put_nowait(("feedback", {"status": status("g", 1), "feedback": {"sequence": [0, 1]}}))
    queue.put_nowait(("result", {"status": status("g", 3), "result": {"sequence": [0, 1, 1]}}))
    assert await follow(queue, goal, None, seen) == (3, {"sequence": [0, 1, 1]})
    assert list(goal.last_feedback) == [{"sequence": [0, 1]}]


async def test_a_goal_the_status_says_ended_finishes_even_without_a_result() -> None:
    """If the status array says our goal ended and no result follows, the wait ends with that status."""
    queue, goal, seen = follower()
    queue.put_nowait(("status", {"status_list": [status("other", 1), status("g", 4)]}))
    assert await asyncio.wait_for(follow(queue, goal, None, seen), 5.0) == (4, None)


async def test_the_last_status_survives_a_timeout() -> None:
    """A wait cut short by a timeout still leaves the last status seen for the report."""
    queue, goal, seen = follower()
    queue.put_nowait(("status", {"status_list": [status("g", 1)]}))
    with pytest.raises(TimeoutError):
        async with asyncio.timeout(0.1):
            await follow(queue, goal, None, seen)
    assert seen.code == 1


async def test_an_error_from_a_subscription_ends_the_wait() -> None:
    """A connection loss reported by a subscription pump is raised."""
    queue, goal, seen = follower()
    queue.put_nowait(("error", RuntimeError("lost")))
    with pytest.raises(RuntimeError, match="lost"):
        await follow(queue, goal, None, seen)
