"""The simulated rosbridge speaks the protocol as the real servers do: replies, error texts, silences."""

from __future__ import annotations

import base64
import json
import struct
import uuid
import zlib
from typing import Any

import pytest
from rawclient import MakeSim, RawClient

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.connection import MAX_QUEUED_MESSAGES


async def test_service_call_answers_with_values_and_echoes_id_and_service(sim: SimulatedRobot) -> None:
    """A call_service gets one service_response with the request's id, service name and values."""
    async with await RawClient.open(sim.url) as client:
        await client.send(
            {"op": "call_service", "id": "c1", "service": "/add_two_ints", "args": {"a": 2, "b": 40}}
        )
        reply = await client.reply("c1")
    assert reply == {
        "op": "service_response",
        "id": "c1",
        "service": "/add_two_ints",
        "result": True,
        "values": {"sum": 42},
    }


async def test_service_args_may_be_a_list_in_field_order(sim: SimulatedRobot) -> None:
    """rosbridge accepts args as a list of values in the request's field order."""
    async with await RawClient.open(sim.url) as client:
        assert (await client.values("/add_two_ints", [5, 6])) == {"sum": 11}


async def test_service_call_with_an_empty_request_succeeds(sim: SimulatedRobot) -> None:
    """A service with an empty request (std_srvs Empty) is called without args."""
    sim.world.turtle.x = 1.0
    async with await RawClient.open(sim.url) as client:
        reply = await client.call("/reset")
    assert reply["result"] is True
    assert reply["values"] == {}
    assert sim.world.turtle.x == pytest.approx(5.544444561004639)


async def test_call_to_a_missing_service_fails_with_the_real_servers_text(sim: SimulatedRobot) -> None:
    """service_response result false, values 'Service /x does not exist' (both lines)."""
    async with await RawClient.open(sim.url) as client:
        reply = await client.call("/no_such_service")
    assert reply["result"] is False
    assert reply["values"] == "Service /no_such_service does not exist"


async def test_bad_service_args_fail_with_a_conversion_text(sim: SimulatedRobot) -> None:
    """Args that do not fit the request type end in result false with rosbridge's conversion error text."""
    async with await RawClient.open(sim.url) as client:
        unknown_field = await client.call("/add_two_ints", {"a": 1, "b": 2, "c": 3})
        float_for_int = await client.call("/add_two_ints", {"a": 1.5, "b": 2})
    assert unknown_field["result"] is False
    assert "c" in unknown_field["values"]
    assert float_for_int["result"] is False
    assert isinstance(float_for_int["values"], str)
    assert "a" in float_for_int["values"]


@pytest.mark.parametrize(
    ("dialect", "result", "values"),
    [
        # ROS 2: the call_service timeout field ends the call with rosbridge's own text.
        pytest.param("ros2", False, "Timeout exceeded while waiting for service response", id="ros2"),
        # ROS 1 has no service timeout: the slow service completes.
        pytest.param("ros1", True, {"success": True, "message": "done after 0.3 s"}, id="ros1"),
    ],
)
async def test_a_timeout_field_on_a_slow_call_acts_as_the_dialect_does(
    make_sim: MakeSim, dialect: str, result: bool, values: object
) -> None:
    """A 0.3 s service called with a 0.05 s timeout field: ROS 2 gives up with its timeout text, ROS 1 ignores
    the field."""
    robot = await make_sim(dialect=dialect, slow_service_seconds=0.3)
    async with await RawClient.open(robot.url) as client:
        reply = await client.call("/slow_service", timeout=0.05)
    assert reply == {
        "op": "service_response",
        "id": reply["id"],
        "service": "/slow_service",
        "result": result,
        "values": values,
    }


