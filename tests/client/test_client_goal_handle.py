"""A goal as the client hands it out: ``client.start_goal`` → ``GoalHandle`` (typed events, ``cancel()``), on
a ROS 2 bridge (its own lane) and a ROS 1 bridge (actionlib's topics), against the simulated robot."""

from __future__ import annotations

import asyncio
from collections.abc import Callable

import pytest
from client_harness import MakeClient, MakeSim

from rosbridge_mcp_server.client import (
    GoalEnded,
    GoalFeedbackEvent,
    GoalHandle,
    RosbridgeClient,
)
from rosbridge_mcp_server.errors import ConnectionLostError, NotSentError
from rosbridge_mcp_server.sim import SimulatedRobot

TYPES = {"ros2": "example_interfaces/action/Fibonacci", "ros1": "actionlib_tutorials/FibonacciAction"}
ROBOTS = {
    "jazzy": {"dialect": "ros2"},
    "humble": {"dialect": "ros2", "in_order": True},
    "ros1": {"dialect": "ros1"},
}
#: How a goal ends: succeeded (ROS 2 SUCCEEDED, ROS 1 SUCCEEDED), cancelled (CANCELED, PREEMPTED).
SUCCEEDED = {"ros2": 4, "ros1": 3}
CANCELED = {"ros2": 5, "ros1": 2}
WAIT = 30.0


@pytest.fixture(params=list(ROBOTS))
async def robot(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    """Jazzy, Humble (in-order) and ROS 1, with goals slow enough to cancel while they run."""
    return await make_sim(action_step=0.1, **ROBOTS[request.param])


async def start(
    client: RosbridgeClient,
    robot: SimulatedRobot,
    order: int,
    *,
    goal_id: str | None = None,
    check: Callable[[], None] | None = None,
) -> GoalHandle:
    """A /fibonacci goal of *order* started through the client, its type spelled for the bridge."""
    action_type = (await client.dialect()).action_type(TYPES[robot.dialect])
    return await client.start_goal(
        "/fibonacci", action_type, {"order": order}, goal_id=goal_id, timeout=WAIT, check=check
    )


async def read_all(handle: GoalHandle) -> None:
    """Read the goal's events until ``next()`` raises."""
    while True:
        await handle.next()


async def test_a_goal_handle_streams_typed_feedback_then_the_goals_end(
    robot: SimulatedRobot, make_client: MakeClient
) -> None:
    """Feedback comes as GoalFeedbackEvent, the end as GoalEnded with the result; closed, the client forgets
    it."""
    client = await make_client(robot)
    handle = await start(client, robot, 3)
    assert client.goals.handle(handle.goal_id) is handle
    feedback: list[GoalFeedbackEvent] = []
    while not isinstance(event := await handle.next(), GoalEnded):
        assert isinstance(event, GoalFeedbackEvent)
        feedback.append(event)
    await handle.aclose()
    assert event.status == SUCCEEDED[robot.dialect]
    assert event.values["sequence"] == [0, 1, 1, 2]
    assert feedback
    assert client.goals.handle(handle.goal_id) is None
    assert client.goals.cut_off == []


async def test_cancel_stops_a_running_goal_and_says_it_reached_it(
    robot: SimulatedRobot, make_client: MakeClient
) -> None:
    """``cancel()`` reaches the goal on every bridge (main connection, lane or cancel topic): it ends
    cancelled on the robot, and nothing is left for a later connection."""
    client = await make_client(robot)
    handle = await start(client, robot, 200)
    try:
        assert isinstance(await handle.next(), GoalFeedbackEvent)
        outcome = await handle.cancel()
        assert outcome.sent
        assert outcome.reaches
        while not isinstance(event := await handle.next(), GoalEnded):
            pass
    finally:
        await handle.aclose()
    assert event.status == CANCELED[robot.dialect]
    [sim_goal] = robot.world.goals.values()
    assert sim_goal.cancel_requested
    assert len(event.values["sequence"]) < 200
    assert client.goals.cut_off == []


async def test_a_goal_the_send_check_refuses_never_reaches_the_robot(
    robot: SimulatedRobot, make_client: MakeClient
) -> None:
    """What the check raises right before the goal goes out ends the start: no goal on the robot, no
    handle."""
    client = await make_client(robot)

    def refuse() -> None:
        raise NotSentError("refused by the test's send gate")

    with pytest.raises(NotSentError, match="send gate"):
        await start(client, robot, 3, goal_id="refused-goal", check=refuse)
    assert client.goals.handle("refused-goal") is None
    assert robot.world.goals == {}
    assert robot.world.published.get("/fibonacci/goal", []) == []


async def test_closing_the_client_cancels_the_goals_it_still_runs(
    robot: SimulatedRobot, make_client: MakeClient
) -> None:
    """``close()`` cancels every open goal while the connection is there: the robot's goal ends cancelled."""
    client = await make_client(robot)
    handle = await start(client, robot, 200)
    assert isinstance(await handle.next(), GoalFeedbackEvent)
    await client.close()
    await robot.wait_for(lambda world: world.goals[handle.goal_id].finished, WAIT)
    assert robot.world.goals[handle.goal_id].status == CANCELED[robot.dialect]


async def test_a_goal_cut_off_by_a_drop_is_cancelled_by_the_client_once_the_connection_is_back(
    robot: SimulatedRobot, make_client: MakeClient
) -> None:
    """After a drop ``next()`` raises ConnectionLostError; the handle's cancel, whether it could be sent or
    not, ends the goal cancelled on the robot, and the client's ledger is empty after."""
    client = await make_client(robot)
    handle = await start(client, robot, 200)
    try:
        assert isinstance(await handle.next(), GoalFeedbackEvent)
        await robot.drop_connections()
        with pytest.raises(ConnectionLostError):
            await asyncio.wait_for(read_all(handle), WAIT)
        outcome = await handle.cancel()
        assert outcome.reaches or handle.goal_id in client.goals.cut_off
    finally:
        await handle.aclose()
    await robot.wait_for(lambda world: world.goals[handle.goal_id].finished, WAIT)
    assert robot.world.goals[handle.goal_id].status == CANCELED[robot.dialect]
    assert client.goals.cut_off == []
