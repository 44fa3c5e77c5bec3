"""Action goals: ROS 2 native ops on their own lane, ROS 1 actionlib topics, timeouts and cancels."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from client_harness import MakeClient, MakeSim

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.errors import ActionError, ConnectionLostError, GoalTimeoutError
from rosbridge_mcp_server.robot import goals
from rosbridge_mcp_server.robot.goals import GoalRegistry, running
from rosbridge_mcp_server.sim import SimulatedRobot


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is done with the answers is tested."""
    return True


ROS2_TYPE = "example_interfaces/action/Fibonacci"
ROS1_TYPE = "actionlib_tutorials/FibonacciAction"
#: Long enough to still be running when a test cancels it (40 steps of 50 ms), short of int32 overflow.
LONG_ORDER = 40

ROBOTS = {
    "jazzy": {"dialect": "ros2"},
    "humble": {"dialect": "ros2", "in_order": True},
    "ros1": {"dialect": "ros1"},
}


def action_type_for(robot: SimulatedRobot) -> str:
    """The action type in the form users of that dialect write."""
    return ROS2_TYPE if robot.dialect == "ros2" else ROS1_TYPE


def running_goal_with_feedback(world: Any) -> bool:
    """Some /fibonacci goal is running and has sent feedback."""
    return any(not g.finished and g.feedback_count >= 1 for g in world.goals.values())


