"""One node's details on a bridge where rosapi must never be asked about a node that is not running.

rosapi 2.1.0 (Jazzy, Kilted) fails in its handler for ``node_details`` of an unknown node and is gone until
restarted; the simulated robot's ``rosapi="2.1.0"`` does the same. Each test reads the robot's own count of
the calls that reached rosapi.
"""

from __future__ import annotations

from collections.abc import AsyncIterator

import pytest

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.robot.graph import RosGraph
from rosbridge_mcp_server.robot.nodes import RECENT_SECONDS, UnknownNodeError, node_details, node_names
from rosbridge_mcp_server.sim import SimulatedRobot
from sim_transport import client_for

DETAILS = "/rosapi/node_details"
NODES = "/rosapi/nodes"
TOPICS = "/rosapi/topics"


class Clock:
    """The graph's clock, moved by the test."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
async def jazzy() -> AsyncIterator[SimulatedRobot]:
    """A robot behind a bridge like rosbridge 2.1.0 on Jazzy (its calls in order, its rosapi 2.1.0)."""
    robot = SimulatedRobot(dialect="ros2", in_order=True, rosapi="2.1.0", action_step=0.05)
    await robot.start(listen=False)  # what rosapi is asked is counted by the robot: no port needed
    try:
        yield robot
    finally:
        await robot.stop()


@pytest.fixture
async def client(jazzy: SimulatedRobot) -> AsyncIterator[RosbridgeClient]:
    async with client_for(jazzy) as client:
        await client.wait_connected(30.0)
        assert not (await client.capabilities()).node_details_of_unknown_safe
        yield client


def calls(robot: SimulatedRobot, service: str) -> int:
    return robot.world.service_calls.get(service, 0)


async def test_a_node_never_listed_never_reaches_node_details(
    jazzy: SimulatedRobot, client: RosbridgeClient
) -> None:
    """With no recent list and with one just seen, a ghost node is looked up in a fresh list, never asked."""
    graph = RosGraph(client)
    with pytest.raises(UnknownNodeError, match="/ghost"):
        await node_details(graph, "/ghost")
    await node_names(graph)  # a list seen now, which does not hold the ghost
    before = calls(jazzy, NODES)
    with pytest.raises(UnknownNodeError, match="/ghost"):
        await node_details(graph, "/ghost")
    assert calls(jazzy, NODES) == before + 1, "the recent list did not hold it: a fresh list decided"
    assert calls(jazzy, DETAILS) == 0
    assert (await node_details(graph, "/turtlesim")).publishes, "rosapi still answers"


async def test_a_node_gone_since_a_list_older_than_the_window_is_not_asked_about(
    jazzy: SimulatedRobot, client: RosbridgeClient
) -> None:
    """A node the last list held, gone since, is looked up again once that list is older than the window."""
    clock = Clock()
    graph = RosGraph(client, clock=clock)
    assert "/talker" in await node_names(graph)
    del jazzy.bridge.graph.nodes["/talker"]
    clock.now += RECENT_SECONDS + 0.1
    with pytest.raises(UnknownNodeError, match="/talker"):
        await node_details(graph, "/talker")
    assert calls(jazzy, DETAILS) == 0


async def test_a_list_seen_within_the_window_spares_the_node_and_topic_listings(
    jazzy: SimulatedRobot, client: RosbridgeClient
) -> None:
    """Two nodes asked about within the window: one node list and one topic list serve both."""
    clock = Clock()
    graph = RosGraph(client, clock=clock)
    first = await node_details(graph, "/turtlesim")
    listed = calls(jazzy, NODES), calls(jazzy, TOPICS)
    clock.now += RECENT_SECONDS / 2
    second = await node_details(graph, "/talker")
    assert (calls(jazzy, NODES), calls(jazzy, TOPICS)) == listed
    assert calls(jazzy, DETAILS) == 2
    assert ("/chatter", "std_msgs/msg/String") in second.publishes
    assert first.subscribes


async def test_a_topic_newer_than_the_recent_list_gets_its_type_from_a_fresh_one(
    jazzy: SimulatedRobot, client: RosbridgeClient
) -> None:
    """A node's topic the recent topic list does not name is typed from a fresh list, not left unknown."""
    clock = Clock()
    graph = RosGraph(client, clock=clock)
    await node_details(graph, "/talker")
    topics = calls(jazzy, TOPICS)
    jazzy.bridge.graph.add_publisher("/talker", "/talker/new_topic", "std_msgs/msg/String")
    details = await node_details(graph, "/talker")
    assert ("/talker/new_topic", "std_msgs/msg/String") in details.publishes
    assert calls(jazzy, TOPICS) == topics + 1