async def test_legacy_hash_id_in_the_service_name_becomes_the_id(sim: SimulatedRobot) -> None:
    """Without an id, '/rosapi/get_time#33' calls /rosapi/get_time and answers with id '33'."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "call_service", "service": "/rosapi/get_time#33"})
        reply = await client.reply("33")
    assert reply["result"] is True


@pytest.mark.parametrize(
    "frame",
    [
        "this is not json",
        '["a", "list"]',
        '{"no_op": true}',
        '{"op": "set_level", "level": "info", "id": "lvl"}',
        '{"op": "status", "level": "error", "msg": "hi"}',
        '{"op": "no_such_op", "id": "x"}',
        '{"op": "subscribe"}',
        '{"op": "subscribe", "topic": "/chatter", "throttle_rate": 100.0}',
        '{"op": "publish", "topic": "/turtle1/cmd_vel", "msg": {"linear": {"x": 1}, "bogus": 1}}',
        '{"op": "call_service", "id": "bad", "service": 7}',
        '{"op": "unsubscribe", "topic": "/never_subscribed"}',
        '{"op": "unadvertise", "topic": "/never_advertised"}',
        '{"op": "cancel_action_goal", "action": "/fibonacci", "id": [1]}',
        '{"op": "subscribe", "topic": "/chatter", "id": {"unhashable": true}}',
        '{"op": "fragment", "id": "f", "data": "{", "num": 0, "total": 1}',
    ],
)
async def test_frames_the_real_server_only_logs_get_no_reply(sim: SimulatedRobot, frame: str) -> None:
    """Unknown ops, bad JSON, missing or mistyped fields and bad messages: no frame comes back, ever."""
    async with await RawClient.open(sim.url) as client:
        await client.send(frame)
        assert await client.frames_before_barrier() == []


async def test_set_level_is_an_unknown_op_and_never_produces_status_frames(sim: SimulatedRobot) -> None:
    """No status op exists on real servers: a failing op after set_level still gets no status frame."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "set_level", "level": "info"})
        await client.send({"op": "subscribe", "topic": "/not_there"})
        frames = await client.frames_before_barrier()
    assert [f for f in frames if f.get("op") == "status"] == []


async def test_subscribe_without_type_to_an_unknown_topic_makes_no_subscription(sim: SimulatedRobot) -> None:
    """'Cannot infer topic type' is only logged, and a later publisher does not reach that client."""
    async with await RawClient.open(sim.url) as subscriber, await RawClient.open(sim.url) as publisher:
        await subscriber.send({"op": "subscribe", "topic": "/later"})
        assert await subscriber.frames_before_barrier() == []
        await publisher.send({"op": "advertise", "topic": "/later", "type": "std_msgs/String"})
        await publisher.send({"op": "publish", "topic": "/later", "msg": {"data": "x"}})
        await publisher.frames_before_barrier()
        assert await subscriber.frames_before_barrier() == []


async def test_subscribe_with_type_before_a_publisher_exists_receives_later_messages(
    sim: SimulatedRobot,
) -> None:
    """With a type, the subscription is made at once and data flows when someone publishes."""
    async with await RawClient.open(sim.url) as subscriber, await RawClient.open(sim.url) as publisher:
        await subscriber.send({"op": "subscribe", "topic": "/later", "type": "std_msgs/String", "id": "s"})
        await subscriber.frames_before_barrier()
        await publisher.send({"op": "advertise", "topic": "/later", "type": "std_msgs/String"})
        await publisher.send({"op": "publish", "topic": "/later", "msg": {"data": "hello"}})
        message = await subscriber.next_publish("/later")
    assert message == {"op": "publish", "topic": "/later", "msg": {"data": "hello"}}


async def test_publish_without_advertise_uses_the_graphs_type(sim: SimulatedRobot) -> None:
    """A publish to an existing topic needs no advertise: the publisher is created with the graph's type."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "publish", "topic": "/turtle1/cmd_vel", "msg": {"linear": {"x": 0.5}}})
        await sim.wait_for(lambda w: "/turtle1/cmd_vel" in w.published)
    record = sim.world.published["/turtle1/cmd_vel"][-1]
    assert record.msg["linear"]["x"] == 0.5
    assert record.msg["angular"]["z"] == 0.0


async def test_publish_to_an_unknown_topic_without_type_is_dropped(sim: SimulatedRobot) -> None:
    """Publishing to a topic nobody knows, with no type, is logged and dropped."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "publish", "topic": "/nobody", "msg": {"data": "x"}})
        await client.frames_before_barrier()
    assert "/nobody" not in sim.world.published


