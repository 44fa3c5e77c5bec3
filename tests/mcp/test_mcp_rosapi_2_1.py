"""Every tool against a simulated rosbridge 2.1.0 on Jazzy with its defaults, as the real labs behave.

rosapi 2.1.0 names TypeDef fields with a leading underscore, has no action_type, hides the hidden action
services, and the bridge handles each connection in order although the distro is Jazzy.
"""

from __future__ import annotations

import io
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import pytest
from mcp_harness import Session, open_session, text_of

from rosbridge_mcp_server.cli.check import run_check
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.graph import ServiceEntry

CMD_VEL = "/turtle1/cmd_vel"
TWIST = "geometry_msgs/msg/Twist"


@pytest.fixture
async def jazzy_2_1(make_sim: Callable[..., Awaitable[SimulatedRobot]]) -> SimulatedRobot:
    """rosbridge 2.1.0 on Jazzy with its launch defaults."""
    return await make_sim(dialect="ros2", in_order=True, distro="jazzy", rosapi="2.1.0")


@pytest.fixture
async def old(jazzy_2_1: SimulatedRobot) -> AsyncIterator[Session]:
    """A session on it."""
    async with open_session(jazzy_2_1.url) as opened:
        yield opened


async def test_the_turtle_is_driven_with_a_twist_as_a_model_writes_it(
    jazzy_2_1: SimulatedRobot, old: Session
) -> None:
    """{"linear": {"x": 1.0}, "angular": {"z": 0.5}} is checked against _linear/_angular TypeDefs and sent."""
    twist = {"linear": {"x": 1.0}, "angular": {"z": 0.5}}
    await old.ok("publish_topic", {"topic": CMD_VEL, "message_type": TWIST, "message": twist})
    await jazzy_2_1.world.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) == 1)
    received = jazzy_2_1.world.published[CMD_VEL][0].msg
    assert (received["linear"]["x"], received["angular"]["z"]) == (1.0, 0.5)


async def test_a_wrong_field_is_named_with_the_names_the_bridge_takes(old: Session) -> None:
    """The refusal suggests linear, never _linear, and its example uses plain names."""
    text = await old.error(
        "publish_topic", {"topic": CMD_VEL, "message_type": TWIST, "message": {"linaer": {"x": 1.0}}}
    )
    assert "did you mean linear?" in text
    assert "_linear" not in text
    assert "_x" not in text


async def test_a_service_request_is_checked_with_plain_names(old: Session) -> None:
    """/add_two_ints {"a": 2, "b": 3} answers 5 (its request TypeDef lists _a and _b)."""
    result = await old.ok(
        "publish_service",
        {
            "service": "/add_two_ints",
            "service_type": "example_interfaces/srv/AddTwoInts",
            "request": {"a": 2, "b": 3},
        },
    )
    assert result.structured_content is not None
    assert result.structured_content["response"] == {"sum": 5}


async def test_list_actions_is_typed_without_rosapi_action_type(old: Session) -> None:
    """The Fibonacci server is typed from the bridge's refusal of a send_goal probe."""
    result = await old.ok("list_actions")
    assert result.structured_content is not None
    assert result.structured_content["actions"] == [
        {"name": "/fibonacci", "type": "example_interfaces/action/Fibonacci"}
    ]
    assert "type unknown" not in text_of(result)


async def test_check_says_what_the_tools_will_meet(jazzy_2_1: SimulatedRobot) -> None:
    """check finds the slot-named TypeDefs readable, the calls in order (measured) and the action typed."""
    out = io.StringIO()
    code = await run_check(Config(url=jazzy_2_1.url), out)
    text = out.getvalue()
    assert code == 0, text
    assert "rosapi names fields _linear, _angular: read as linear, angular" in text
    assert "[ok  ] concurrency: a slow service call holds up later calls on its connection" in text
    assert "action types: known (/fibonacci is example_interfaces/action/Fibonacci)" in text


async def test_a_goal_with_a_wrong_field_is_refused_in_whole_sentences(old: Session) -> None:
    """Without action details the bridge itself refuses the goal; its text ends before the advice starts."""
    fibonacci = "example_interfaces/action/Fibonacci"
    arguments = {"action_name": "/fibonacci", "action_type": fibonacci, "goal": {"ordr": 5}}
    text = await old.error("publish_action", arguments)
    assert "does not have a field ordr. Check the action name" in text


async def test_an_action_type_service_of_another_bridge_that_fails_is_passed_over(
    jazzy_2_1: SimulatedRobot,
) -> None:
    """Two bridges on one graph: rosapi 2.1.0 lists the other's newer /rosapi/action_type, which 2.1.0 cannot
    call (it cannot load its type). list_actions and publish_action take the way they use on 2.1.0."""

    async def never_reached(request: dict[str, Any]) -> dict[str, Any]:
        raise AssertionError("2.1.0 cannot load this service's type, so it never calls it")

    jazzy_2_1.graph.add_service(
        ServiceEntry("/rosapi/action_type", "rosapi_msgs/srv/GetActionType", "/rosapi_rs", never_reached)
    )
    fibonacci = "example_interfaces/action/Fibonacci"
    async with open_session(jazzy_2_1.url) as session:
        assert "/rosapi/action_type" in (await session.ros.call_service("/rosapi/services"))["services"]
        actions = (await session.ok("list_actions")).structured_content
        assert actions is not None
        assert {"name": "/fibonacci", "type": fibonacci} in actions["actions"]
        arguments = {"action_name": "/fibonacci", "action_type": fibonacci, "goal": {"order": 2}}
        result = (await session.ok("publish_action", arguments)).structured_content
    assert result is not None
    assert result["succeeded"] is True
    assert jazzy_2_1.world.refused_calls.get("/rosapi/action_type")
