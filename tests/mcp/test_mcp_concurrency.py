"""Calls run side by side: a slow service or a running goal never holds up the other tools."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Awaitable, Callable

import pytest
from mcp_harness import Session, open_session, text_of, types_for

from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 30.0
# Long enough that the other calls finish first even on a loaded machine; the slow call is cancelled, not
# awaited. The Humble-like robot's connection stays busy with the call until it ends (as Humble's would), and
# stopping that robot waits for it, so it gets a shorter one.
SLOW_SECONDS = 30.0
HUMBLE_SLOW_SECONDS = 4.0


@pytest.fixture(params=["ros2", "ros1", "humble", "jazzy-2.1.0"])
async def robot(
    request: pytest.FixtureRequest, make_sim: Callable[..., Awaitable[SimulatedRobot]]
) -> SimulatedRobot:
    """Each dialect, and ROS 2 handling each connection in order, with a very slow service.

    "jazzy-2.1.0" is rosbridge 2.1.0 on Jazzy with its launch defaults: in order although the distro is Jazzy.
    """
    if request.param == "humble":
        return await make_sim(dialect="ros2", in_order=True, slow_service_seconds=HUMBLE_SLOW_SECONDS)
    if request.param == "jazzy-2.1.0":
        return await make_sim(
            dialect="ros2",
            in_order=True,
            distro="jazzy",
            rosapi="2.1.0",
            slow_service_seconds=HUMBLE_SLOW_SECONDS,
        )
    return await make_sim(dialect=request.param, slow_service_seconds=SLOW_SECONDS)


@pytest.fixture
async def robot_session(robot: SimulatedRobot) -> AsyncIterator[Session]:
    """A session on that robot."""
    async with open_session(robot.url, request_timeout=60.0) as opened:
        yield opened


async def test_other_tools_answer_while_a_slow_service_call_is_pending(
    robot_session: Session, robot: SimulatedRobot
) -> None:
    """list_topics, another service call and a publish all complete while /slow_service still runs."""
    slow = asyncio.create_task(
        robot_session.call(
            "publish_service",
            {
                "service": "/slow_service",
                "service_type": types_for(robot)["trigger"],
                "request": {},
                "timeout": 60,
            },
        )
    )
    await robot.world.wait_for(lambda w: w.service_calls.get("/slow_service") == 1, WAIT)

    await robot_session.ok("list_topics")
    added = await robot_session.ok(
        "publish_service",
        {
            "service": "/add_two_ints",
            "service_type": types_for(robot)["add_two_ints"],
            "request": {"a": 1, "b": 2},
        },
    )
    await robot_session.ok(
        "publish_topic",
        {
            "topic": "/turtle1/cmd_vel",
            "message_type": types_for(robot)["twist"],
            "message": {"linear": {"x": 0.1}},
        },
    )
    assert not slow.done(), "the slow call should still be running"
    assert added.structured_content is not None
    assert added.structured_content["response"] == {"sum": 3}

    slow.cancel()
    with pytest.raises(asyncio.CancelledError):
        await slow


async def test_tools_answer_while_a_goal_runs_and_the_goal_can_be_cancelled(
    robot_session: Session, robot: SimulatedRobot
) -> None:
    """While publish_action waits, list_topics works and cancel_action reaches the goal (Humble included)."""
    goal = asyncio.create_task(
        robot_session.call(
            "publish_action",
            {
                "action_name": "/fibonacci",
                "action_type": types_for(robot)["fibonacci"],
                "goal": {"order": 45},
                "timeout": 60,
            },
        )
    )
    await robot.world.wait_for(lambda w: any(g.feedback_count > 0 for g in w.goals.values()), WAIT)
    await robot_session.ok("list_topics")
    assert not goal.done()
    await robot_session.ok("cancel_action", {"action_name": "/fibonacci"})
    result = await asyncio.wait_for(goal, WAIT)
    assert result.structured_content is not None, text_of(result)
    assert result.structured_content["canceled_by"] == "cancel_action"
