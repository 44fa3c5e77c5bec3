"""publish_service: a call's response, the bridge's failure text, and requests checked before the call."""

from __future__ import annotations

import asyncio
import json
import re
from typing import Any

import websockets
from mcp_harness import Session, service_rows, types_for

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.sim import SimulatedRobot


async def test_a_service_call_returns_its_response(session: Session, sim: SimulatedRobot) -> None:
    """/add_two_ints with a=2, b=3 answers sum 5, in text and structured content."""
    result = await session.ok(
        "publish_service",
        {
            "service": "/add_two_ints",
            "service_type": types_for(sim)["add_two_ints"],
            "request": {"a": 2, "b": 3},
        },
    )
    assert result.structured_content == {
        "service": "/add_two_ints",
        "service_type": types_for(sim)["add_two_ints"],
        "response": {"sum": 5},
    }
    assert sim.world.service_calls["/add_two_ints"] == 1


async def test_an_empty_request_works_for_trigger_and_empty_services(
    session: Session, sim: SimulatedRobot
) -> None:
    """std_srvs Empty and SetBool calls change the robot; {} and an omitted request are both fine."""
    await session.ok(
        "publish_service",
        {"service": "/set_enabled", "service_type": types_for(sim)["set_bool"], "request": {"data": False}},
    )
    await sim.world.wait_for(lambda w: not w.enabled)
    await session.ok(
        "publish_service", {"service": "/reset", "service_type": types_for(sim)["empty_srv"], "request": {}}
    )
    await session.ok("publish_service", {"service": "/clear", "service_type": types_for(sim)["empty_srv"]})
    assert sim.world.service_calls["/reset"] == 1
    assert sim.world.service_calls["/clear"] == 1


async def test_an_unknown_service_is_an_error_with_a_suggestion(
    session: Session, sim: SimulatedRobot
) -> None:
    """A misspelt service is named, with the close match and a pointer to list_services; nothing is called."""
    text = await session.error(
        "publish_service",
        {"service": "/add_two_int", "service_type": types_for(sim)["add_two_ints"], "request": {}},
    )
    assert "Service /add_two_int is not offered by any node" in text
    assert "Did you mean /add_two_ints?" in text
    assert "list_services" in text


async def test_a_request_that_does_not_fit_is_refused_before_the_call(
    session: Session, sim: SimulatedRobot
) -> None:
    """A float for an int64 field is named, and the service is not called."""
    text = await session.error(
        "publish_service",
        {
            "service": "/add_two_ints",
            "service_type": types_for(sim)["add_two_ints"],
            "request": {"a": 2.5, "c": 1},
        },
    )
    assert "a: expected an integer (int64), got 2.5" in text
    assert "c: no such field" in text
    assert "The service was not called" in text
    assert "/add_two_ints" not in sim.world.service_calls


async def test_the_wrong_service_type_is_refused_naming_the_real_one(
    session: Session, sim: SimulatedRobot
) -> None:
    """Calling /add_two_ints as a Trigger is an error that gives its real type."""
    text = await session.error(
        "publish_service",
        {"service": "/add_two_ints", "service_type": types_for(sim)["trigger"], "request": {}},
    )
    assert f"Service /add_two_ints has type {types_for(sim)['add_two_ints']}" in text


#: rosapi's set_param with a value that is not JSON: the call's arguments on each dialect, and what the error
#: must say (every pattern matches).
NOT_JSON_SET_PARAM: dict[str, tuple[dict[str, Any], list[str]]] = {
    # A rospy service that raises is reported with rosbridge's own error text.
    "ros1": (
        {"service_type": "rosapi/SetParam", "request": {"name": "/x", "value": "not json"}},
        [
            re.escape(
                "Service call /rosapi/set_param failed: service [/rosapi/set_param] responded with an error"
            )
        ],
    ),
    # A ROS 2 service whose handler raised never answers: the call ends at its timeout with a clear text.
    "ros2": (
        {
            "service_type": "rosapi_msgs/srv/SetParam",
            "request": {"name": "/turtlesim:background_r", "value": "not json"},
            "timeout": 0.5,
        },
        ["/rosapi/set_param", r"0\.5|Timeout exceeded"],
    ),
}


