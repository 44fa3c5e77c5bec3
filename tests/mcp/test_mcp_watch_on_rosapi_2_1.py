"""The watch tools on a bridge like rosbridge 2.1.0 (the Jazzy/Kilted labs): what its rosapi lacks, and the
questions that kill or deadlock it."""

from __future__ import annotations

from collections.abc import AsyncIterator, Awaitable, Callable

import pytest
from mcp_harness import Session, open_session, parameter_names

from rosbridge_mcp_server.sim import SimulatedRobot


@pytest.fixture
async def old_robot(make_sim: Callable[..., Awaitable[SimulatedRobot]]) -> SimulatedRobot:
    """ROS 2 with rosapi 2.1.0: underscored TypeDef fields, no interfaces or action details, in-order."""
    return await make_sim(dialect="ros2", in_order=True, distro="kilted", rosapi="2.1.0")


@pytest.fixture
async def old(old_robot: SimulatedRobot) -> AsyncIterator[Session]:
    """An MCP session on it."""
    async with open_session(old_robot.url) as session:
        yield session


async def test_a_message_type_reads_with_plain_field_names(old: Session) -> None:
    """Twist's TypeDef says _linear/_angular and lists SLOT_TYPES; the outline says linear/angular."""
    data = (await old.ok("describe_type", {"type_name": "geometry_msgs/msg/Twist"})).structured_content
    assert data is not None
    assert data["parts"][0]["outline"][0] == "linear: geometry_msgs/Vector3"
    assert data["parts"][0]["constants"] == {}
    assert set(data["example"]) == {"linear", "angular"}


async def test_a_service_type_in_use_is_described_and_rosapi_lives(
    old: Session, old_robot: SimulatedRobot
) -> None:
    """SetBool (served by /set_enabled) is described; rosapi is still alive afterwards."""
    data = (await old.ok("describe_type", {"type_name": "std_srvs/srv/SetBool"})).structured_content
    assert data is not None
    assert data["parts"][1]["outline"] == ["success: bool", "message: string"]
    assert not old_robot.rosapi_node.dead


async def test_a_service_type_not_in_use_is_not_asked_about(old: Session, old_robot: SimulatedRobot) -> None:
    """A service type no running service has is refused before rosapi is asked (asking would kill it)."""
    text = await old.error("describe_type", {"type_name": "rospy_tutorials/srv/AddTwoInts"})
    assert "No running service has the type rospy_tutorials/srv/AddTwoInts" in text
    assert not old_robot.rosapi_node.dead


async def test_an_action_type_says_this_rosapi_cannot_describe_it(old: Session) -> None:
    """No action details on 2.1.0: the error says so and points at list_actions."""
    text = await old.error("describe_type", {"type_name": "example_interfaces/action/Fibonacci"})
    assert "cannot describe action types" in text
    assert "list_actions" in text


async def test_parameters_never_deadlock_rosapi(old: Session, old_robot: SimulatedRobot) -> None:
    """rosapi's own parameter, a missing one and a set all go through the nodes' services; rosapi lives."""
    own = (await old.ok("get_parameter", {"name": "/rosapi:use_sim_time"})).structured_content
    assert own is not None
    assert own["value"] is False
    assert "has no parameter 'nope'" in await old.error("get_parameter", {"name": "/turtlesim:nope"})
    written = (
        await old.ok("set_parameter", {"name": "/turtlesim:background_g", "value": 10})
    ).structured_content
    assert written is not None
    assert written["value"] == 10
    names = (await old.ok("list_parameters", {"node": "/turtlesim"})).structured_content
    assert names is not None
    assert "/turtlesim:background_g" in parameter_names(names)
    assert not old_robot.rosapi_node.dead
    await old.ok("list_nodes")


async def test_fields_are_checked_against_underscored_typedefs(old: Session) -> None:
    """fields ["x"] works and ["pose"] is refused on a type whose TypeDef says _x, _y, _theta."""
    result = await old.ok("subscribe_topic", {"topic": "/turtle1/pose", "fields": ["x"]})
    assert list((result.structured_content or {})["messages"][0]["message"]) == ["x"]
    assert "there is no 'pose'" in await old.error(
        "subscribe_topic", {"topic": "/turtle1/pose", "fields": ["pose"]}
    )
