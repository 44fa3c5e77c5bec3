"""Every tool on a bridge like rosbridge-server-rs 0.1.6 (the simulated robot's ``server="rs"``), and
cancels of goals another client started, on it and on rosbridge_suite."""

from __future__ import annotations

import io
import json
from collections.abc import AsyncIterator

import pytest
from mcp_harness import Session, open_session, parameter_names, text_of, types_for
from websockets.asyncio.client import ClientConnection, connect

from rosbridge_mcp_server.cli.check import run_check
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.actions import ActionServer
from rosbridge_mcp_server.sim.world import World

FIB = "/fibonacci"
WAIT = 30.0


@pytest.fixture
async def rs_robot(make_sim: object) -> SimulatedRobot:
    """A robot behind a bridge like rosbridge-server-rs, whose Fibonacci goals take a while."""
    return await make_sim(dialect="ros2", server="rs", action_step=0.2)  # type: ignore[operator]


@pytest.fixture
async def rs(rs_robot: SimulatedRobot) -> AsyncIterator[Session]:
    """A session on it."""
    async with open_session(rs_robot.url) as opened:
        yield opened


async def _foreign_goal(robot: SimulatedRobot, rid: str) -> ClientConnection:
    """Another client (a plain WebSocket) starts a long Fibonacci goal with rosbridge id *rid*."""
    other = await connect(robot.url, compression=None)
    goal = {"order": 40}
    fib_type = types_for(robot)["fibonacci"]
    await other.send(
        json.dumps(
            {"op": "send_action_goal", "id": rid, "action": FIB, "action_type": fib_type, "args": goal}
        )
    )
    await robot.world.wait_for(lambda world: rid in world.goals and world.goals[rid].feedback_count > 0, WAIT)
    return other


def _uuid_of(robot: SimulatedRobot, rid: str) -> str:
    server = robot.graph.actions[FIB]
    assert isinstance(server, ActionServer)
    return next(uuid.hex() for uuid, handle in server.goals.items() if handle.record.goal_id == rid)


def _canceled(rid: str) -> object:
    def check(world: World) -> bool:
        return world.goals[rid].finished and world.goals[rid].status == 5

    return check


async def test_the_server_judges_the_bridge_by_its_answers_not_by_a_node_of_that_name(
    rs: Session, rs_robot: SimulatedRobot
) -> None:
    """Its error status for a cancel nobody could own tells it calls run side by side: no lanes, no probe
    service, and the bridge node's parameters are never asked."""
    info = await rs.ros.ros_info()
    assert info.status_replies
    assert await rs.ros.ordering_known(0.0)
    assert rs.ros.calls_share_connection
    asked = rs_robot.world.service_calls
    assert not any(name.startswith("/rosbridge_mcp_check_") for name in asked)
    assert not any(name.endswith("/get_parameters") for name in asked)
    await rs.ok("list_topics")
    assert rs.ros.lanes.opened == 0


async def test_a_goal_another_client_started_is_cancelled_by_its_uuid(
    rs: Session, rs_robot: SimulatedRobot
) -> None:
    """Given its UUID, the goal is cancelled through the action's own cancel_goal service, which every
    bridge reaches; the answer says the action server is canceling it."""
    other = await _foreign_goal(rs_robot, "other:1")
    try:
        uuid = _uuid_of(rs_robot, "other:1")
        result = await rs.ok("cancel_action", {"action_name": FIB, "goal_id": uuid})
        await rs_robot.world.wait_for(_canceled("other:1"), WAIT)
    finally:
        await other.close()
    assert result.structured_content is not None
    assert result.structured_content["goals_canceling"] == [uuid]
    assert "It is canceling that goal" in text_of(result)


async def test_a_goal_another_client_started_cannot_be_cancelled_by_its_rosbridge_id_and_the_answer_says_why(
    rs: Session, rs_robot: SimulatedRobot
) -> None:
    """The bridge refuses ("unknown active goal"): an error naming the ways that work, the goal runs on."""
    other = await _foreign_goal(rs_robot, "other:2")
    try:
        text = await rs.error("cancel_action", {"action_name": FIB, "goal_id": "other:2"})
        assert not rs_robot.world.goals["other:2"].cancel_requested
    finally:
        await other.close()
    assert "Goal other:2 on /fibonacci was not cancelled: the bridge refused (unknown active goal)" in text
    assert "Give the goal's UUID instead" in text
    assert "omit goal_id to cancel every goal" in text
    assert (await rs.ros.capabilities()).cancel_by_owner_only


