"""A goal left running on the robot by a dropped connection is cancelled once the connection is back."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Iterator

import pytest
from client_harness import MakeClient, MakeSim

from rosbridge_mcp_server.client import cut_off
from rosbridge_mcp_server.client import goals as client_goals
from rosbridge_mcp_server.errors import ConnectionLostError, GoalTimeoutError
from rosbridge_mcp_server.robot import goals
from rosbridge_mcp_server.robot.goals import GoalRegistry, running
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.world import PublishedMessage, World

ROS2_TYPE = "example_interfaces/action/Fibonacci"
ROS1_TYPE = "actionlib_tutorials/FibonacciAction"
#: 40 steps of 0.2 s: still running long after the drop and the reconnect.
LONG_ORDER = 40
SLOW_STEP = 0.2
WAIT = 30.0

ROBOTS = {
    "jazzy": {"dialect": "ros2"},
    "humble": {"dialect": "ros2", "in_order": True},
    "ros1": {"dialect": "ros1"},
}
#: The status a cancelled running goal ends with: ROS 2 CANCELED, ROS 1 PREEMPTED.
CANCELED = {"ros2": 5, "ros1": 2}


@pytest.fixture(params=list(ROBOTS))
async def robot(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    """A robot of each flavour (Jazzy, Humble in-order, ROS 1) whose goals take a while."""
    return await make_sim(action_step=SLOW_STEP, **ROBOTS[request.param])


class _CancelLog(logging.Handler):
    """Collects the client's warnings, keeps its "Sent a cancel for goal ..." lines apart, wakes waiters."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.warnings: list[str] = []
        self.lines: list[str] = []
        self.errors: list[str] = []
        self._changed = asyncio.Event()

    def emit(self, record: logging.LogRecord) -> None:
        text = record.getMessage()
        self.warnings.append(text)
        if record.levelno >= logging.ERROR:
            self.errors.append(text)
        if text.startswith("Sent a cancel for goal"):
            self.lines.append(text)
        self._changed.set()

    async def wait_for(self, start: str) -> None:
        """Until a warning starting with *start* was logged."""
        async with asyncio.timeout(WAIT):
            while not any(line.startswith(start) for line in self.warnings):
                self._changed.clear()
                await self._changed.wait()

    async def wait_for_goal(self, goal_id: str) -> None:
        """Until the cancel of *goal_id* after a reconnect was logged."""
        await self.wait_for(f"Sent a cancel for goal {goal_id} ")


@pytest.fixture
def cancel_log() -> Iterator[_CancelLog]:
    """The client's and the goals' warnings (not the simulated robot's), for the duration of the test."""
    handler = _CancelLog()
    loggers = [
        logging.getLogger("rosbridge_mcp_server.client"),
        logging.getLogger("rosbridge_mcp_server.robot.goals"),
    ]
    for logger in loggers:
        logger.addHandler(handler)
    try:
        yield handler
    finally:
        for logger in loggers:
            logger.removeHandler(handler)


def action_type_for(robot: SimulatedRobot) -> str:
    """The action type as users of the robot's dialect write it."""
    return ROS2_TYPE if robot.dialect == "ros2" else ROS1_TYPE


def running_with_feedback(goal_id: str) -> Callable[[World], bool]:
    """Goal *goal_id* runs on the robot and has sent feedback."""

    def check(world: World) -> bool:
        goal = world.goals.get(goal_id)
        return goal is not None and not goal.finished and goal.feedback_count >= 1

    return check


def cut_off_ids(registry: GoalRegistry) -> list[str]:
    """The ids of the goals a drop cut off that the client of *registry* still means to cancel, oldest
    first."""
    return registry.client.goals.cut_off


async def start_long_goal(registry: GoalRegistry, robot: SimulatedRobot) -> tuple[str, asyncio.Task[object]]:
    """A long /fibonacci goal through run_goal, once it runs on the robot: its id and its task."""
    goal_id = registry.client.new_goal_id("/fibonacci")
    task: asyncio.Task[object] = asyncio.create_task(
        goals.run_goal(
            registry,
            "/fibonacci",
            action_type_for(robot),
            {"order": LONG_ORDER},
            timeout=60.0,
            goal_id=goal_id,
        )
    )
    await robot.wait_for(running_with_feedback(goal_id), WAIT)
    return goal_id, task