async def test_ros2_publish_with_a_type_registers_the_topic(sim_ros2: SimulatedRobot) -> None:
    """ROS 2 (2.0.6/2.6.0+) accepts a type on publish to create the registration."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send(
            {"op": "publish", "topic": "/new", "type": "std_msgs/msg/String", "msg": {"data": "x"}}
        )
        await client.frames_before_barrier()
        topics = await client.values("/rosapi/topics")
    assert sim_ros2.world.published["/new"][-1].msg["data"] == "x"
    assert "/new" in topics["topics"]


async def test_type_conflict_on_advertise_is_only_logged(sim: SimulatedRobot) -> None:
    """Advertising an existing topic with another type is refused silently; the graph keeps the first type."""
    async with await RawClient.open(sim.url) as client:
        wrong = "std_msgs/msg/String" if sim.dialect == "ros2" else "std_msgs/String"
        await client.send({"op": "advertise", "topic": "/turtle1/pose", "type": wrong})
        assert await client.frames_before_barrier() == []
        topic_type = await client.values("/rosapi/topic_type", {"topic": "/turtle1/pose"})
    assert topic_type["type"].endswith("Pose")


async def test_incoming_fragments_are_reassembled_into_one_op(sim: SimulatedRobot) -> None:
    """A call_service split into fragment ops is joined and answered once."""
    text = json.dumps(
        {"op": "call_service", "id": "frag-call", "service": "/add_two_ints", "args": {"a": 3, "b": 4}}
    )
    chunks = [text[i : i + 10] for i in range(0, len(text), 10)]
    fragment_id = str(uuid.uuid4())
    async with await RawClient.open(sim.url) as client:
        for num, chunk in enumerate(chunks):
            await client.send(
                {"op": "fragment", "id": fragment_id, "data": chunk, "num": num, "total": len(chunks)}
            )
        reply = await client.reply("frag-call")
    assert reply["values"] == {"sum": 7}


async def test_fragment_size_splits_outgoing_frames_for_the_whole_connection(sim: SimulatedRobot) -> None:
    """A fragment_size on any op makes every larger outgoing frame arrive as fragment ops that join back."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/chatter", "fragment_size": 16, "id": "s"})
        first = await client.recv_until(lambda f: f.get("op") == "fragment")
        parts = [first]
        count = int(first["total"])
        while len(parts) < count:
            parts.append(await client.recv_until(lambda f: f.get("op") == "fragment"))
    assert [p["num"] for p in parts] == list(range(count))
    assert all(len(p["data"]) <= 16 for p in parts)
    text = "".join(p["data"] for p in parts)
    # Both lines compute total = ((len - 1) / size) + 1 with true division: a float, never an int.
    assert isinstance(first["total"], float)
    assert first["total"] == (len(text) - 1) / 16 + 1
    joined = json.loads(text)
    assert joined["op"] == "publish"
    assert joined["topic"] == "/chatter"
    assert joined["msg"]["data"].startswith("Hello World: ")
    # Fragments of an id-less publish carry id "0" (ROS 2) or 0 (ROS 1).
    assert first["id"] == ("0" if sim.dialect == "ros2" else 0)


async def test_ros2_fragment_size_is_capped_at_max_message_size(make_sim: MakeSim) -> None:
    """ROS 2 (2.0.2/2.4.0+) caps a client's fragment_size at the server's max_message_size."""
    robot = await make_sim(dialect="ros2", max_message_size=40)
    async with await RawClient.open(robot.url) as client:
        await client.send(
            {"op": "call_service", "id": "big", "service": "/rosapi/nodes", "fragment_size": 10**9}
        )
        first = await client.recv()
    assert first["op"] == "fragment"
    assert len(first["data"]) == 40


async def test_ros1_sends_whole_frames_unless_asked_to_fragment(sim_ros1: SimulatedRobot) -> None:
    """ROS 1 has no fragment size until a client sends one."""
    async with await RawClient.open(sim_ros1.url) as client:
        reply = await client.call("/rosapi/services")
    assert reply["op"] == "service_response"
    assert len(json.dumps(reply)) > 1000


