"""Conformance of the real-bridge options: our robot set up like a real bridge answers rosapi as it does.

With ``ROSBRIDGE_TEST_URL`` set (a real ROS 1 0.11.17, or a ROS 2 2.1.0 bridge with its defaults), each test
asks the real bridge and a simulated robot set up like it (ROS 2: ``in_order``, the bridge's distro,
``rosapi="2.1.0"``) the same questions and compares the answers. Without it, the timing test runs against
simulated robots with a rosapi latency; the comparisons need a real bridge and are skipped.

Only questions that are safe on a real 2.1.0 are asked: never ``get_param_names``, ``has_param`` of an
undeclared parameter, or the details of a service type rosapi did not report itself (each ends its rosapi).
"""

from __future__ import annotations

import json
import os
import re
import time
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import Any

import pytest
from rawclient import RawClient

from rosbridge_mcp_server.sim import SimulatedRobot

REAL_URL = os.environ.get("ROSBRIDGE_TEST_URL")
SIDE_BY_SIDE = 8
#: Per-call latency of the simulated rosapi in the timing test (the real ones take ~3-7 ms per call).
SIM_LATENCY = 0.01
#: The arm's trajectory action, served where the lab was built with the arm (ros2_control's layout).
_ARM_ACTION = "/arm_controller/follow_joint_trajectory"

_ADDRESS = re.compile(r"0x[0-9a-f]+")


@dataclass
class Bridge:
    """A bridge under test: its URL and dialect, and the simulated robot when it is ours."""

    url: str
    dialect: str
    distro: str
    robot: SimulatedRobot | None
    server: str = "rosbridge_suite"
    world: str = "turtle"


async def _detect(url: str) -> Bridge:
    async with await RawClient.open(url) as client:
        reply = await client.call("/rosapi/get_ros_version")
        if reply["result"] is not True:
            return Bridge(url, "ros1", "noetic", None)
        # A lab built with the arm serves its trajectory action: the twin then carries the arm too.
        servers = await client.call("/rosapi/action_servers")
        world = "arm" if _ARM_ACTION in (servers.get("values") or {}).get("action_servers", []) else "turtle"
        # rosbridge-server-rs answers a cancel of a goal nobody started with an error status; 2.1.0 is silent.
        await client.send({"op": "cancel_action_goal", "id": "conformance:probe", "action": "/nobody"})
        told = any(frame.get("op") == "status" for frame in await client.frames_before_barrier())
    distro = str(reply["values"]["distro"])
    return Bridge(url, "ros2", distro, None, "rs" if told else "rosbridge_suite", world)


def _twin_settings(bridge: Bridge) -> dict[str, Any]:
    """How to set up our robot like the real bridge: 2.1.0's defaults on ROS 2, or rosbridge-server-rs."""
    if bridge.dialect == "ros1":
        return {"dialect": "ros1"}
    settings: dict[str, Any] = {"dialect": "ros2", "distro": bridge.distro, "world": bridge.world}
    if bridge.server == "rs":
        return {**settings, "server": "rs"}
    return {**settings, "in_order": True, "rosapi": "2.1.0"}


@pytest.fixture(params=["ros2", "ros1"])
async def bridge(request: pytest.FixtureRequest) -> AsyncIterator[Bridge]:
    """The real bridge of ROSBRIDGE_TEST_URL (once), else our robot with a rosapi latency in each dialect."""
    if REAL_URL:
        if request.param != "ros2":
            pytest.skip("the real bridge runs once")
        yield await _detect(REAL_URL)
        return
    settings = _twin_settings(Bridge("", request.param, "kilted", None))
    async with SimulatedRobot(**settings, rosapi_latency=SIM_LATENCY) as robot:
        yield Bridge(robot.url, robot.dialect, robot.bridge.config.distro, robot)


@pytest.fixture
async def twin(bridge: Bridge) -> AsyncIterator[SimulatedRobot]:
    """Our robot set up like the real bridge (the comparisons need a real one)."""
    if bridge.robot is not None:
        pytest.skip("set ROSBRIDGE_TEST_URL=ws://host:port to compare with a real rosbridge")
    async with SimulatedRobot(**_twin_settings(bridge)) as robot:
        yield robot


async def _answers(url: str, questions: list[tuple[str, dict[str, Any]]]) -> list[Any]:
    """Each question's (result, values), object addresses of rclpy reprs blanked out."""
    answers = []
    async with await RawClient.open(url) as client:
        for service, args in questions:
            reply = await client.call(service, args)
            answers.append(json.loads(_ADDRESS.sub("0x?", json.dumps([reply["result"], reply["values"]]))))
    return answers


async def test_rosapi_serves_calls_sent_side_by_side_one_at_a_time(bridge: Bridge) -> None:
    """N calls sent at once take at least N times the fastest single call (halved for noise): a real
    rosapi does not answer them in parallel (on ROS 1 side by side is even slower)."""
    service = "/rosapi/service_type"
    args = {"service": "/add_two_ints"}
    async with await RawClient.open(bridge.url) as client:
        single = []
        for _ in range(SIDE_BY_SIDE):
            started = time.monotonic()
            await client.values(service, args)
            single.append(time.monotonic() - started)
        started = time.monotonic()
        for n in range(SIDE_BY_SIDE):
            await client.send({"op": "call_service", "service": service, "args": args, "id": f"side:{n}"})
        replies = [await client.reply(f"side:{n}") for n in range(SIDE_BY_SIDE)]
        side_by_side = time.monotonic() - started
    assert all(r["result"] is True for r in replies)
    assert side_by_side >= SIDE_BY_SIDE * min(single) / 2