async def test_a_goal_running_at_a_drop_is_cancelled_on_the_robot_once_the_connection_is_back(
    robot: SimulatedRobot, make_client: MakeClient, cancel_log: _CancelLog
) -> None:
    """The goal call fails at once saying a cancel will follow; after the reconnect the goal ends canceled."""
    client = await make_client(robot)
    registry = GoalRegistry(client)
    goal_id, task = await start_long_goal(registry, robot)
    await robot.drop_connections()
    with pytest.raises(ConnectionLostError, match="will be sent as soon as the connection is back") as caught:
        await asyncio.wait_for(task, WAIT)
    assert caught.value.goal_cancel == "pending"
    assert goal_id in str(caught.value)
    await robot.wait_for(lambda world: world.goals[goal_id].finished, WAIT)
    record = robot.world.goals[goal_id]
    assert record.cancel_requested
    assert record.status == CANCELED[robot.dialect]
    assert len(record.sequence) < LONG_ORDER + 1
    await cancel_log.wait_for_goal(goal_id)
    assert cut_off_ids(registry) == []


async def test_a_ros1_cancel_after_a_reconnect_is_published_again_a_moment_later(
    make_sim: MakeSim, make_client: MakeClient
) -> None:
    """rospy often loses a message published right after its publisher is recreated: the cancel goes twice."""
    robot = await make_sim(dialect="ros1", action_step=SLOW_STEP)
    client = await make_client(robot)
    registry = GoalRegistry(client)
    goal_id, task = await start_long_goal(registry, robot)
    await robot.drop_connections()
    with pytest.raises(ConnectionLostError):
        await asyncio.wait_for(task, WAIT)

    def cancels(world: World) -> list[PublishedMessage]:
        return [m for m in world.published.get("/fibonacci/cancel", []) if m.msg.get("id") == goal_id]

    await robot.wait_for(lambda world: len(cancels(world)) >= 2, WAIT)
    first, second = cancels(robot.world)[:2]
    assert first.connection_id == second.connection_id
    assert second.received_at - first.received_at >= client_goals.ROS1_CANCEL_REPEAT_SECONDS * 0.9


async def test_a_goal_that_finished_before_the_drop_is_not_cancelled(
    robot: SimulatedRobot, make_client: MakeClient, cancel_log: _CancelLog
) -> None:
    """Only the goal still running at the drop gets a cancel after the reconnect, not one that had ended."""
    client = await make_client(robot)
    registry = GoalRegistry(client)
    done_id = client.new_goal_id("/fibonacci")
    outcome = await goals.run_goal(
        registry, "/fibonacci", action_type_for(robot), {"order": 2}, timeout=WAIT, goal_id=done_id
    )
    assert outcome.succeeded
    running_id, task = await start_long_goal(registry, robot)
    await robot.drop_connections()
    with pytest.raises(ConnectionLostError):
        await asyncio.wait_for(task, WAIT)
    await robot.wait_for(lambda world: world.goals[running_id].finished, WAIT)
    await cancel_log.wait_for_goal(running_id)
    assert not any(done_id in line for line in cancel_log.lines)
    assert not robot.world.goals[done_id].cancel_requested
    cancels = [m.msg.get("id") for m in robot.world.published.get("/fibonacci/cancel", [])]
    assert done_id not in cancels
    assert cut_off_ids(registry) == []


async def test_a_restarted_robot_that_lost_the_goal_gets_a_harmless_cancel_and_a_log_line(
    robot: SimulatedRobot, make_client: MakeClient, cancel_log: _CancelLog
) -> None:
    """A robot restart loses its goals: the cancel after the reconnect raises nothing, it is only logged."""
    client = await make_client(robot)
    registry = GoalRegistry(client)
    goal_id, task = await start_long_goal(registry, robot)
    await robot.stop()
    with pytest.raises(ConnectionLostError):
        await asyncio.wait_for(task, WAIT)
    await robot.start()
    await client.wait_connected(WAIT)
    await cancel_log.wait_for_goal(goal_id)
    assert cancel_log.errors == []
    assert cut_off_ids(registry) == []
    outcome = await goals.run_goal(registry, "/fibonacci", action_type_for(robot), {"order": 1}, timeout=WAIT)
    assert outcome.succeeded


