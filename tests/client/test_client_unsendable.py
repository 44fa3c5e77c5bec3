"""Frames the bridge could not take are refused before sending; nothing restored can cost the connection."""

from __future__ import annotations

import pytest

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.errors import FrameTooLargeError, NotSentError
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.wire.protocol import BRIDGE_MAX_FRAME_BYTES


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is done with the answers is tested."""
    return True


async def _round_trip(client: RosbridgeClient) -> None:
    """A service call answered on the same connection: nothing was dropped."""
    await client.call_service("/rosapi/topics", timeout=5.0)
    assert client.connections_made == 1


async def test_a_message_over_the_frame_limit_is_refused_and_the_connection_stays(
    client: RosbridgeClient, sim: SimulatedRobot
) -> None:
    """11 MB of text is refused with the sizes named; the bridge never sees it and keeps the connection."""
    with pytest.raises(FrameTooLargeError) as raised:
        await client.publish("/chatter", "std_msgs/String", {"data": "x" * (11 * 1024 * 1024)})
    assert raised.value.limit == BRIDGE_MAX_FRAME_BYTES
    assert "nothing was sent" in str(raised.value)
    await _round_trip(client)
    assert "/chatter" not in sim.world.published


async def test_a_lone_surrogate_is_refused_instead_of_closing_the_connection(
    client: RosbridgeClient, sim: SimulatedRobot
) -> None:
    """Text that cannot be UTF-8 is a NotSentError; websockets would otherwise close the socket on it."""
    with pytest.raises(NotSentError, match="ud800"):
        await client.publish("/chatter", "std_msgs/String", {"data": "\ud800"})
    await _round_trip(client)


async def test_a_six_megabyte_topic_name_makes_a_six_megabyte_advertisement_not_twelve(
    client: RosbridgeClient, sim: SimulatedRobot
) -> None:
    """Ids carry a bounded part of the name, so the advertise frame stays under the limit and goes through."""
    topic = "/" + "a" * 6_000_000
    # The name twice (topic and id) would be over the bridge's limit, and the advertisement refused.
    assert len(topic) < BRIDGE_MAX_FRAME_BYTES < 2 * len(topic)
    await client.publish(topic, "std_msgs/String", {"data": "x"})
    await _round_trip(client)
    await sim.world.wait_for(lambda w: topic in w.published)
    assert [message.msg for message in sim.world.published[topic]] == [{"data": "x"}]


async def test_an_advertisement_that_could_not_be_sent_is_not_restored_after_a_reconnect(
    client: RosbridgeClient, sim: SimulatedRobot
) -> None:
    """A refused advertise is forgotten: the reconnect restores nothing that would get it dropped again."""
    topic = "/" + "a" * (BRIDGE_MAX_FRAME_BYTES + 1)
    with pytest.raises(FrameTooLargeError):
        await client.publish(topic, "std_msgs/String", {"data": "x"})
    await sim.drop_connections()
    await client.wait_disconnected(5.0)
    await client.wait_connected(30.0)
    await client.call_service("/rosapi/topics", timeout=5.0)
    assert client.connections_made == 2
