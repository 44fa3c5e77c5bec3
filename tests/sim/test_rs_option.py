"""``server="rs"``: the simulated robot behaves like rosbridge-server-rs 0.1.6 where a client can tell.

With ``ROSBRIDGE_TEST_URL`` pointing at a real rosbridge-server-rs, the same tests run against it too (a
bridge that does not answer a refused op with a status is skipped: rosbridge_suite's are tested elsewhere).
"""

from __future__ import annotations

import os
from collections.abc import AsyncIterator

import pytest
from rawclient import RawClient

from rosbridge_mcp_server.sim import SimulatedRobot

REAL_URL = os.environ.get("ROSBRIDGE_TEST_URL")
FIB_TYPE = "example_interfaces/action/Fibonacci"


@pytest.fixture(params=["sim", "real"])
async def url(request: pytest.FixtureRequest) -> AsyncIterator[str]:
    """Our robot with ``server="rs"``, or the real bridge when it is one like it."""
    if request.param == "sim":
        async with SimulatedRobot(dialect="ros2", server="rs", action_step=0.1) as robot:
            yield robot.url
        return
    if not REAL_URL:
        pytest.skip("set ROSBRIDGE_TEST_URL=ws://host:port to compare with a real rosbridge-server-rs")
    async with await RawClient.open(REAL_URL) as client:
        await client.send({"op": "cancel_action_goal", "id": "rs_option:probe", "action": "/nobody"})
        told = any(frame.get("op") == "status" for frame in await client.frames_before_barrier())
    if not told:
        pytest.skip("the real bridge is not like rosbridge-server-rs (no status answers)")
    yield REAL_URL


def _goal(rid: str, order: int = 30) -> dict[str, object]:
    return {
        "op": "send_action_goal",
        "id": rid,
        "action": "/fibonacci",
        "action_type": FIB_TYPE,
        "args": {"order": order},
        "feedback": True,
    }


async def test_an_unknown_op_is_answered_with_an_error_status(url: str) -> None:
    """The status names the op and carries its id (rosbridge_suite only logs it)."""
    async with await RawClient.open(url) as client:
        await client.send({"op": "bogus_op", "id": "bg"})
        assert await client.reply("bg") == {
            "op": "status",
            "level": "error",
            "msg": "unknown operation: bogus_op",
            "id": "bg",
        }


async def test_a_subscribe_it_cannot_type_is_answered_with_an_error_status(url: str) -> None:
    """A topic missing from the graph, without a type: "type is required when interface is absent ..."."""
    async with await RawClient.open(url) as client:
        await client.send({"op": "subscribe", "id": "sb", "topic": "/rs_option_no_such_topic"})
        status = await client.reply("sb")
    assert status["op"] == "status"
    assert status["msg"] == "type is required when interface is absent from ROS graph"


async def test_only_the_connection_that_started_a_goal_can_cancel_it(url: str) -> None:
    """Another connection's cancel is refused ("unknown active goal"); the owner's ends it CANCELED, with
    result false and the sequence so far."""
    async with await RawClient.open(url) as owner, await RawClient.open(url) as other:
        await owner.send(_goal("rs_option:g1"))
        await owner.reply("rs_option:g1", op="action_feedback")
        await other.send({"op": "cancel_action_goal", "id": "rs_option:g1", "action": "/fibonacci"})
        refused = await other.reply("rs_option:g1")
        await owner.send({"op": "cancel_action_goal", "id": "rs_option:g1", "action": "/fibonacci"})
        result = await owner.reply("rs_option:g1", op="action_result")
    assert refused == {"op": "status", "level": "error", "msg": "unknown active goal", "id": "rs_option:g1"}
    assert result["result"] is False
    assert result["status"] == 5
    assert result["values"]["sequence"][:2] == [0, 1]


async def test_a_goal_it_cannot_load_ends_aborted_with_result_false(url: str) -> None:
    """An action type it cannot load: result false, status 6 (ABORTED), the reason as values."""
    async with await RawClient.open(url) as client:
        goal = _goal("rs_option:g2") | {"action_type": "no_such_pkg/action/Nothing"}
        await client.send(goal)
        result = await client.reply("rs_option:g2", op="action_result")
    assert (result["result"], result["status"]) == (False, 6)
    assert isinstance(result["values"], str)


async def test_the_goals_of_a_connection_that_closes_are_cancelled() -> None:
    """rosbridge-server-rs cancels a departed connection's goals (rosbridge_suite lets them run on)."""
    async with SimulatedRobot(dialect="ros2", server="rs", action_step=0.1) as robot:
        client = await RawClient.open(robot.url)
        await client.send(_goal("rs_option:g3"))
        await client.reply("rs_option:g3", op="action_feedback")
        await client.close()
        await robot.wait_for(lambda world: world.goals["rs_option:g3"].finished)
        assert robot.world.goals["rs_option:g3"].status == 5
