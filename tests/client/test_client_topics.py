"""Publishing and subscribing: separate listeners, bounded queues, and nothing stale after an outage."""

from __future__ import annotations

import asyncio

import pytest
from client_harness import MakeClient, MakeSim, unused_port

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.errors import ConnectionLostError, NotConnectedError, RequestTimeoutError
from rosbridge_mcp_server.sim import SimulatedRobot
from sim_transport import client_for


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is done with the answers is tested."""
    return True


async def test_a_subscription_receives_messages_of_its_topic(client: RosbridgeClient) -> None:
    """subscribe('/chatter') yields the robot's String messages in order."""
    async with client.subscribe("/chatter", "std_msgs/String") as sub:
        first = await sub.get(3.0)
        second = await sub.get(3.0)
    assert first["data"].startswith("Hello World")
    assert first != second


async def test_async_iteration_yields_messages_until_closed(client: RosbridgeClient) -> None:
    """``async for msg in sub`` yields messages; closing the subscription ends the loop."""
    seen: list[dict[str, object]] = []
    async with client.subscribe("/chatter") as sub:
        async with asyncio.timeout(5.0):
            async for msg in sub:
                seen.append(msg)
                if len(seen) == 3:
                    await sub.close()
    assert len(seen) == 3


async def test_two_listeners_on_one_topic_never_remove_each_other(client: RosbridgeClient) -> None:
    """Each listener has its own subscription id: closing one leaves the other receiving."""
    first = await client.subscribe("/chatter", "std_msgs/String").open()
    second = await client.subscribe("/chatter", "std_msgs/String").open()
    assert first.id != second.id
    try:
        a = await first.get(3.0)
        b = await second.get(3.0)
        assert a == b, "both listeners see the same stream"
        await first.close()
        while second.get_nowait() is not None:
            pass
        later = await second.get(3.0)
        assert later["data"] != b["data"]
    finally:
        await first.close()
        await second.close()


async def test_a_slow_consumer_loses_the_oldest_messages_and_counts_them(
    make_sim: MakeSim, make_client: MakeClient
) -> None:
    """With max_queue=10 on a 1 kHz topic the queue keeps the newest 10 and counts the drops."""
    robot = await make_sim(dialect="ros2", fast_topic=True)
    client = await make_client(robot)
    async with client.subscribe("/fast_counter", "std_msgs/UInt64", max_queue=10) as sub:
        start = (await sub.get(3.0))["data"]
        await robot.wait_for(lambda world: world.fast_count >= start + 300, 10.0)
        await robot.wait_for(lambda _world: sub.received >= 100, 10.0)
        assert sub.pending() == 10
        assert sub.dropped == sub.received - 1 - 10
        values = [(await sub.get(1.0))["data"] for _ in range(10)]
    assert values == sorted(values)
    assert values[0] > start + 1


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_publish_reaches_the_robot(make_sim: MakeSim, make_client: MakeClient, dialect: str) -> None:
    """A Twist on /turtle1/cmd_vel arrives in the robot's world (type name in either spelling)."""
    robot = await make_sim(dialect=dialect)
    client = await make_client(robot)
    await client.publish("/turtle1/cmd_vel", "geometry_msgs/msg/Twist", {"linear": {"x": 1.5}})
    await client.publish("/turtle1/cmd_vel", "geometry_msgs/Twist", {"linear": {"x": 0.5}})
    await robot.wait_for(lambda world: len(world.published.get("/turtle1/cmd_vel", ())) >= 2)
    received = [m.msg["linear"]["x"] for m in robot.world.published["/turtle1/cmd_vel"]]
    assert received == [1.5, 0.5]


async def test_ros1_publish_respells_time_fields(sim_ros1: SimulatedRobot, make_client: MakeClient) -> None:
    """sec/nanosec become secs/nsecs for ROS 1, which would silently leave the stamp at zero."""
    client = await make_client(sim_ros1)
    stamped = {"header": {"stamp": {"sec": 12, "nanosec": 34}, "frame_id": "map"}, "pose": {}}
    await client.publish("/goal_pose", "geometry_msgs/PoseStamped", stamped)
    await sim_ros1.wait_for(lambda world: bool(world.published.get("/goal_pose")))
    stamp = sim_ros1.world.published["/goal_pose"][-1].msg["header"]["stamp"]
    assert stamp == {"secs": 12, "nsecs": 34}