async def test_throttle_rate_limits_how_often_a_topic_is_delivered(sim: SimulatedRobot) -> None:
    """With throttle_rate 300 ms, /chatter (10 Hz) arrives at most every 300 ms."""
    import time

    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/chatter", "throttle_rate": 300})
        stamps = []
        for _ in range(3):
            await client.next_publish("/chatter")
            stamps.append(time.monotonic())
    assert stamps[1] - stamps[0] >= 0.25
    assert stamps[2] - stamps[1] >= 0.25


async def test_unsubscribe_by_id_keeps_the_other_subscription(sim: SimulatedRobot) -> None:
    """Two subscriptions with different ids: removing one keeps data flowing for the other."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/chatter", "id": "a"})
        await client.send({"op": "subscribe", "topic": "/chatter", "id": "b"})
        await client.send({"op": "unsubscribe", "topic": "/chatter", "id": "a"})
        await client.frames_before_barrier()
        message = await client.next_publish("/chatter")
        await client.send({"op": "unsubscribe", "topic": "/chatter", "id": "b"})
        await client.frames_before_barrier()
        subscribers = await client.values("/rosapi/subscribers", {"topic": "/chatter"})
    assert message["msg"]["data"].startswith("Hello World")
    assert subscribers["subscribers"] == []


async def test_a_bad_frame_from_one_client_does_not_disturb_another(sim: SimulatedRobot) -> None:
    """Garbage on one socket; the other client's subscription and calls go on."""
    async with await RawClient.open(sim.url) as good, await RawClient.open(sim.url) as bad:
        await good.send({"op": "subscribe", "topic": "/chatter", "id": "s"})
        await good.next_publish("/chatter")
        for frame in ["{", "[]", "null", '{"op": 5}', '{"op": "publish", "topic": 3}', "\x00\xff"]:
            await bad.send(frame)
        await bad.ws.send(b"\xff\xfe not utf-8")
        await good.next_publish("/chatter")
        assert (await good.values("/add_two_ints", {"a": 1, "b": 1})) == {"sum": 2}
        assert (await bad.values("/add_two_ints", {"a": 2, "b": 2})) == {"sum": 4}


async def test_disconnect_cleans_up_subscriptions_and_advertisements_but_not_services(
    sim: SimulatedRobot,
) -> None:
    """Like rosbridge's finish(): topics are released; advertised services stay, as on the real server."""
    string = "std_msgs/msg/String" if sim.dialect == "ros2" else "std_msgs/String"
    trigger = "std_srvs/srv/Trigger" if sim.dialect == "ros2" else "std_srvs/Trigger"
    leaving = await RawClient.open(sim.url)
    await leaving.send({"op": "advertise", "topic": "/mine", "type": string})
    await leaving.send({"op": "subscribe", "topic": "/chatter"})
    await leaving.send({"op": "advertise_service", "service": "/my_service", "type": trigger})
    await leaving.frames_before_barrier()
    async with await RawClient.open(sim.url) as observer:
        before = await observer.values("/rosapi/topics")
        assert "/mine" in before["topics"]
        await leaving.close()
        await sim.wait_for(lambda w: sim.connection_count == 1)
        after = await observer.values("/rosapi/topics")
        subscribers = await observer.values("/rosapi/subscribers", {"topic": "/chatter"})
        services = await observer.values("/rosapi/services")
    # ROS 1 keeps the publisher for unregister_timeout (10 s) before it leaves the master's lists.
    assert ("/mine" in after["topics"]) is (sim.dialect == "ros1")
    assert "/rosbridge_websocket" not in subscribers["subscribers"]
    assert "/my_service" in services["services"]


async def test_a_client_hosted_service_is_forwarded_to_it_and_answered(sim: SimulatedRobot) -> None:
    """advertise_service: the bridge forwards call_service with a service_request id; the values return."""
    add = "example_interfaces/srv/AddTwoInts" if sim.dialect == "ros2" else "rospy_tutorials/AddTwoInts"
    async with await RawClient.open(sim.url) as host, await RawClient.open(sim.url) as caller:
        await host.send({"op": "advertise_service", "service": "/hosted_add", "type": add})
        await host.frames_before_barrier()
        await caller.send(
            {"op": "call_service", "id": "via-host", "service": "/hosted_add", "args": {"a": 1, "b": 2}}
        )
        request = await host.recv_until(lambda f: f.get("op") == "call_service")
        assert request["id"].startswith("service_request:/hosted_add:")
        assert request["args"] == {"a": 1, "b": 2}
        await host.send(
            {
                "op": "service_response",
                "id": request["id"],
                "service": "/hosted_add",
                "result": True,
                "values": {"sum": 99},
            }
        )
        reply = await caller.reply("via-host")
    assert reply["result"] is True
    assert reply["values"] == {"sum": 99}


