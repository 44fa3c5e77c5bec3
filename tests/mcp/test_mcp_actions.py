"""publish_action and cancel_action: results, feedback as progress, and cancellation of every kind."""

from __future__ import annotations

import asyncio
import re
from collections.abc import AsyncIterator, Awaitable, Callable

import pytest
from mcp_harness import Session, open_session, text_of, types_for

from rosbridge_mcp_server.sim import GoalRecord, SimulatedRobot

FIB = "/fibonacci"
WAIT = 30.0


def _running(robot: SimulatedRobot) -> list[GoalRecord]:
    return [goal for goal in robot.world.goals.values() if not goal.finished and goal.feedback_count > 0]


async def test_a_goal_succeeds_with_result_feedback_and_progress(
    session: Session, sim: SimulatedRobot
) -> None:
    """Fibonacci order 5 succeeds with the sequence; every feedback arrived as a progress notification."""
    result = await session.ok(
        "publish_action",
        {"action_name": FIB, "action_type": types_for(sim)["fibonacci"], "goal": {"order": 5}},
    )
    data = result.structured_content
    assert data is not None
    assert data["succeeded"] is True
    assert data["status"] == "succeeded"
    assert data["result"] == {"sequence": [0, 1, 1, 2, 3, 5]}
    assert data["feedback_count"] >= 1
    assert data["last_feedback"][-1] == {"sequence": [0, 1, 1, 2, 3, 5]}
    assert data["canceled_by"] is None
    assert len(session.progress) == data["feedback_count"]
    assert [p for p, _, _ in session.progress] == list(range(1, data["feedback_count"] + 1))
    assert all(message and message.startswith("goal ") for _, _, message in session.progress)
    assert f"Goal {data['goal_id']} on {FIB}" in text_of(result)
    assert "succeeded" in text_of(result)


@pytest.mark.parametrize(
    ("dialect", "spelling"),
    [
        ("ros2", "example_interfaces/Fibonacci"),
        ("ros2", "example_interfaces/FibonacciAction"),
        ("ros1", "actionlib_tutorials/Fibonacci"),
        ("ros1", "actionlib_tutorials/action/Fibonacci"),
    ],
)
async def test_every_action_type_spelling_names_the_same_action(
    make_sim: Callable[..., Awaitable[SimulatedRobot]], dialect: str, spelling: str
) -> None:
    """pkg/Name, pkg/action/Name and pkg/NameAction all reach the Fibonacci server, on ROS 2 and ROS 1."""
    robot = await make_sim(dialect=dialect)
    async with open_session(robot.url) as session:
        result = await session.ok(
            "publish_action", {"action_name": FIB, "action_type": spelling, "goal": {"order": 2}}
        )
    assert result.structured_content is not None
    assert result.structured_content["succeeded"] is True
    assert result.structured_content["action_type"] == (
        "example_interfaces/action/Fibonacci" if dialect == "ros2" else "actionlib_tutorials/FibonacciAction"
    )


async def test_an_unknown_action_is_an_error_pointing_at_list_actions(
    session: Session, sim: SimulatedRobot
) -> None:
    """A misspelt action server is named with the close match; no goal is sent."""
    text = await session.error(
        "publish_action",
        {"action_name": "/fibonaci", "action_type": types_for(sim)["fibonacci"], "goal": {"order": 3}},
    )
    assert "No action server /fibonaci is running" in text
    assert "Did you mean /fibonacci?" in text
    assert not sim.world.goals


async def test_a_wrong_action_type_is_refused_naming_the_real_one(
    session: Session, sim: SimulatedRobot
) -> None:
    """Sending a goal of another action type says what type the server has."""
    text = await session.error(
        "publish_action", {"action_name": FIB, "action_type": "nav2_msgs/action/NavigateToPose", "goal": {}}
    )
    assert f"Action {FIB} has type {types_for(sim)['fibonacci']}" in text
    assert not sim.world.goals


async def test_a_goal_that_does_not_fit_names_the_field(session: Session, sim: SimulatedRobot) -> None:
    """A string order is named before any goal is sent."""
    text = await session.error(
        "publish_action",
        {"action_name": FIB, "action_type": types_for(sim)["fibonacci"], "goal": {"order": "five"}},
    )
    assert 'order: expected an integer (int32), got "five"' in text
    assert not sim.world.goals