async def test_publish_advertises_once_and_reuses_the_advertisement(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """Repeated publishes share one advertisement; unadvertise drops it."""
    client = await make_client(sim_ros2)
    for n in range(5):
        await client.publish("/chatter_in", "std_msgs/String", {"data": f"m{n}"})
    await sim_ros2.wait_for(lambda world: len(world.published.get("/chatter_in", ())) == 5)
    advertisements = [c.advertisements.get("/chatter_in") for c in sim_ros2.bridge.connections.values()]
    assert [ids for ids in advertisements if ids] == [[client.topics.adverts["/chatter_in"].id]]
    await client.unadvertise("/chatter_in")
    await client.call_service("/rosapi/topics")  # the bridge handles our frames in order: a barrier
    assert all("/chatter_in" not in c.advertisements for c in sim_ros2.bridge.connections.values())


async def test_one_message_read_in_a_subscription_block_leaves_no_subscription(
    client: RosbridgeClient,
) -> None:
    """A subscription opened for one message returns it and is gone once its block ends."""
    async with client.subscribe("/chatter", "std_msgs/String", max_queue=1) as sub:
        msg = await sub.get(3.0)
    assert "data" in msg
    assert client.topics.subscriptions == {}


async def test_waiting_for_a_message_times_out_on_a_silent_topic(client: RosbridgeClient) -> None:
    """No message within the timeout raises RequestTimeoutError naming the topic."""
    with pytest.raises(RequestTimeoutError, match="a message on /nobody_publishes_here"):
        async with client.subscribe("/nobody_publishes_here", "std_msgs/String", max_queue=1) as sub:
            await sub.get(0.2)


async def test_a_drop_interrupts_a_waiting_consumer_and_the_subscription_comes_back(
    sim: SimulatedRobot, make_client: MakeClient
) -> None:
    """get() raises ConnectionLostError at a drop; after the reconnect the subscription delivers again."""
    client = await make_client(sim)
    async with client.subscribe("/chatter", "std_msgs/String") as sub:
        await sub.get(3.0)
        while sub.get_nowait() is not None:
            pass
        # The consumer task starts waiting at the drop's first await, long before the close
        # handshake reaches the client.
        waiting = asyncio.create_task(sub.get(10.0))
        await sim.drop_connections()
        with pytest.raises(ConnectionLostError):
            await asyncio.wait_for(waiting, 15.0)
        await client.wait_connected(30.0)
        before = sim.world.chatter_count
        msg = await sub.get(5.0)
        while msg is not None and int(msg["data"].rsplit(" ", 1)[-1]) <= before:
            msg = await sub.get(5.0)
        assert msg is not None


async def test_nothing_published_during_an_outage_arrives_after_the_robot_restarts(
    sim: SimulatedRobot, make_client: MakeClient
) -> None:
    """Publishes during an outage raise and are never sent later; the advertisement is restored."""
    client = await make_client(sim)
    await client.publish("/turtle1/cmd_vel", "geometry_msgs/Twist", {"linear": {"x": 1.0}})
    await sim.wait_for(lambda world: len(world.published.get("/turtle1/cmd_vel", ())) == 1)
    await sim.stop()
    await client.wait_disconnected(5.0)
    for stale in (7.0, 8.0, 9.0):
        with pytest.raises(NotConnectedError):
            await client.publish("/turtle1/cmd_vel", "geometry_msgs/Twist", {"linear": {"x": stale}})
    await sim.start()
    await client.wait_connected(30.0)
    await client.call_service("/rosapi/topics")  # the bridge handles our frames in order: a barrier
    advertised = [c.advertisements.get("/turtle1/cmd_vel") for c in sim.bridge.connections.values()]
    assert any(advertised), "the advertisement is restored on reconnect"
    await client.publish("/turtle1/cmd_vel", "geometry_msgs/Twist", {"linear": {"x": 2.0}})
    await sim.wait_for(lambda world: world.published["/turtle1/cmd_vel"][-1].msg["linear"]["x"] == 2.0)
    received = [m.msg["linear"]["x"] for m in sim.world.published["/turtle1/cmd_vel"]]
    assert received == [1.0, 2.0]


async def test_closing_a_subscription_unsubscribes_only_its_own_id(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """The bridge keeps the other listener's subscription id; closing the last removes the topic."""
    client = await make_client(sim_ros2)
    first = await client.subscribe("/chatter", "std_msgs/String").open()
    second = await client.subscribe("/chatter", "std_msgs/String").open()
    await client.call_service("/rosapi/topics")  # the bridge handles our frames in order: a barrier
    [bridge_side] = sim_ros2.bridge.connections.values()
    assert set(bridge_side.subscriptions["/chatter"].by_id) == {first.id, second.id}
    await first.close()
    await client.call_service("/rosapi/topics")
    assert set(bridge_side.subscriptions["/chatter"].by_id) == {second.id}
    await second.close()
    await client.call_service("/rosapi/topics")
    assert "/chatter" not in bridge_side.subscriptions


async def test_subscribing_while_disconnected_raises_not_connected(make_client: MakeClient) -> None:
    """Opening a subscription with no bridge raises NotConnectedError instead of waiting forever."""
    client = await make_client(f"ws://127.0.0.1:{unused_port()}", connected=False, connect_timeout=0.3)
    with pytest.raises(NotConnectedError):
        async with client.subscribe("/chatter", "std_msgs/String"):
            pass
    assert client.topics.subscriptions == {}


async def test_a_second_concurrent_consumer_of_one_subscription_is_refused(client: RosbridgeClient) -> None:
    """Two tasks waiting on one subscription would starve one of them, so the second is refused."""
    async with client.subscribe("/nobody_publishes_here", "std_msgs/String") as sub:
        first = asyncio.create_task(sub.get(5.0))
        await asyncio.sleep(0)  # a yield, not a timed wait: lets the first consumer start waiting
        with pytest.raises(RuntimeError, match="another task"):
            await sub.get(0.1)
        first.cancel()
        with pytest.raises(asyncio.CancelledError):
            await first


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_a_latched_publish_says_latch_so_the_bridge_keeps_it_latched_without_a_warning(
    dialect: str, make_sim: MakeSim, caplog: pytest.LogCaptureFixture
) -> None:
    """Both rosbridge lines register the publisher again with each publish's latch flag; ours says true."""
    robot = await make_sim(dialect=dialect)
    msg_type = "std_msgs/msg/String" if dialect == "ros2" else "std_msgs/String"
    async with client_for(robot) as client:
        await client.wait_connected(30.0)
        for text in ("first", "second"):
            await client.publish("/latched_note", msg_type, {"data": text}, latch=True)
        await robot.world.wait_for(lambda w: len(w.published.get("/latched_note", ())) == 2)
    assert "non-latched publisher registration" not in caplog.text