async def test_on_rosbridge_suite_a_goal_another_client_started_is_cancelled_by_its_rosbridge_id(
    make_sim: object,
) -> None:
    """rosbridge_suite keeps one goal table for the process: the id alone reaches the goal, silently."""
    robot: SimulatedRobot = await make_sim(dialect="ros2", action_step=0.2)  # type: ignore[operator]
    async with open_session(robot.url) as session:
        other = await _foreign_goal(robot, "other:3")
        try:
            result = await session.ok("cancel_action", {"action_name": FIB, "goal_id": "other:3"})
            await robot.world.wait_for(_canceled("other:3"), WAIT)
        finally:
            await other.close()
    assert result.structured_content is not None
    assert result.structured_content["unknown_goal_id"] is True


async def test_a_goal_cancelled_on_rs_ends_canceled_though_its_result_says_false(
    rs: Session, rs_robot: SimulatedRobot
) -> None:
    """rosbridge-server-rs sends result false with the CANCELED status and the result: a cancelled goal."""
    fib_type = types_for(rs_robot)["fibonacci"]
    arguments = {"action_name": FIB, "action_type": fib_type, "goal": {"order": 40}, "timeout": 0.5}
    result = await rs.call("publish_action", arguments)
    assert result.structured_content is not None, text_of(result)
    assert result.structured_content["status"] == "canceled"
    assert result.structured_content["canceled_by"] == "timeout"
    assert result.structured_content["result"]["sequence"][:3] == [0, 1, 1]


async def test_a_missing_service_is_named_in_a_sentence_the_model_can_act_on(rs: Session) -> None:
    """'type is required when interface is absent from ROS graph' becomes: not in the graph, list_services."""
    arguments = {"service": "/no_such_service", "service_type": "std_srvs/srv/Trigger", "request": {}}
    text = await rs.error("publish_service", arguments)
    assert "/no_such_service" in text
    assert "list_services" in text


async def test_every_read_tool_answers_on_rs(rs: Session, rs_robot: SimulatedRobot) -> None:
    """The listing, watching and parameter tools all answer on it."""
    for tool, arguments in [
        ("list_topics", {}),
        ("list_services", {}),
        ("list_actions", {}),
        ("list_nodes", {}),
        ("get_topic_info", {"topic": "/chatter"}),
        ("subscribe_topic", {"topic": "/chatter", "count": 1}),
        ("describe_type", {"type_name": "geometry_msgs/msg/Twist"}),
        ("list_parameters", {"node": "/turtlesim"}),
        ("get_parameter", {"name": "/turtlesim:background_r"}),
    ]:
        await rs.ok(tool, arguments)
    actions = (await rs.ok("list_actions")).structured_content
    assert actions is not None
    assert {"name": FIB, "type": types_for(rs_robot)["fibonacci"]} in actions["actions"]


async def test_check_says_what_it_judged_of_the_bridge(rs_robot: SimulatedRobot) -> None:
    """check names the implementation it can tell, the cancel path and the measured concurrency."""
    out = io.StringIO()
    code = await run_check(Config(url=rs_robot.url), out)
    text = out.getvalue()
    assert code == 0, text
    assert "implementation: answers a refused op with an error status (rosbridge-server-rs does" in text
    assert "cancelled by its UUID through <action>/_action/cancel_goal, not by its rosbridge id" in text
    assert "run side by side (measured now; the server knew: from the bridge's status answers)" in text


async def test_every_parameter_is_listed_with_one_rosapi_call_where_that_is_safe(
    rs: Session, rs_robot: SimulatedRobot
) -> None:
    """On it rosapi's get_param_names answers (on rosapi 2.1.0 it kills rosapi): one call lists them all."""
    before = dict(rs_robot.world.service_calls)
    names = (await rs.ok("list_parameters")).structured_content
    assert names is not None
    assert "/turtlesim:background_r" in parameter_names(names)
    asked = {
        k: v - before.get(k, 0) for k, v in rs_robot.world.service_calls.items() if v != before.get(k, 0)
    }
    assert asked == {"/rosapi/get_param_names": 1}