@pytest.fixture(params=["ros2", "ros1", "humble", "rs"])
async def slow_robot(
    request: pytest.FixtureRequest, make_sim: Callable[..., Awaitable[SimulatedRobot]]
) -> SimulatedRobot:
    """A robot of each dialect (Humble-like, and like rosbridge-server-rs, which lets only the connection
    that started a goal cancel it) whose Fibonacci goals take a while (a step every 0.2 s)."""
    if request.param == "humble":
        return await make_sim(dialect="ros2", in_order=True, action_step=0.2)
    if request.param == "rs":
        return await make_sim(dialect="ros2", server="rs", action_step=0.2)
    return await make_sim(dialect=request.param, action_step=0.2)


@pytest.fixture
async def slow_session(slow_robot: SimulatedRobot) -> AsyncIterator[Session]:
    """A session on the slow robot."""
    async with open_session(slow_robot.url) as opened:
        yield opened


def _long_goal(robot: SimulatedRobot, timeout: float = 60.0) -> dict[str, object]:
    return {
        "action_name": FIB,
        "action_type": types_for(robot)["fibonacci"],
        "goal": {"order": 40},
        "timeout": timeout,
    }


def _goal_id_from_progress(session: Session) -> str:
    """The goal id, as an MCP client learns it from the progress messages of a running publish_action."""
    message = session.progress[0][2] or ""
    match = re.match(r"goal (\S+) feedback 1: ", message)
    assert match is not None, message
    return match.group(1)


async def _the_goal_ended_cancelled(robot: SimulatedRobot) -> GoalRecord:
    await robot.world.wait_for(lambda w: bool(w.goals) and all(g.finished for g in w.goals.values()), WAIT)
    (goal,) = robot.world.goals.values()
    assert goal.cancel_requested
    assert goal.status == (5 if robot.dialect == "ros2" else 2)  # ROS 2 CANCELED, ROS 1 PREEMPTED
    return goal


async def test_a_goal_that_times_out_is_cancelled_and_the_answer_says_so(
    slow_session: Session, slow_robot: SimulatedRobot
) -> None:
    """After its timeout the goal is cancelled on the robot, and the answer says so."""
    result = await slow_session.call("publish_action", _long_goal(slow_robot, timeout=0.5))
    text = text_of(result)
    assert "cancelled because it did not finish within the timeout" in text
    assert result.structured_content is not None
    assert result.structured_content["canceled_by"] == "timeout"
    await _the_goal_ended_cancelled(slow_robot)


@pytest.mark.parametrize("by_id", [True, False], ids=["one-goal", "all-goals"])
async def test_cancel_action_stops_a_goal_while_publish_action_waits(
    slow_session: Session, slow_robot: SimulatedRobot, by_id: bool
) -> None:
    """cancel_action, with the goal id from the progress messages or without one, ends the running goal."""
    goal_call = asyncio.create_task(slow_session.call("publish_action", _long_goal(slow_robot)))
    await slow_robot.world.wait_for(lambda w: bool(slow_session.progress), WAIT)
    goal_id = _goal_id_from_progress(slow_session)
    arguments = {"action_name": FIB, "goal_id": goal_id} if by_id else {"action_name": FIB}
    cancel = await slow_session.ok("cancel_action", arguments)
    result = await asyncio.wait_for(goal_call, WAIT)

    assert cancel.structured_content is not None
    assert cancel.structured_content["canceled_goals"] == [goal_id]
    assert cancel.structured_content["unknown_goal_id"] is False
    data = result.structured_content
    assert data is not None, text_of(result)
    assert data["goal_id"] == goal_id
    assert data["canceled_by"] == "cancel_action"
    assert data["succeeded"] is False
    assert data["status"] == ("canceled" if slow_robot.dialect == "ros2" else "preempted")
    assert "cancelled by cancel_action" in text_of(result)
    await _the_goal_ended_cancelled(slow_robot)


async def test_cancelling_the_mcp_request_cancels_the_goal_on_the_robot(
    slow_session: Session, slow_robot: SimulatedRobot
) -> None:
    """When the MCP client cancels a running publish_action, the goal is cancelled on the robot."""
    goal_call = asyncio.create_task(slow_session.call("publish_action", _long_goal(slow_robot)))
    await slow_robot.world.wait_for(lambda w: bool(_running(slow_robot)), WAIT)
    goal_call.cancel()
    with pytest.raises(asyncio.CancelledError):
        await goal_call
    await _the_goal_ended_cancelled(slow_robot)
    # The session is still usable afterwards.
    await slow_session.ok("list_actions")