@pytest.fixture(params=list(ROBOTS))
async def robot(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    """A robot of each flavour: Jazzy, Humble (in-order) and ROS 1."""
    return await make_sim(**ROBOTS[request.param])


@pytest.fixture(params=["jazzy", "humble"])
async def robot2(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    """A ROS 2 robot, threaded (Jazzy) and in-order (Humble)."""
    return await make_sim(**ROBOTS[request.param])


# --- goals.running.send_action_goal (ROS 2) ----------------------------------------------------------


async def test_send_action_goal_returns_the_result_and_streams_feedback(
    robot2: SimulatedRobot, make_client: MakeClient
) -> None:
    """A goal runs on its own lane, feedback reaches the callback, the result has status 4."""
    client = await make_client(robot2)
    registry = GoalRegistry(client)
    feedback: list[dict[str, Any]] = []

    async def on_feedback(_goal: goals.Goal, values: dict[str, Any]) -> None:
        feedback.append(values)

    result = await running.send_action_goal(
        registry,
        "/fibonacci",
        "example_interfaces/Fibonacci",
        {"order": 5},
        on_feedback=on_feedback,
        timeout=5.0,
    )
    assert result.status_code == 4
    assert result.status == "succeeded"
    assert result.result["sequence"] == [0, 1, 1, 2, 3, 5]
    assert feedback
    assert feedback[-1]["sequence"] == [0, 1, 1, 2, 3, 5]
    assert registry.running() == []


async def test_a_running_goal_can_be_cancelled_from_the_main_connection(
    robot2: SimulatedRobot, make_client: MakeClient
) -> None:
    """A cancel on the main connection alone reaches a goal running on its lane, even on an in-order (Humble)
    bridge."""
    client = await make_client(robot2)
    registry = GoalRegistry(client)
    goal = asyncio.create_task(
        running.send_action_goal(registry, "/fibonacci", ROS2_TYPE, {"order": LONG_ORDER}, timeout=10.0)
    )
    await robot2.wait_for(running_goal_with_feedback)
    [running_goal] = registry.running("/fibonacci")
    answer = await client.goals.cancel("/fibonacci", running_goal.goal_id, timeout=3.0)
    assert answer.refused is None
    result = await asyncio.wait_for(goal, 15.0)
    assert result.status_code == 5
    assert len(result.result["sequence"]) < LONG_ORDER + 1


async def test_a_goal_past_its_timeout_is_cancelled_and_reports_the_partial_result(
    robot2: SimulatedRobot, make_client: MakeClient
) -> None:
    """At the deadline a cancel is sent; GoalTimeoutError carries the canceled status and result."""
    client = await make_client(robot2)
    registry = GoalRegistry(client)
    with pytest.raises(GoalTimeoutError) as caught:
        await running.send_action_goal(registry, "/fibonacci", ROS2_TYPE, {"order": LONG_ORDER}, timeout=0.3)
    assert caught.value.status == 5
    assert isinstance(caught.value.result, dict)
    assert 2 <= len(caught.value.result["sequence"]) < LONG_ORDER + 1
    await robot2.wait_for(lambda world: all(g.finished for g in world.goals.values()))


async def test_a_rejected_goal_raises_action_error(sim_ros2: SimulatedRobot, make_client: MakeClient) -> None:
    """A goal the server rejects raises ActionError with the bridge's text."""
    client = await make_client(sim_ros2)
    registry = GoalRegistry(client)
    with pytest.raises(ActionError, match="rejected"):
        await running.send_action_goal(registry, "/fibonacci", ROS2_TYPE, {"order": -1}, timeout=5.0)


async def test_send_action_goal_refuses_ros1(sim_ros1: SimulatedRobot, make_client: MakeClient) -> None:
    """ROS 1 has no action ops: send_action_goal says to use actionlib topics."""
    client = await make_client(sim_ros1)
    registry = GoalRegistry(client)
    with pytest.raises(ActionError, match="actionlib"):
        await running.send_action_goal(registry, "/fibonacci", ROS1_TYPE, {"order": 3}, timeout=2.0)


# --- goals.run_goal / cancel_goals (both dialects) ---------------------------------------------------


async def test_run_goal_succeeds_with_feedback_on_every_dialect(
    robot: SimulatedRobot, make_client: MakeClient
) -> None:
    """run_goal returns a succeeded outcome with the result and the last feedback."""
    client = await make_client(robot)
    registry = GoalRegistry(client)
    seen: list[int] = []

    async def on_feedback(goal: goals.Goal, values: dict[str, Any]) -> None:
        seen.append(goal.feedback_count)

    outcome = await goals.run_goal(
        registry, "/fibonacci", action_type_for(robot), {"order": 6}, timeout=5.0, on_feedback=on_feedback
    )
    assert outcome.succeeded
    assert outcome.status == "succeeded"
    assert outcome.status_code == (4 if robot.dialect == "ros2" else 3)
    assert outcome.result == {"sequence": [0, 1, 1, 2, 3, 5, 8]}
    assert outcome.feedback_count == len(seen) >= 1
    assert seen == list(range(1, len(seen) + 1))
    assert 1 <= len(outcome.last_feedback) <= 5
    assert outcome.canceled_by is None
    assert outcome.dialect == (2 if robot.dialect == "ros2" else 1)
    assert registry.running() == []


@pytest.mark.parametrize(
    ("dialect", "written"),
    [
        ("ros2", "example_interfaces/Fibonacci"),
        ("ros2", "example_interfaces/FibonacciAction"),
        ("ros1", "actionlib_tutorials/Fibonacci"),
        ("ros1", "actionlib_tutorials/action/Fibonacci"),
    ],
)
async def test_run_goal_accepts_the_action_type_as_users_write_it(
    make_sim: MakeSim, make_client: MakeClient, dialect: str, written: str
) -> None:
    """pkg/Fibonacci, pkg/action/Fibonacci and pkg/FibonacciAction all work on both dialects."""
    robot = await make_sim(dialect=dialect)
    client = await make_client(robot)
    registry = GoalRegistry(client)
    outcome = await goals.run_goal(registry, "fibonacci", written, {"order": 2}, timeout=5.0)
    assert outcome.succeeded
    assert outcome.action == "/fibonacci"


async def test_run_goal_past_its_timeout_cancels_and_says_so(
    robot: SimulatedRobot, make_client: MakeClient
) -> None:
    """A goal past its timeout is cancelled; the outcome names the dialect's canceled status."""
    client = await make_client(robot)
    registry = GoalRegistry(client)
    outcome = await goals.run_goal(
        registry, "/fibonacci", action_type_for(robot), {"order": LONG_ORDER}, timeout=0.3
    )
    assert not outcome.succeeded
    assert outcome.canceled_by == "timeout"
    assert outcome.status == ("canceled" if robot.dialect == "ros2" else "preempted")
    assert outcome.result is not None
    await robot.wait_for(lambda world: all(g.finished for g in world.goals.values()))


async def test_cancel_goals_stops_a_goal_while_run_goal_is_waiting(
    robot: SimulatedRobot, make_client: MakeClient
) -> None:
    """cancel_goals by our goal id works during run_goal, on Humble too; the outcome says who cancelled."""
    client = await make_client(robot)
    registry = GoalRegistry(client)
    run = asyncio.create_task(
        goals.run_goal(registry, "/fibonacci", action_type_for(robot), {"order": LONG_ORDER}, timeout=10.0)
    )
    await robot.wait_for(running_goal_with_feedback)
    [running] = registry.running("/fibonacci")
    report = await goals.cancel_goals(registry, "/fibonacci", running.goal_id)
    assert report.canceled_ours == [running.goal_id]
    assert not report.unknown_goal_id
    outcome = await asyncio.wait_for(run, 15.0)
    assert outcome.canceled_by == "cancel_action"
    assert outcome.status == ("canceled" if robot.dialect == "ros2" else "preempted")


async def test_cancel_goals_without_an_id_also_cancels_goals_of_other_clients(
    robot: SimulatedRobot, make_client: MakeClient
) -> None:
    """Cancel-all reaches a goal another client started (ROS 2: hidden cancel_goal service)."""
    ours = await make_client(robot)
    our_goals = GoalRegistry(ours)
    theirs = await make_client(robot)
    their_goals = GoalRegistry(theirs)
    run = asyncio.create_task(
        goals.run_goal(their_goals, "/fibonacci", action_type_for(robot), {"order": LONG_ORDER}, timeout=10.0)
    )
    await robot.wait_for(running_goal_with_feedback)
    report = await goals.cancel_goals(our_goals, "/fibonacci")
    assert report.canceled_ours == []
    if robot.dialect == "ros2":
        assert report.goals_canceling is not None
        assert len(report.goals_canceling) == 1
    outcome = await asyncio.wait_for(run, 15.0)
    assert not outcome.succeeded
    assert outcome.status == ("canceled" if robot.dialect == "ros2" else "preempted")


async def test_cancel_goals_reports_an_unknown_goal_id(
    robot: SimulatedRobot, make_client: MakeClient
) -> None:
    """A goal id that is not one of our running goals is reported as unknown."""
    client = await make_client(robot)
    registry = GoalRegistry(client)
    report = await goals.cancel_goals(registry, "/fibonacci", "not-a-goal-of-ours")
    assert report.unknown_goal_id
    assert report.canceled_ours == []


async def test_a_rejected_ros1_goal_ends_rejected(sim_ros1: SimulatedRobot, make_client: MakeClient) -> None:
    """A goal the actionlib server rejects ends with status "rejected" (5)."""
    client = await make_client(sim_ros1)
    registry = GoalRegistry(client)
    outcome = await goals.run_goal(registry, "/fibonacci", ROS1_TYPE, {"order": -1}, timeout=5.0)
    assert outcome.status == "rejected"
    assert outcome.status_code == 5
    assert not outcome.succeeded


async def test_two_clients_never_mint_the_same_goal_id(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """Goal ids carry a per-client token, because the bridge's goal table is shared by all clients."""
    first: RosbridgeClient = await make_client(sim_ros2)
    second: RosbridgeClient = await make_client(sim_ros2)
    assert first.new_goal_id("/fibonacci") != second.new_goal_id("/fibonacci")


async def test_every_goal_runs_on_a_connection_of_its_own_closed_afterwards(
    robot2: SimulatedRobot, make_client: MakeClient
) -> None:
    """While a goal runs the robot sees a second connection (its lane); it goes away with the goal."""
    client = await make_client(robot2)
    registry = GoalRegistry(client)
    goal = asyncio.create_task(
        running.send_action_goal(registry, "/fibonacci", ROS2_TYPE, {"order": 8}, timeout=10.0)
    )
    await robot2.wait_for(running_goal_with_feedback)
    assert robot2.connection_count == 2
    assert (await goal).status_code == 4
    await robot2.wait_for(lambda _world: robot2.connection_count == 1)


async def test_a_plain_function_can_take_feedback(sim_ros2: SimulatedRobot, make_client: MakeClient) -> None:
    """on_feedback may be a plain function as well as a coroutine function."""
    client = await make_client(sim_ros2)
    registry = GoalRegistry(client)
    seen: list[dict[str, Any]] = []
    result = await running.send_action_goal(
        registry,
        "/fibonacci",
        ROS2_TYPE,
        {"order": 3},
        on_feedback=lambda _goal, values: seen.append(values),
        timeout=5.0,
    )
    assert result.status_code == 4
    assert seen


async def test_cancelling_the_task_running_a_goal_cancels_the_goal_on_the_robot(
    robot: SimulatedRobot, make_client: MakeClient
) -> None:
    """If the caller is cancelled (the MCP request was cancelled), the goal is cancelled too (ROS 1: a cancel
    is published for it) before the cancellation propagates."""
    client = await make_client(robot)
    registry = GoalRegistry(client)
    run = asyncio.create_task(
        goals.run_goal(registry, "/fibonacci", action_type_for(robot), {"order": LONG_ORDER}, timeout=10.0)
    )
    await robot.wait_for(running_goal_with_feedback)
    run.cancel()
    with pytest.raises(asyncio.CancelledError):
        await run
    await robot.wait_for(lambda world: all(g.finished and g.cancel_requested for g in world.goals.values()))
    assert robot.world.goals
    assert registry.running() == []


@pytest.mark.parametrize(
    ("dialect", "timeout", "refusal"),
    [
        # rosbridge 2.x refuses the goal after about a second.
        pytest.param("ros2", 5.0, "No action server available", id="ros2"),
        # actionlib has no refusal: no status messages on <ns>/status within the wait (rounded) tells. The
        # wait is what is left of the timeout when it starts: on a busy machine less than 0.3 s.
        pytest.param(
            "ros1",
            0.3,
            r"no action server at /nowhere: no status messages on /nowhere/status within 0\.[0-3] s ",
            id="ros1",
        ),
    ],
)
async def test_a_goal_for_a_missing_action_server_fails_with_action_error(
    make_sim: MakeSim, make_client: MakeClient, dialect: str, timeout: float, refusal: str
) -> None:
    """A goal for an action nobody serves raises ActionError with the dialect's reason."""
    robot = await make_sim(dialect=dialect)
    client = await make_client(robot)
    registry = GoalRegistry(client)
    with pytest.raises(ActionError, match=refusal):
        await goals.run_goal(registry, "/nowhere", action_type_for(robot), {"order": 1}, timeout=timeout)
    assert registry.running() == []


async def test_a_drop_fails_a_running_goal_with_connection_lost(
    sim: SimulatedRobot, make_client: MakeClient
) -> None:
    """When the bridge drops every connection, a goal (ROS 2: waiting on its lane, ROS 1: followed over
    topics) fails at once with ConnectionLostError and leaves nothing behind."""
    client = await make_client(sim)
    registry = GoalRegistry(client)
    run = asyncio.create_task(
        goals.run_goal(registry, "/fibonacci", action_type_for(sim), {"order": LONG_ORDER}, timeout=20.0)
    )
    await sim.wait_for(running_goal_with_feedback)
    await sim.drop_connections()
    with pytest.raises(ConnectionLostError):
        await asyncio.wait_for(run, 15.0)
    assert registry.running() == []
    assert client.topics.subscriptions == {}
