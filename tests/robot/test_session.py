"""A robot session: made once per robot, it owns the goals and the service-type warm-up of its client."""

from __future__ import annotations

import asyncio

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.robot.approval import ALLOW_ALL
from rosbridge_mcp_server.robot.goals import run_goal
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.robot.warm_up import ServiceTypeWarmUp
from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 30.0
FIBONACCI = "example_interfaces/action/Fibonacci"
#: The background learning asks rosapi one service at a time: generous on a loaded machine.
WARM_UP_WAIT = 60.0


async def test_asking_twice_to_learn_the_service_types_starts_one_warm_up(sim_ros2: SimulatedRobot) -> None:
    """A second learn_service_types() is the first one: the client has one warm-up, which runs to its end."""
    client = RosbridgeClient(sim_ros2.url, request_timeout=WAIT)
    robot = RobotSession(client, ALLOW_ALL)
    warm_up = robot.learn_service_types()
    assert robot.learn_service_types() is warm_up
    async with client:
        await client.wait_connected(WAIT)
        await asyncio.wait_for(warm_up.done.wait(), WARM_UP_WAIT)
    assert [w for w in client.watchers if isinstance(w, ServiceTypeWarmUp)] == [warm_up]
    assert sim_ros2.world.service_calls.get("/rosapi/service_type", 0) > 0


async def test_the_goals_of_a_session_are_its_client_s_and_no_one_else_s(sim_ros2: SimulatedRobot) -> None:
    """Two robot sessions on two clients keep their goals apart: a goal one runs is not the other's."""
    first = RobotSession(RosbridgeClient(sim_ros2.url, request_timeout=WAIT), ALLOW_ALL)
    second = RobotSession(RosbridgeClient(sim_ros2.url, request_timeout=WAIT), ALLOW_ALL)
    async with first.client, second.client:
        await first.client.wait_connected(WAIT)
        await second.client.wait_connected(WAIT)
        running = asyncio.create_task(
            run_goal(
                first.goals, "/fibonacci", "example_interfaces/action/Fibonacci", {"order": 40}, timeout=20.0
            )
        )
        await sim_ros2.wait_for(lambda world: any(g.feedback_count >= 1 for g in world.goals.values()), WAIT)
        [goal] = first.goals.running("/fibonacci")
        assert goal.goal_id in sim_ros2.world.goals
        assert second.goals.running() == []
        running.cancel()
        await asyncio.gather(running, return_exceptions=True)
        assert first.goals.running() == []


async def test_the_log_is_kept_after_the_graph_first_fails_to_answer(sim_ros2: SimulatedRobot) -> None:
    """A bridge that cannot list its topics at connect (rosapi busy or not up yet): the log keeper asks again
    and then follows /rosout, instead of keeping no log until the next reconnect."""
    topics = sim_ros2.graph.remove_service("/rosapi/topics")
    assert topics is not None
    robot = RobotSession(RosbridgeClient(sim_ros2.url, request_timeout=WAIT), ALLOW_ALL)
    keeper = robot.keep_logs()
    async with robot.client:
        await robot.client.wait_connected(WAIT)
        await asyncio.wait_for(keeper.looked.wait(), WAIT)
        assert not keeper.ready.is_set()
        sim_ros2.graph.add_service(topics)
        await asyncio.wait_for(keeper.ready.wait(), WAIT)
    assert keeper.source == "/rosout"