async def test_a_goal_orphaned_too_long_ago_is_forgotten_without_a_cancel(
    sim_ros2: SimulatedRobot, make_client: MakeClient, cancel_log: _CancelLog, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Past the age limit a surprise cancel would stop whatever the robot does now: it is logged, not sent."""
    monkeypatch.setattr(cut_off, "ORPHAN_MAX_AGE_SECONDS", 0.0)
    client = await make_client(sim_ros2)
    registry = GoalRegistry(client)
    goal_id = client.new_goal_id("/fibonacci")
    await sim_ros2.stop()
    client.goals.remember("/fibonacci", goal_id, 2)
    await sim_ros2.start()
    await client.wait_connected(WAIT)
    await cancel_log.wait_for(f"Not cancelling goal {goal_id}")
    assert cut_off_ids(registry) == []
    assert not any(goal_id in line for line in cancel_log.lines)


async def test_at_most_a_bounded_number_of_orphaned_goals_are_remembered(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """Beyond the limit the oldest orphaned goal is forgotten, so an outage cannot grow memory."""
    client = await make_client(sim_ros2)
    registry = GoalRegistry(client)
    await sim_ros2.stop()
    await client.wait_disconnected(WAIT)
    ids = [f"goal-{n}" for n in range(cut_off.ORPHAN_LIMIT + 1)]
    for goal_id in ids:
        client.goals.remember("/fibonacci", goal_id, 2)
    assert cut_off_ids(registry) == ids[1:]


@pytest.fixture(params=["jazzy", "humble"])
async def robot2(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    """A ROS 2 robot, threaded (Jazzy) and in-order (Humble), whose goals take a while."""
    return await make_sim(action_step=SLOW_STEP, **ROBOTS[request.param])


async def test_when_only_the_goals_lane_drops_the_cancel_goes_out_at_once_on_the_main_connection(
    robot2: SimulatedRobot, make_client: MakeClient, cancel_log: _CancelLog
) -> None:
    """The main connection stays up: the goal is cancelled right away; the error says a cancel was sent."""
    client = await make_client(robot2)
    registry = GoalRegistry(client)
    goal_id, task = await start_long_goal(registry, robot2)
    main_id, lane_id = sorted(robot2.bridge.connections)
    await robot2.bridge.connections[lane_id].ws.close(1001, "only the lane drops")
    with pytest.raises(ConnectionLostError, match="a cancel for the goal was sent, so it stops") as caught:
        await asyncio.wait_for(task, WAIT)
    assert caught.value.goal_cancel == "sent"
    await robot2.wait_for(lambda world: world.goals[goal_id].finished, WAIT)
    assert robot2.world.goals[goal_id].status == CANCELED["ros2"]
    assert cut_off_ids(registry) == []
    assert client.connections_made == 1
    assert main_id in robot2.bridge.connections
    assert cancel_log.lines == []


async def test_a_goal_timing_out_while_only_its_lane_is_up_is_remembered_only_on_an_in_order_bridge(
    robot2: SimulatedRobot, make_client: MakeClient
) -> None:
    """With the main connection down the timeout's cancel goes on the lane, which Humble reads too late."""
    # A long backoff keeps the main connection down past the goal's deadline.
    client = await make_client(robot2, reconnect_min=60.0, reconnect_max=60.0)
    registry = GoalRegistry(client)
    goal_id = client.new_goal_id("/fibonacci")
    task = asyncio.create_task(
        running.send_action_goal(
            registry, "/fibonacci", ROS2_TYPE, {"order": LONG_ORDER}, timeout=1.0, goal_id=goal_id
        )
    )
    await robot2.wait_for(running_with_feedback(goal_id), WAIT)
    main_id, _lane_id = sorted(robot2.bridge.connections)
    await robot2.bridge.connections[main_id].ws.close(1001, "only the main connection drops")
    await client.wait_disconnected(WAIT)
    with pytest.raises(GoalTimeoutError) as caught:
        await asyncio.wait_for(task, WAIT)
    if robot2.bridge.config.in_order:
        assert caught.value.status is None
        assert cut_off_ids(registry) == [goal_id]
        assert not robot2.world.goals[goal_id].cancel_requested
    else:
        assert caught.value.status == CANCELED["ros2"]
        assert cut_off_ids(registry) == []