async def test_the_twin_answers_rosapi_as_the_real_bridge(bridge: Bridge, twin: SimulatedRobot) -> None:
    """TypeDefs (field names, constnames), parameters, the missing services, hidden names."""
    questions: list[tuple[str, dict[str, Any]]] = []
    if bridge.server == "rs":
        # What the twin models of rosbridge-server-rs's built-in rosapi (the newer rosbridge_suite formats;
        # not its TypeDefs, which list only real constants where rosapi also lists SLOT_TYPES and fields).
        questions += [
            ("/rosapi/get_param", {"name": "/turtlesim:background_r", "default_value": ""}),
            ("/rosapi/action_type", {"action": "/fibonacci"}),
            ("/rosapi/get_ros_version", {}),
            ("/nobody_has_this_service", {}),
        ]
    elif bridge.dialect == "ros2":
        questions += [
            ("/rosapi/action_servers", {}),
            ("/rosapi/message_details", {"type": "geometry_msgs/msg/Twist"}),
            ("/rosapi/service_request_details", {"type": "example_interfaces/srv/AddTwoInts"}),
            ("/rosapi/service_response_details", {"type": "std_srvs/srv/Trigger"}),
            ("/rosapi/get_param", {"name": "/turtlesim:background_r", "default_value": ""}),
            ("/rosapi/get_param", {"name": "/turtlesim:not_declared", "default_value": '"d"'}),
            ("/rosapi/set_param", {"name": "/turtlesim:not_declared", "value": "1"}),
            ("/rosapi/has_param", {"name": "/turtlesim:background_r"}),
            ("/rosapi/action_type", {"action": "/fibonacci"}),
            ("/rosapi/interfaces", {}),
            ("/rosapi/get_ros_version", {}),
            ("/rosapi/node_details", {"node": "/fibonacci_server"}),
            ("/rosapi/node_details", {"node": "/rosapi_params"}),
            ("/rosapi/service_type", {"service": "/fibonacci/_action/send_goal"}),
            ("/rosapi/service_type", {"service": "/turtlesim/get_type_description"}),
            ("/turtlesim/get_parameters", {"names": ["background_r", "nope"]}),
            ("/turtlesim/list_parameters", {}),
            ("/rosapi/list_parameters", {}),
            ("/rosbridge_websocket/list_parameters", {}),
        ]
    else:
        questions += [
            ("/rosapi/message_details", {"type": "geometry_msgs/Twist"}),
            ("/rosapi/message_details", {"type": "geometry_msgs/msg/Twist"}),
            ("/rosapi/service_response_details", {"type": "std_srvs/Trigger"}),
            ("/rosapi/get_param", {"name": "/turtlesim/background_r"}),
            ("/rosapi/service_type", {"service": "/talker/get_loggers"}),
        ]
    real = await _answers(bridge.url, questions)
    ours = await _answers(twin.url, questions)
    for question, theirs, mine in zip(questions, real, ours, strict=True):
        assert mine == theirs, question


async def test_every_node_offers_the_services_of_the_real_graph(bridge: Bridge, twin: SimulatedRobot) -> None:
    """For each node both graphs have: the same per-node services with the same types."""

    async def graph(url: str) -> tuple[set[str], dict[str, str]]:
        async with await RawClient.open(url) as client:
            nodes = set((await client.values("/rosapi/nodes"))["nodes"])
            services = (await client.values("/rosapi/services"))["services"]
            types = {}
            for name in services:
                if "/" + name.split("/")[1] in nodes:
                    types[name] = (await client.values("/rosapi/service_type", {"service": name}))["type"]
        return nodes, types

    real_nodes, real_types = await graph(bridge.url)
    our_nodes, our_types = await graph(twin.url)
    shared = real_nodes & our_nodes
    # rosbridge-server-rs has no /rosapi node and names its own node /rosbridge_rs.
    assert (
        {"/talker"} if bridge.server == "rs" else {"/rosapi", "/rosbridge_websocket", "/talker"}
    ) <= shared
    for node in shared:
        real_services = {n: t for n, t in real_types.items() if n.startswith(node + "/")}
        our_services = {n: t for n, t in our_types.items() if n.startswith(node + "/")}
        if node == "/turtlesim":
            our_services = {n: t for n, t in our_services.items() if "/teleport_" not in n}
        assert our_services == real_services, node


async def test_a_latched_topic_answers_a_new_subscriber_at_once(bridge: Bridge) -> None:
    """rosbridge's /client_count is latched (ROS 1) / transient-local (ROS 2): a count comes without waiting
    for the next connect or disconnect (on 2.1.0 first the one from before this client connected)."""
    if bridge.server == "rs":
        pytest.skip("rosbridge-server-rs 0.1.6 has no /client_count")
    async with await RawClient.open(bridge.url) as client:
        await client.send({"op": "subscribe", "topic": "/client_count", "id": "latched"})
        count = (await client.next_publish("/client_count", wait=2.0))["msg"]["data"]
    assert isinstance(count, int)
    assert count >= 0


async def test_the_twin_waits_out_a_slow_service_despite_a_timeout_field(
    bridge: Bridge, twin: SimulatedRobot
) -> None:
    """2.1.0 and 0.11.17 read no timeout field: /slow_service answers after its 3 s on both;
    rosbridge-server-rs reads it, and gives up after 0.5 s like our newest-rosbridge twin."""
    answers = []
    for url in (bridge.url, twin.url):
        async with await RawClient.open(url) as client:
            answers.append(await client.call("/slow_service", {}, timeout=0.5))
    if bridge.server == "rs":
        assert [a["result"] for a in answers] == [False, False]
        return
    assert [a["result"] for a in answers] == [True, True]
    assert answers[0]["values"] == answers[1]["values"]