async def test_a_service_that_fails_inside_is_an_error_saying_what_the_dialect_tells(
    session: Session, sim: SimulatedRobot
) -> None:
    """A service whose handler raises is an error: ROS 1 with the bridge's text, ROS 2 at the timeout."""
    arguments, expected = NOT_JSON_SET_PARAM[sim.dialect]
    text = await session.error("publish_service", {"service": "/rosapi/set_param", **arguments})
    for pattern in expected:
        assert re.search(pattern, text), (pattern, text)


async def test_a_hidden_ros2_service_that_rosapi_does_not_list_can_still_be_called(
    session_ros2: Session,
) -> None:
    """/fibonacci/_action/cancel_goal is hidden from list_services, yet publish_service reaches it."""
    listed = (await session_ros2.ok("list_services")).structured_content
    assert listed is not None
    assert "/fibonacci/_action/cancel_goal" not in [row["name"] for row in service_rows(listed)]
    result = await session_ros2.ok(
        "publish_service",
        {
            "service": "/fibonacci/_action/cancel_goal",
            "service_type": "action_msgs/srv/CancelGoal",
            "request": {},
        },
    )
    assert result.structured_content is not None
    assert "return_code" in result.structured_content["response"]


async def test_a_service_offered_anew_with_another_type_is_called_with_the_new_type(
    session_ros2: Session, sim_ros2: SimulatedRobot
) -> None:
    """A remembered service type is only a shortcut: a service offered anew as SetBool is called as one."""
    session = session_ros2
    async with websockets.connect(sim_ros2.url) as provider:

        async def offer(srv_type: str) -> None:
            await provider.send(json.dumps({"op": "advertise_service", "service": "/dyn", "type": srv_type}))
            # No acknowledgement exists in rosbridge: wait until rosapi lists the new type.
            async with RosbridgeClient(sim_ros2.url) as probe:
                await probe.wait_connected(30.0)
                for _ in range(100):
                    found = await probe.call_service("/rosapi/service_type", {"service": "/dyn"})
                    if found["type"] == srv_type:
                        return
                    await asyncio.sleep(0)  # a bare yield: the next look-up is the barrier
            raise AssertionError(f"/dyn never became {srv_type}")

        async def answer(values: dict[str, object]) -> None:
            request = json.loads(await asyncio.wait_for(provider.recv(), 5.0))
            assert request["op"] == "call_service"
            await provider.send(
                json.dumps(
                    {
                        "op": "service_response",
                        "id": request["id"],
                        "service": "/dyn",
                        "result": True,
                        "values": values,
                    }
                )
            )

        await offer("std_srvs/srv/Trigger")
        call = asyncio.ensure_future(
            session.ok("publish_service", {"service": "/dyn", "service_type": "std_srvs/srv/Trigger"})
        )
        await answer({"success": True, "message": "first"})
        assert (await call).structured_content["response"] == {"success": True, "message": "first"}

        await offer("std_srvs/srv/SetBool")
        call = asyncio.ensure_future(
            session.ok(
                "publish_service",
                {"service": "/dyn", "service_type": "std_srvs/srv/SetBool", "request": {"data": True}},
            )
        )
        await answer({"success": True, "message": "second"})
        result = await call
        assert result.structured_content["service_type"] == "std_srvs/srv/SetBool"
        assert result.structured_content["response"] == {"success": True, "message": "second"}


async def test_a_call_past_its_timeout_warns_it_may_still_take_effect(session_ros1: Session) -> None:
    """A ROS 1 call that outlives its timeout may still run on the robot (as /slow_service does): say so."""
    text = await session_ros1.error(
        "publish_service",
        {"service": "/slow_service", "service_type": "std_srvs/Trigger", "request": {}, "timeout": 0.2},
    )
    assert "No reply to service /slow_service within 0.2 s" in text
    assert "may still take effect on the robot" in text
