"""Subscriptions asking for CBOR: binary frames decoded into the same messages as JSON, arrays compact."""

from __future__ import annotations

import base64
from array import array
from typing import Any

import pytest
from client_harness import MakeClient, MakeSim

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.sim import SimulatedRobot


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is done with the answers is tested."""
    return True


ARRAYS = [
    ("/test/int8", "std_msgs/Int8MultiArray", [-128, -1, 0, 100, 127]),
    ("/test/uint16", "std_msgs/UInt16MultiArray", [0, 1, 65535]),
    ("/test/int32", "std_msgs/Int32MultiArray", [-(2**31), 7, 2**31 - 1]),
    ("/test/float32", "std_msgs/Float32MultiArray", [0.5, -1.25, 0.1, 3.0e38]),
    ("/test/float64", "std_msgs/Float64MultiArray", [0.1, -2.5e-300, 1e300]),
]


def as_lists(value: Any) -> Any:
    """The message with typed arrays as lists, for comparing with its JSON form."""
    if isinstance(value, dict):
        return {key: as_lists(item) for key, item in value.items()}
    if isinstance(value, list):
        return [as_lists(item) for item in value]
    if isinstance(value, array):
        return value.tolist()
    return value


async def first(client: RosbridgeClient, topic: str, **options: Any) -> dict[str, Any]:
    async with client.subscribe(topic, max_queue=1, **options) as sub:
        return await sub.get(5.0)


@pytest.mark.parametrize(("topic", "msg_type", "values"), ARRAYS)
async def test_a_cbor_subscription_delivers_the_same_message_as_json(
    sim: SimulatedRobot, make_client: MakeClient, topic: str, msg_type: str, values: list[Any]
) -> None:
    """A latched MultiArray read through CBOR equals the JSON reading, its data a typed array."""
    publisher = await make_client(sim)
    layout = {"dim": [{"label": "x", "size": len(values), "stride": len(values)}], "data_offset": 0}
    await publisher.publish(topic, msg_type, {"layout": layout, "data": values}, latch=True)
    as_json = await first(await make_client(sim), topic)
    as_cbor = await first(await make_client(sim), topic, compression="cbor")
    assert isinstance(as_cbor["data"], array)
    assert isinstance(as_json["data"], list)
    assert as_lists(as_cbor) == as_json
    assert as_json["data"][:2] == pytest.approx(values[:2])


async def test_a_map_arrives_through_cbor_as_int8_cells(sim: SimulatedRobot, make_client: MakeClient) -> None:
    """The room's /map through CBOR: its cells one int8 array, equal to the JSON list; the rest the same."""
    as_json = await first(await make_client(sim), "/map")
    as_cbor = await first(await make_client(sim), "/map", compression="cbor")
    cells = as_cbor.pop("data")
    assert isinstance(cells, array)
    assert cells.typecode == "b"
    assert cells.tolist() == as_json.pop("data")
    assert as_cbor == as_json


async def test_a_bridge_that_ignores_cbor_still_delivers_json(
    make_sim: MakeSim, make_client: MakeClient
) -> None:
    """On a bridge without CBOR the same subscription gets the JSON message (the fallback is the decoder)."""
    robot = await make_sim(dialect="ros2", cbor=False)
    msg = await first(await make_client(robot), "/map", compression="cbor")
    assert isinstance(msg["data"], list)
    assert len(msg["data"]) == msg["info"]["width"] * msg["info"]["height"]


async def test_json_and_cbor_listeners_on_one_connection_both_get_the_message(
    sim: SimulatedRobot, make_client: MakeClient
) -> None:
    """rosbridge sends CBOR to every listener of the topic once one asks; each still gets /map in the form it
    asked for: the JSON listener a list equal to a JSON-only client's, the CBOR listener a typed array."""
    client = await make_client(sim)
    async with client.subscribe("/map", max_queue=1, compression="cbor") as compact:
        b = await compact.get(5.0)
        assert isinstance(b["data"], array)
        # The second listener's subscribe has the bridge send the latched map again, as CBOR (the strongest
        # compression asked for on the connection): the JSON listener still gets it as JSON.
        async with client.subscribe("/map", max_queue=1) as plain:
            a = await plain.get(5.0)
    assert isinstance(a["data"], list)
    assert a == await first(await make_client(sim), "/map")
    assert a["data"] == b["data"].tolist()


async def test_a_json_listener_beside_a_cbor_one_gets_bytes_as_base64(
    sim: SimulatedRobot, make_client: MakeClient
) -> None:
    """An image's uint8[] comes as CBOR bytes once a CBOR listener shares the topic; the JSON listener beside
    it gets the base64 text JSON carries (seen as a bug: record's CBOR /scan broke subscribe_topic and
    view_scan)."""
    client = await make_client(sim)
    async with client.subscribe("/camera/image_raw", max_queue=1, compression="cbor") as compact:
        assert isinstance((await compact.get(5.0))["data"], bytes)  # the connection now gets CBOR frames
        async with client.subscribe("/camera/image_raw", max_queue=1) as plain:
            a = await plain.get(5.0)
            b = await compact.get(5.0)
    assert isinstance(b["data"], bytes)
    assert isinstance(a["data"], str)
    assert len(base64.b64decode(a["data"], validate=True)) == len(b["data"]) == a["step"] * a["height"]


async def test_a_cbor_subscription_asks_for_cbor_again_after_the_robot_restarts(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """The restored subscribe keeps its compression: /map arrives as a typed array after the outage too."""
    client = await make_client(sim_ros2)
    async with client.subscribe("/map", max_queue=1, compression="cbor") as sub:
        assert isinstance((await sub.get(5.0))["data"], array)
        await sim_ros2.stop()
        await client.wait_disconnected(5.0)
        await sim_ros2.start()
        await client.wait_connected(30.0)
        again = await sub.get(5.0)
    assert isinstance(again["data"], array)