async def test_a_goal_running_when_the_connection_drops_is_cancelled_once_it_is_back(
    slow_session: Session, slow_robot: SimulatedRobot
) -> None:
    """publish_action fails at once, saying a cancel will follow; once reconnected the goal is cancelled."""
    goal_call = asyncio.create_task(slow_session.call("publish_action", _long_goal(slow_robot)))
    await slow_robot.world.wait_for(lambda w: bool(_running(slow_robot)), WAIT)
    await slow_robot.drop_connections()
    result = await asyncio.wait_for(goal_call, WAIT)
    assert result.is_error
    text = text_of(result)
    assert f"The connection to rosbridge at {slow_robot.url} dropped while waiting for action goal" in text
    assert "a cancel for it will be sent as soon as the connection is back" in text
    await _the_goal_ended_cancelled(slow_robot)
    # Nothing else is re-sent: the goal itself never reaches the robot a second time.
    assert len(slow_robot.world.goals) == 1


async def test_cancel_action_with_an_unknown_goal_id_says_so(session: Session) -> None:
    """A goal id that is not running is reported as unknown (the cancel is still sent, harmlessly)."""
    result = await session.ok("cancel_action", {"action_name": FIB, "goal_id": "no-such-goal"})
    assert result.structured_content is not None
    assert result.structured_content["unknown_goal_id"] is True
    assert "not a goal publish_action is running now" in text_of(result)


async def test_cancel_action_on_an_unknown_action_is_an_error(session: Session) -> None:
    """There is nothing to cancel on an action nobody serves."""
    text = await session.error("cancel_action", {"action_name": "/navigate"})
    assert "No action server /navigate is running" in text


async def test_the_2026_protocol_carries_progress_and_cancellation_too(
    make_sim: Callable[..., Awaitable[SimulatedRobot]],
) -> None:
    """With the newest protocol revision, feedback is progress and a cancelled call cancels its goal."""
    robot = await make_sim(dialect="ros2", action_step=0.2)
    async with open_session(robot.url, mode="auto") as session:
        assert session.mcp.protocol_version == "2026-07-28"
        done = await session.ok(
            "publish_action",
            {"action_name": FIB, "action_type": types_for(robot)["fibonacci"], "goal": {"order": 2}},
        )
        assert done.structured_content is not None
        assert session.progress, "feedback should arrive as progress"
        goal_call = asyncio.create_task(session.call("publish_action", _long_goal(robot)))
        await robot.world.wait_for(lambda w: bool(_running(robot)), WAIT)
        goal_call.cancel()
        with pytest.raises(asyncio.CancelledError):
            await goal_call
        await robot.world.wait_for(lambda w: all(g.finished for g in w.goals.values()), WAIT)
    cancelled = [g for g in robot.world.goals.values() if g.cancel_requested]
    assert len(cancelled) == 1
    assert cancelled[0].status == 5


async def test_cancelling_every_goal_does_not_read_as_if_ours_went_on(
    make_sim: Callable[..., Awaitable[SimulatedRobot]],
) -> None:
    """The cancel-all answer may leave out our goal (already being canceled, on 2.1.0): the text says so."""
    robot = await make_sim(dialect="ros2", action_step=0.2)
    async with open_session(robot.url) as session:
        goal_call = asyncio.create_task(session.call("publish_action", _long_goal(robot)))
        await robot.world.wait_for(lambda w: bool(session.progress), WAIT)
        cancel = await session.ok("cancel_action", {"action_name": FIB})
        await asyncio.wait_for(goal_call, WAIT)
    text = text_of(cancel)
    assert "a goal already being canceled, as ours may be, is not listed" in text
    await _the_goal_ended_cancelled(robot)


@pytest.mark.parametrize("line", ["2.1.0", "ros1"])
async def test_a_goal_running_when_the_server_stops_is_cancelled_on_a_busy_bridge(
    make_sim: Callable[..., Awaitable[SimulatedRobot]], line: str
) -> None:
    """The server's last cancel is handled before it closes, though a bridge drops a closing link's frames."""
    kilted = {"dialect": "ros2", "in_order": True, "distro": "kilted", "rosapi": "2.1.0"}
    robot = await make_sim(**({"dialect": "ros1"} if line == "ros1" else kilted), action_step=0.2)
    robot.bridge.incoming_delay = 0.05
    async with open_session(robot.url) as session:
        goal_call = asyncio.create_task(session.call("publish_action", _long_goal(robot)))
        await robot.world.wait_for(lambda w: bool(session.progress), WAIT)
    goal_call.cancel()
    await _the_goal_ended_cancelled(robot)