async def test_a_slow_reader_loses_the_oldest_messages_not_memory(sim: SimulatedRobot) -> None:
    """A client that does not read gets at most MAX_QUEUED_MESSAGES queued; older data is dropped."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/chatter", "id": "s"})
        await client.frames_before_barrier()
        string = "std_msgs/msg/String" if sim.dialect == "ros2" else "std_msgs/String"
        for n in range(MAX_QUEUED_MESSAGES * 3):
            sim.bridge.publish_json("/chatter", string, {"data": f"flood {n}"})
        (conn,) = sim.bridge.connections.values()
        assert conn.dropped >= MAX_QUEUED_MESSAGES
        frames = await client.frames_before_barrier()
    # The talker's own /chatter messages may be interleaved; only the flood is counted.
    floods = [
        f["msg"]["data"] for f in frames if f.get("op") == "publish" and f["msg"]["data"].startswith("flood")
    ]
    assert len(floods) <= MAX_QUEUED_MESSAGES
    assert floods[-1] == f"flood {MAX_QUEUED_MESSAGES * 3 - 1}"
    assert "flood 0" not in floods


async def test_drop_connections_closes_sockets_and_clients_can_reconnect(sim: SimulatedRobot) -> None:
    """drop_connections() closes every socket; the server keeps serving."""
    client = await RawClient.open(sim.url)
    await client.values("/rosapi/get_time")
    await sim.drop_connections()
    await client.ws.wait_closed()
    await sim.wait_for(lambda w: sim.connection_count == 0)
    async with await RawClient.open(sim.url) as again:
        assert "time" in await again.values("/rosapi/get_time")


async def test_stop_and_start_serve_again_on_the_same_port(sim: SimulatedRobot) -> None:
    """stop() ends the server; start() serves on the same port (the restart our client must survive)."""
    port = sim.port
    await sim.stop()
    with pytest.raises(OSError, match=r"Connect call failed|refused"):
        await RawClient.open(sim.url)
    await sim.start()
    assert sim.port == port
    async with await RawClient.open(sim.url) as client:
        assert (await client.values("/add_two_ints", {"a": 1, "b": 2})) == {"sum": 3}


async def test_a_latched_advertisement_hands_the_last_message_to_later_subscribers(
    sim: SimulatedRobot,
) -> None:
    """advertise with latch: a subscriber arriving after the publish still gets the last message."""
    string = "std_msgs/msg/String" if sim.dialect == "ros2" else "std_msgs/String"
    async with await RawClient.open(sim.url) as talker, await RawClient.open(sim.url) as late:
        await talker.send({"op": "advertise", "topic": "/latched", "type": string, "latch": True})
        await talker.send({"op": "publish", "topic": "/latched", "msg": {"data": "first"}})
        await talker.send({"op": "publish", "topic": "/latched", "msg": {"data": "last"}})
        await talker.frames_before_barrier()
        await late.send({"op": "subscribe", "topic": "/latched"})
        message = await late.next_publish("/latched")
    assert message["msg"] == {"data": "last"}


async def test_ros2_accepts_a_qos_object_on_subscribe(sim_ros2: SimulatedRobot) -> None:
    """The qos object of protocol v2.1.0 is accepted; data flows."""
    qos = {"history": "keep_last", "depth": 5, "reliability": "best_available", "durability": "volatile"}
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send({"op": "subscribe", "topic": "/chatter", "qos": qos})
        message = await client.next_publish("/chatter")
    assert message["msg"]["data"].startswith("Hello World")


async def test_humble_refuses_best_available_qos_silently(sim_humble: SimulatedRobot) -> None:
    """Humble has no best_available policies: the subscribe is only logged, nothing arrives."""
    async with await RawClient.open(sim_humble.url) as client:
        await client.send({"op": "subscribe", "topic": "/chatter", "qos": {"reliability": "best_available"}})
        assert await client.frames_before_barrier() == []
        subscribers = await client.values("/rosapi/subscribers", {"topic": "/chatter"})
    assert subscribers["subscribers"] == []


async def test_ros1_rejects_three_part_type_names_silently(sim_ros1: SimulatedRobot) -> None:
    """ROS 1 only knows pkg/Type: advertising 'std_msgs/msg/String' is logged, nothing is registered."""
    async with await RawClient.open(sim_ros1.url) as client:
        await client.send({"op": "advertise", "topic": "/three_part", "type": "std_msgs/msg/String"})
        assert await client.frames_before_barrier() == []
        topics = await client.values("/rosapi/topics")
    assert "/three_part" not in topics["topics"]


async def test_stopping_mid_goal_and_restarting_leaves_a_working_action_server(sim: SimulatedRobot) -> None:
    """A goal cut short by stop() ends aborted; after start() a new goal succeeds."""
    async with await RawClient.open(sim.url) as client:
        await _send_fibonacci(client, sim, "before-stop", 40)
        await sim.wait_for(lambda w: "before-stop" in w.goals and w.goals["before-stop"].feedback_count >= 1)
    await sim.stop()
    await sim.start()
    assert sim.world.goals["before-stop"].finished
    async with await RawClient.open(sim.url) as client:
        await _send_fibonacci(client, sim, "after-restart", 3)
        await sim.wait_for(lambda w: "after-restart" in w.goals and w.goals["after-restart"].finished)
    assert sim.world.goals["after-restart"].sequence == [0, 1, 1, 2]


async def _send_fibonacci(client: RawClient, robot: SimulatedRobot, goal_id: str, order: int) -> None:
    if robot.dialect == "ros2":
        await client.send(
            {
                "op": "send_action_goal",
                "id": goal_id,
                "action": "/fibonacci",
                "action_type": "example_interfaces/action/Fibonacci",
                "args": {"order": order},
            }
        )
    else:
        goal = {"goal_id": {"id": goal_id}, "goal": {"order": order}}
        await client.send({"op": "publish", "topic": "/fibonacci/goal", "msg": goal})


async def test_wait_for_raises_timeout_error_when_the_world_never_gets_there(sim: SimulatedRobot) -> None:
    """robot.wait_for is bounded: an impossible condition ends in TimeoutError."""
    with pytest.raises(TimeoutError):
        await sim.wait_for(lambda w: w.turtle.x > 100, timeout=0.2)


async def test_a_service_whose_client_left_is_never_answered(sim_ros2: SimulatedRobot) -> None:
    """rosbridge keeps a client's advertised service after it disconnects; calls then run into the timeout."""
    host = await RawClient.open(sim_ros2.url)
    await host.send({"op": "advertise_service", "service": "/orphan", "type": "std_srvs/srv/Trigger"})
    await host.frames_before_barrier()
    await host.close()
    await sim_ros2.wait_for(lambda w: sim_ros2.connection_count == 0)
    async with await RawClient.open(sim_ros2.url) as caller:
        reply = await caller.call("/orphan", {}, timeout=0.2)
    assert reply["result"] is False
    assert reply["values"] == "Timeout exceeded while waiting for service response"


