"""The client against a bridge like rosbridge-server-rs 0.1.6 (the simulated robot's ``server="rs"``)."""

from __future__ import annotations

import asyncio
import logging

import pytest
from client_harness import MakeClient, MakeSim

from rosbridge_mcp_server.errors import Advice, GoalTimeoutError, Hint, ServiceError
from rosbridge_mcp_server.robot.goals import GoalRegistry, running
from rosbridge_mcp_server.server.advice import advised


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is done with the answers is tested."""
    return True


async def test_a_refused_subscribe_is_logged_with_the_bridges_words(
    make_sim: MakeSim, make_client: MakeClient, caplog: pytest.LogCaptureFixture
) -> None:
    """Its error status for a subscribe nobody waits on is a warning naming the reason, not lost."""
    robot = await make_sim(dialect="ros2", server="rs")
    client = await make_client(robot)
    with caplog.at_level(logging.WARNING, logger="rosbridge_mcp_server.client"):
        sub = client.subscribe("/no_such_topic")
        await sub.open()
        await client.call_service("/rosapi/get_time")  # a barrier: the refusal came before its answer
        await sub.close()
    refused = [r.getMessage() for r in caplog.records if "the bridge refused" in r.getMessage()]
    assert refused
    assert "type is required when interface is absent from ROS graph" in refused[0]


async def test_a_missing_service_fails_with_a_sentence_naming_it(
    make_sim: MakeSim, make_client: MakeClient
) -> None:
    """The bridge's "type is required ..." becomes: the service is not in the graph, check list_services."""
    robot = await make_sim(dialect="ros2", server="rs")
    client = await make_client(robot)
    with pytest.raises(ServiceError) as caught:
        await client.call_service("/no_such_service")
    assert caught.value.not_in_graph
    assert str(caught.value).startswith("Service /no_such_service is not in the ROS graph")
    # What to try is a fact the MCP edge words (tests/mcp/test_mcp_rs_bridge.py sees it name list_services).
    assert caught.value.hint == Hint(Advice.SERVICE_NAME)
    assert advised(caught.value).endswith(
        "(the bridge said: type is required when interface is absent from ROS graph); check the name with "
        "list_services"
    )


async def test_a_goal_timing_out_is_cancelled_on_its_own_connection_without_a_warning(
    make_sim: MakeSim, make_client: MakeClient, caplog: pytest.LogCaptureFixture
) -> None:
    """The lane's cancel ends the goal CANCELED; the refusal of the main connection's copy is not logged."""
    robot = await make_sim(dialect="ros2", server="rs", action_step=0.1)
    client = await make_client(robot)
    registry = GoalRegistry(client)
    with caplog.at_level(logging.WARNING, logger="rosbridge_mcp_server"):
        with pytest.raises(GoalTimeoutError) as caught:
            await running.send_action_goal(
                registry, "/fibonacci", "example_interfaces/Fibonacci", {"order": 40}, timeout=0.5
            )
        await client.call_service("/rosapi/get_time")  # a barrier: the refusal came before its answer
    assert caught.value.status == 5
    ours = [r for r in caplog.records if not r.name.startswith("rosbridge_mcp_server.sim")]
    assert not [r.getMessage() for r in ours if r.levelno >= logging.WARNING]


async def test_a_cancel_on_the_main_connection_alone_does_not_reach_its_goal_and_says_so(
    make_sim: MakeSim, make_client: MakeClient
) -> None:
    """Only the goal's own connection may cancel it there: the main connection's copy is refused and the
    client says it does not reach the goal; the lane's copy ends it CANCELED."""
    robot = await make_sim(dialect="ros2", server="rs", action_step=0.05)
    client = await make_client(robot)
    registry = GoalRegistry(client)
    goal_task = asyncio.create_task(
        running.send_action_goal(
            registry, "/fibonacci", "example_interfaces/Fibonacci", {"order": 400}, timeout=30
        )
    )
    try:
        await robot.wait_for(lambda world: any(g.feedback_count >= 1 for g in world.goals.values()))
        [goal] = registry.running("/fibonacci")
        alone = await client.goals.cancel(goal.action, goal.goal_id, timeout=3.0)
        assert alone.refused is not None
        [sim_goal] = robot.world.goals.values()
        assert not sim_goal.cancel_requested
        assert not sim_goal.finished
        handle = client.goals.handle(goal.goal_id)
        assert handle is not None
        both = await handle.cancel()
        assert (both.on_main, both.on_lane, both.reaches) == (True, True, True)
        ended = await asyncio.wait_for(goal_task, 15.0)
        assert ended.status_code == 5
    finally:
        goal_task.cancel()
        await asyncio.gather(goal_task, return_exceptions=True)