async def test_unadvertise_service_answers_calls_in_flight_with_an_empty_response(
    sim_ros2: SimulatedRobot,
) -> None:
    """ROS 2 aborts in-flight calls when a service is unadvertised: callers get a default response."""
    async with await RawClient.open(sim_ros2.url) as host, await RawClient.open(sim_ros2.url) as caller:
        await host.send({"op": "advertise_service", "service": "/going", "type": "std_srvs/srv/Trigger"})
        await host.frames_before_barrier()
        await caller.send({"op": "call_service", "id": "in-flight", "service": "/going"})
        await host.recv_until(lambda f: f.get("op") == "call_service")
        await host.send({"op": "unadvertise_service", "service": "/going"})
        reply = await caller.reply("in-flight")
        services = await caller.values("/rosapi/services")
    assert reply["result"] is True
    assert reply["values"] == {"success": False, "message": ""}
    assert "/going" not in services["services"]


async def test_unadvertise_service_of_someone_elses_service_is_only_logged(sim: SimulatedRobot) -> None:
    """Only the advertising client can unadvertise; anything else is logged and changes nothing."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "unadvertise_service", "service": "/add_two_ints"})
        assert await client.frames_before_barrier() == []
        assert (await client.values("/add_two_ints", {"a": 1, "b": 1})) == {"sum": 2}


async def test_a_subscribe_with_an_unhashable_id_registers_nothing(sim: SimulatedRobot) -> None:
    """rosbridge fails on an id it cannot use as a key; no subscription is left behind."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/chatter", "id": {"not": "hashable"}})
        await client.frames_before_barrier()
        subscribers = await client.values("/rosapi/subscribers", {"topic": "/chatter"})
    assert subscribers["subscribers"] == []


async def test_throttle_with_a_queue_releases_the_newest_messages_at_the_throttle_rate(
    sim: SimulatedRobot,
) -> None:
    """throttle_rate 250 ms with queue_length 1: messages keep coming, spaced by the throttle, newest kept."""
    import time

    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/chatter", "throttle_rate": 250, "queue_length": 1})
        received = []
        for _ in range(3):
            message = await client.next_publish("/chatter")
            received.append((time.monotonic(), int(message["msg"]["data"].split(": ")[1])))
    (t0, n0), (t1, n1), (t2, n2) = received
    assert t1 - t0 >= 0.2
    assert t2 - t1 >= 0.2
    assert n0 < n1 < n2


async def test_type_inference_needs_the_fully_qualified_name(sim: SimulatedRobot) -> None:
    """'chatter' does not find '/chatter' without a type; with a type it subscribes and echoes 'chatter'."""
    string = "std_msgs/msg/String" if sim.dialect == "ros2" else "std_msgs/String"
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "chatter", "id": "relative"})
        assert await client.frames_before_barrier() == []
        await client.send({"op": "subscribe", "topic": "chatter", "type": string, "id": "typed"})
        message = await client.next_publish("chatter")
    assert message["msg"]["data"].startswith("Hello World")


def _decode_png_op(frame: dict[str, Any]) -> dict[str, Any]:
    """png compression: base64 → PNG → RGB bytes → text without the newline padding → the publish message."""
    png = base64.b64decode(frame["data"])
    width, height = struct.unpack(">II", png[16:24])
    idat_len = struct.unpack(">I", png[33:37])[0]
    raw = zlib.decompress(png[41 : 41 + idat_len])
    stride = width * 3 + 1
    pixels = b"".join(raw[row * stride + 1 : (row + 1) * stride] for row in range(height))
    return dict(json.loads(pixels.decode("utf-8").rstrip("\n")))


async def test_png_compression_sends_png_ops_that_decode_to_the_publish(sim: SimulatedRobot) -> None:
    """subscribe with compression png: each message arrives as {op: png} holding the publish frame's text."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/chatter", "compression": "png"})
        frame = await client.recv_until(lambda f: f.get("op") == "png")
    message = _decode_png_op(frame)
    assert message["op"] == "publish"
    assert message["topic"] == "/chatter"
    assert message["msg"]["data"].startswith("Hello World: ")


async def test_interleaved_fragments_of_two_messages_are_joined_by_id(sim: SimulatedRobot) -> None:
    """Fragments of two calls, interleaved (and from two clients), each join into their own op."""
    texts = {
        f"frag-{n}": json.dumps(
            {"op": "call_service", "id": f"frag-{n}", "service": "/add_two_ints", "args": {"a": n, "b": 100}}
        )
        for n in (1, 2)
    }
    async with await RawClient.open(sim.url) as first, await RawClient.open(sim.url) as second:
        chunked = {key: [text[i : i + 7] for i in range(0, len(text), 7)] for key, text in texts.items()}
        for num in range(max(len(c) for c in chunked.values())):
            for client, (key, chunks) in zip((first, second), chunked.items(), strict=True):
                if num < len(chunks):
                    await client.send(
                        {"op": "fragment", "id": key, "data": chunks[num], "num": num, "total": len(chunks)}
                    )
        replies = [await first.reply("frag-1"), await second.reply("frag-2")]
    assert [r["values"]["sum"] for r in replies] == [101, 102]


async def test_many_clients_at_once_each_get_their_own_answers(sim: SimulatedRobot) -> None:
    """Twenty connections calling and subscribing at the same time: every reply goes to its own caller."""
    clients = [await RawClient.open(sim.url) for _ in range(20)]
    try:
        for n, client in enumerate(clients):
            await client.send({"op": "subscribe", "topic": "/chatter"})
            await client.send(
                {
                    "op": "call_service",
                    "id": f"many-{n}",
                    "service": "/add_two_ints",
                    "args": {"a": n, "b": n},
                }
            )
        sums = [(await client.reply(f"many-{n}"))["values"]["sum"] for n, client in enumerate(clients)]
        heard = [await client.next_publish("/chatter") for client in clients]
        assert sim.connection_count == 20
    finally:
        for client in clients:
            await client.close()
    assert sums == [2 * n for n in range(20)]
    assert all(h["msg"]["data"].startswith("Hello World") for h in heard)


async def test_both_lines_buffer_input_several_objects_per_frame_and_split_objects(
    sim: SimulatedRobot,
) -> None:
    """protocol.incoming is the same on both branches: objects are taken out of a per-connection buffer."""
    first = json.dumps(
        {"op": "call_service", "id": "x1", "service": "/add_two_ints", "args": {"a": 1, "b": 1}}
    )
    second = json.dumps(
        {"op": "call_service", "id": "x2", "service": "/add_two_ints", "args": {"a": 2, "b": 2}}
    )
    async with await RawClient.open(sim.url) as client:
        await client.send(first + second[:10])
        await client.send(second[10:])
        replies = [await client.reply("x1"), await client.reply("x2")]
    assert [r["values"] for r in replies] == [{"sum": 2}, {"sum": 4}]


async def test_a_bare_number_ends_the_connections_reading_on_both_lines(sim: SimulatedRobot) -> None:
    """'"id" in 5' raises outside the per-op error handling: the connection ignores everything after."""
    async with await RawClient.open(sim.url) as client:
        await client.send("5")
        await client.send({"op": "call_service", "id": "late", "service": "/rosapi/get_time"})
        conn = max(sim.bridge.connections.values(), key=lambda c: c.id)
        await sim.wait_for(lambda _: conn.frames_ignored >= 1)
    assert conn.dead
    assert conn.frames_queued == 0


async def test_ros2_rosbridge_also_publishes_its_client_topics(sim_ros2: SimulatedRobot) -> None:
    """The ros2 branch's ClientManager publishes /client_count and /connected_clients (transient local)."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send({"op": "subscribe", "topic": "/client_count"})
        count = await client.next_publish("/client_count")
        topics = await client.values("/rosapi/topics")
    assert count["msg"] == {"data": 1}
    types = dict(zip(topics["topics"], topics["types"], strict=True))
    assert types["/client_count"] == "std_msgs/msg/Int32"
    assert types["/connected_clients"] == "rosbridge_msgs/msg/ConnectedClients"


@pytest.mark.parametrize("args", [None, "hello", 5])
async def test_args_that_are_not_an_object_or_list_are_ignored_on_both_lines(
    sim: SimulatedRobot, args: Any
) -> None:
    """args_to_service_request_instance (ros1 and ros2 branches) only uses lists and dicts."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "call_service", "id": "n", "service": "/add_two_ints", "args": args})
        reply = await client.reply("n")
    assert reply["result"] is True
    assert reply["values"] == {"sum": 0}


async def test_ros2_resolves_a_relative_service_name_under_the_root(sim_ros2: SimulatedRobot) -> None:
    """ROS 2 call_service runs expand_topic_name first: 'add_two_ints' is /add_two_ints, 'nope' is /nope."""
    async with await RawClient.open(sim_ros2.url) as client:
        found = await client.call("add_two_ints", {"a": 1, "b": 2})
        missing = await client.call("nope")
    assert found["values"] == {"sum": 3}
    assert missing["values"] == "Service /nope does not exist"
