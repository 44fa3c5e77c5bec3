"""The ROS 1 dialect behaves as the real rosbridge_suite 0.11.17 on Noetic did, frame by frame.

Each case was first run against a real 0.11.17 bridge. Set ``ROSBRIDGE_TEST_URL`` to a real ROS 1 rosbridge
(with the same world nodes: turtlesim, /add_two_ints, /fibonacci...) to run them against it too; cases about
our world's internals only run against the simulated robot. Silence is checked with a barrier request.
"""

from __future__ import annotations

import json
import os
import re
import struct
import uuid
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import Any

import pytest
from rawclient import MakeSim, RawClient

from rosbridge_mcp_server.sim import SimulatedRobot

REAL_URL = os.environ.get("ROSBRIDGE_TEST_URL")


@dataclass
class Target:
    """The bridge under test: its URL, and our robot (None for a real bridge)."""

    url: str
    robot: SimulatedRobot | None


async def _is_ros1(url: str) -> bool:
    async with await RawClient.open(url) as client:
        reply = await client.call("/rosapi/get_ros_version")
    return reply["result"] is False


@pytest.fixture(params=["sim", pytest.param("real", marks=pytest.mark.real_bridge)])
async def target(request: pytest.FixtureRequest, make_sim: MakeSim) -> AsyncIterator[Target]:
    """A ROS 1 simulated robot, or the real ROS 1 bridge named by ROSBRIDGE_TEST_URL."""
    if request.param == "real":
        if not REAL_URL:
            pytest.skip("set ROSBRIDGE_TEST_URL=ws://host:port to run these against a real ROS 1 rosbridge")
        if not await _is_ros1(REAL_URL):
            pytest.skip("the real bridge is not ROS 1")
        yield Target(REAL_URL, None)
        return
    robot = await make_sim(dialect="ros1")
    yield Target(robot.url, robot)


@pytest.fixture
def url(target: Target) -> str:
    """The URL of the bridge under test."""
    return target.url


async def assert_reading_died(target: Target, client: RawClient, request_id: str) -> None:
    """``request_id`` (sent after the fatal frame) is never answered.

    Our robot says when it has dropped the frame (no timer needed); a real bridge gives no sign at all, so
    there the proof is a bounded wait.
    """
    robot = target.robot
    if robot is None:
        with pytest.raises(TimeoutError):
            await client.reply(request_id, wait=1.0)
        return
    conn = max(robot.bridge.connections.values(), key=lambda c: c.id)
    await robot.wait_for(lambda _: conn.frames_ignored >= 1)
    assert conn.dead
    assert conn.frames_queued == 0


async def _fragments(client: RawClient, request_id: Any) -> list[dict[str, Any]]:
    first = await client.recv_until(lambda f: f.get("op") == "fragment" and f.get("id") == request_id)
    parts = [first]
    while len(parts) < int(first["total"]):
        parts.append(
            await client.recv_until(lambda f: f.get("op") == "fragment" and f.get("id") == request_id)
        )
    return parts


# --- 1. fragments ---------------------------------------------------------------------------------------


async def test_fragment_total_is_a_float_from_true_division(url: str) -> None:
    """0.11.17 on Python 3 sends total = ((len - 1) / size) + 1, a float; int(total) is the count."""
    async with await RawClient.open(url) as client:
        await client.send(
            {"op": "call_service", "id": "f1", "service": "/rosapi/get_time", "fragment_size": 30}
        )
        parts = await _fragments(client, "f1")
    text = "".join(p["data"] for p in parts)
    assert isinstance(parts[0]["total"], float)
    assert parts[0]["total"] == (len(text) - 1) / 30 + 1
    assert len(parts) == int(parts[0]["total"])
    assert json.loads(text)["values"]["time"]["secs"] > 0


async def test_fragments_of_an_idless_service_response_carry_the_integer_0(url: str) -> None:
    """A call without id answers without id; its fragments carry id 0 (an int) on ROS 1."""
    async with await RawClient.open(url) as client:
        await client.send({"op": "call_service", "service": "/rosapi/get_time", "fragment_size": 30})
        parts = await _fragments(client, 0)
    assert all(p["id"] == 0 and isinstance(p["id"], int) for p in parts)
    assert "id" not in json.loads("".join(p["data"] for p in parts))


# --- 2. rospy's error texts -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("type_name", "detail"),
    [
        ("std_msgs/msg/String", "std_msgs/msg/String is not a valid type string"),
        ("", " is not a valid type string"),
    ],
)
async def test_rosapi_errors_carry_noetic_bytes_wrapper(url: str, type_name: str, detail: str) -> None:
    """Noetic's rospy formats the error bytes with %s: "... responded with an error: b'error ...'"."""
    async with await RawClient.open(url) as client:
        reply = await client.call("/rosapi/message_details", {"type": type_name})
    assert reply["result"] is False
    assert reply["values"] == (
        f"service [/rosapi/message_details] responded with an error: b'error processing request: {detail}'"
    )


async def test_an_error_text_with_a_quote_is_wrapped_in_double_quotes(url: str) -> None:
    """Python's bytes repr switches to b"..." when the text holds a single quote."""
    async with await RawClient.open(url) as client:
        reply = await client.call("/rosapi/message_details", {"type": "std_msgs/string"})
    assert reply["result"] is False
    assert reply["values"] == (
        'service [/rosapi/message_details] responded with an error: b"error processing request: Unable to '
        "import msg class string from package std_msgs. Caused by module 'std_msgs.msg' has no attribute "
        "'string'\""
    )


async def test_message_details_of_a_primitive_answers_no_typedefs(url: str) -> None:
    """'int32' is no message: rosapi answers an empty typedefs list rather than an error."""
    async with await RawClient.open(url) as client:
        assert (await client.values("/rosapi/message_details", {"type": "int32"})) == {"typedefs": []}


# --- 3. args that are neither an object nor a list ------------------------------------------------------


@pytest.mark.parametrize("args", [None, "hello", 5, True])
async def test_args_that_are_not_an_object_or_list_are_an_empty_request(url: str, args: Any) -> None:
    """services.py only handles lists and dicts: anything else leaves the request at its defaults."""
    async with await RawClient.open(url) as client:
        await client.send({"op": "call_service", "id": "a", "service": "/add_two_ints", "args": args})
        reply = await client.reply("a")
    assert reply == {
        "op": "service_response",
        "service": "/add_two_ints",
        "values": {"sum": 0},
        "result": True,
        "id": "a",
    }


# --- 4. names are resolved the rospy way ----------------------------------------------------------------


@pytest.mark.parametrize("spelling", ["/add_two_ints/", "//add_two_ints", "add_two_ints"])
async def test_service_names_are_canonicalised(url: str, spelling: str) -> None:
    """rospy resolves the name: trailing and doubled slashes go, relative names go under /."""
    async with await RawClient.open(url) as client:
        reply = await client.call(spelling, {"a": 1, "b": 1})
    assert reply["result"] is True
    assert reply["values"] == {"sum": 2}
    assert reply["service"] == spelling  # echoed as sent


@pytest.mark.parametrize(("spelling", "resolved"), [("nope", "/nope"), ("", "/"), ("/nope//", "/nope")])
async def test_missing_service_error_names_the_resolved_name(url: str, spelling: str, resolved: str) -> None:
    """'Service /nope does not exist' for 'nope'; the empty name resolves to '/'."""
    async with await RawClient.open(url) as client:
        reply = await client.call(spelling)
    assert reply["result"] is False
    assert reply["values"] == f"Service {resolved} does not exist"


async def test_topic_type_and_subscribe_accept_a_trailing_slash(url: str) -> None:
    """rostopic matches '/chatter/' to /chatter, and rospy subscribes the canonical name."""
    async with await RawClient.open(url) as client:
        topic_type = await client.values("/rosapi/topic_type", {"topic": "/chatter/"})
        await client.send({"op": "subscribe", "topic": "/chatter/"})
        frame = await client.next_publish("/chatter/")
    assert topic_type == {"type": "std_msgs/String"}
    assert frame["msg"]["data"].startswith("Hello World")


# --- 5. the input buffer and the inputs that end a connection's reading ---------------------------------


async def test_several_objects_in_one_frame_are_all_handled(url: str) -> None:
    """The buffer parser takes one object after the other out of the same frame."""
    calls = [
        {"op": "call_service", "id": f"m{n}", "service": "/add_two_ints", "args": {"a": n, "b": 1}}
        for n in range(3)
    ]
    async with await RawClient.open(url) as client:
        await client.send("".join(json.dumps(c) for c in calls))
        replies = [await client.reply(f"m{n}") for n in range(3)]
    assert [r["values"] for r in replies] == [{"sum": 1}, {"sum": 2}, {"sum": 3}]


async def test_an_object_split_over_frames_is_handled_once_complete(url: str) -> None:
    """The first half waits in the buffer; the second completes it."""
    text = json.dumps(
        {"op": "call_service", "id": "split", "service": "/add_two_ints", "args": {"a": 4, "b": 5}}
    )
    async with await RawClient.open(url) as client:
        await client.send(text[:20])
        await client.send(text[20:])
        reply = await client.reply("split")
    assert reply["values"] == {"sum": 9}


async def test_garbage_before_an_object_is_thrown_away(url: str) -> None:
    """'garbage{' stays in the buffer; the next frame's object is found after it."""
    async with await RawClient.open(url) as client:
        await client.send("garbage{")
        assert (await client.values("/add_two_ints", {"a": 2, "b": 2})) == {"sum": 4}


@pytest.mark.parametrize(
    "frame",
    [
        "5",
        "true",
        '{"op": "call_service", "id": "p", "service": "/rosapi/get_time", "png": "x"}',
        '{"op": "call_service", "id": "p", "service": "/rosapi/get_time", "message_intervall": null}',
    ],
)
async def test_inputs_that_end_the_connections_reading_silence_it_for_good(
    target: Target, frame: str
) -> None:
    """After such a frame every later frame is ignored (the socket stays open); others are unaffected."""
    async with await RawClient.open(target.url) as bystander, await RawClient.open(target.url) as victim:
        await victim.send(frame)
        await victim.send({"op": "call_service", "id": "after", "service": "/rosapi/get_time"})
        await assert_reading_died(target, victim, "after")
        assert (await bystander.call("/add_two_ints", {"a": 1, "b": 1}))["result"] is True
        pong = await victim.ws.ping()  # the socket is still open
        await pong


@pytest.mark.parametrize(
    "frame",
    [
        "[1, 2]",
        '"str"',
        "null",
        '{"op": "call_service", "id": "p", "service": "/rosapi/get_time", "message_intervall": "abc"}',
    ],
)
async def test_inputs_that_only_cost_their_own_frame(url: str, frame: str) -> None:
    """A list, a string, null or a non-numeric message_intervall string do not end the reading."""
    async with await RawClient.open(url) as client:
        await client.send(frame)
        assert (await client.values("/add_two_ints", {"a": 1, "b": 2})) == {"sum": 3}


async def test_a_non_numeric_fragment_size_breaks_every_later_reply(target: Target) -> None:
    """0.11.17 keeps fragment_size as sent; comparing a length with 'big' fails every later send."""
    async with await RawClient.open(target.url) as client:
        await client.send(
            {"op": "call_service", "id": "b1", "service": "/rosapi/get_time", "fragment_size": "big"}
        )
        await client.send({"op": "call_service", "id": "b2", "service": "/add_two_ints", "args": {"a": 1}})
        if target.robot is not None:
            # Our calls run as tasks: wait until /add_two_ints has answered (into the broken send).
            await target.robot.wait_for(lambda w: w.service_calls.get("/add_two_ints", 0) >= 1)
        else:
            # A real bridge answers in threads and gives no sign: a bounded wait is the only proof there.
            with pytest.raises(TimeoutError):
                await client.recv(wait=1.0)
        # Incoming ops still work: fragment_size null switches fragmenting off and replies flow again, so
        # this reply is a barrier: b1 and b2 were answered (and lost) before it.
        await client.send(
            {"op": "call_service", "id": "b3", "service": "/rosapi/get_time", "fragment_size": None}
        )
        first = await client.recv()
    assert first["id"] == "b3"
    assert first["result"] is True


async def test_a_binary_frame_is_read_through_its_bytes_repr(url: str) -> None:
    """0.11.17 appends str(payload) ("b'{...}'"); the brace scan still finds the object inside."""
    async with await RawClient.open(url) as client:
        await client.ws.send(
            json.dumps({"op": "call_service", "id": "bin", "service": "/rosapi/get_time"}).encode()
        )
        reply = await client.reply("bin")
        # The trailing quote left in the buffer does not disturb the next frame.
        assert (await client.values("/add_two_ints", {"a": 3, "b": 3})) == {"sum": 6}
    assert reply["result"] is True


# --- 6. rosbridge's own topics --------------------------------------------------------------------------


async def test_client_count_is_latched_and_follows_connects_and_disconnects(url: str) -> None:
    """/client_count (std_msgs/Int32, latched) is republished on every connect and disconnect."""
    async with await RawClient.open(url) as watcher:
        await watcher.send({"op": "subscribe", "topic": "/client_count"})
        now = (await watcher.next_publish("/client_count"))["msg"]["data"]
        other = await RawClient.open(url)
        assert (await watcher.next_publish("/client_count"))["msg"]["data"] == now + 1
        await other.close()
        assert (await watcher.next_publish("/client_count"))["msg"]["data"] == now


async def test_connected_clients_names_each_clients_address_and_time(url: str) -> None:
    """/connected_clients (rosbridge_msgs/ConnectedClients, latched) lists ip_address and connection_time."""
    async with await RawClient.open(url) as client:
        await client.send({"op": "subscribe", "topic": "/connected_clients"})
        clients = (await client.next_publish("/connected_clients"))["msg"]["clients"]
        topics = await client.values("/rosapi/topics")
        details = await client.values("/rosapi/node_details", {"node": "/rosbridge_websocket"})
    assert clients
    assert clients[-1]["ip_address"] == "127.0.0.1"
    assert set(clients[-1]["connection_time"]) == {"secs", "nsecs"}
    assert clients[-1]["connection_time"]["secs"] > 0
    types = dict(zip(topics["topics"], topics["types"], strict=True))
    assert types["/client_count"] == "std_msgs/Int32"
    assert types["/connected_clients"] == "rosbridge_msgs/ConnectedClients"
    assert {"/client_count", "/connected_clients"} <= set(details["publishing"])


# --- 7. rosapi details ----------------------------------------------------------------------------------


async def test_service_providers_names_a_node_once_per_matching_service(url: str) -> None:
    """/reset and /clear are both std_srvs/Empty on /turtlesim: it is listed twice."""
    async with await RawClient.open(url) as client:
        providers = await client.values("/rosapi/service_providers", {"service": "std_srvs/Empty"})
    assert providers == {"providers": ["/turtlesim", "/turtlesim"]}


@pytest.mark.parametrize("value", ["null", '{"a": null}'])
async def test_set_param_with_null_fails_with_xmlrpcs_text(url: str, value: str) -> None:
    """XML-RPC cannot marshal None: rospy's error, and the parameter is left alone."""
    async with await RawClient.open(url) as client:
        await client.values("/rosapi/set_param", {"name": "/probe_null", "value": "1"})
        reply = await client.call("/rosapi/set_param", {"name": "/probe_null", "value": value})
        after = await client.values("/rosapi/get_param", {"name": "/probe_null"})
        await client.values("/rosapi/delete_param", {"name": "/probe_null"})
    assert reply["result"] is False
    assert reply["values"] == (
        "service [/rosapi/set_param] responded with an error: "
        "b'error processing request: cannot marshal None unless allow_none is enabled'"
    )
    assert after == {"value": "1"}


async def test_the_master_remembers_the_type_of_a_topic_nobody_uses_any_more(url: str) -> None:
    """After unsubscribe, topic_type and topics_for_type still know it; topics no longer lists it."""
    async with await RawClient.open(url) as client:
        await client.send({"op": "subscribe", "topic": "/probe_memory", "type": "std_msgs/Float64"})
        await client.send({"op": "unsubscribe", "topic": "/probe_memory"})
        topic_type = await client.values("/rosapi/topic_type", {"topic": "/probe_memory"})
        for_type = await client.values("/rosapi/topics_for_type", {"type": "std_msgs/Float64"})
        topics = await client.values("/rosapi/topics")
        # A subscribe without type infers the remembered type.
        await client.send({"op": "subscribe", "topic": "/probe_memory"})
        subscribers = await client.values("/rosapi/subscribers", {"topic": "/probe_memory"})
    assert topic_type == {"type": "std_msgs/Float64"}
    assert "/probe_memory" in for_type["topics"]
    assert "/probe_memory" not in topics["topics"]
    assert subscribers == {"subscribers": ["/rosbridge_websocket"]}


# --- 10. what a message looks like after rospy carried it -----------------------------------------------


async def _latched_publish(url: str, topic: str, msg_type: str, msg: dict[str, Any]) -> dict[str, Any]:
    """Advertise without latch, publish with latch: true, and return what a later subscriber gets."""
    async with await RawClient.open(url) as publisher, await RawClient.open(url) as subscriber:
        await publisher.send({"op": "advertise", "topic": topic, "type": msg_type})
        await publisher.send({"op": "publish", "topic": topic, "latch": True, "msg": msg})
        await publisher.frames_before_barrier()
        await subscriber.send({"op": "subscribe", "topic": topic})
        return (await subscriber.next_publish(topic))["msg"]


async def test_latch_on_a_publish_op_latches_the_topic(url: str) -> None:
    """0.11.17 registers the publisher again with the publish's latch flag: a later subscriber gets it."""
    msg = await _latched_publish(url, "/probe_latch_op", "std_msgs/String", {"data": "kept"})
    assert msg == {"data": "kept"}


async def test_root_header_seq_is_the_publishers_own_counter(url: str) -> None:
    """rospy overwrites header.seq: the first message of a new publisher is seq 1, whatever was sent."""
    msg = await _latched_publish(
        url, "/probe_seq", "geometry_msgs/PointStamped", {"header": {"seq": 42, "frame_id": "f"}}
    )
    assert msg["header"]["seq"] == 1
    assert msg["header"]["frame_id"] == "f"


async def test_float32_values_arrive_rounded_to_float32(url: str) -> None:
    """0.1 on a std_msgs/Float32 comes back as 0.10000000149011612 (packed as a C float on the way)."""
    msg = await _latched_publish(url, "/probe_f32", "std_msgs/Float32", {"data": 0.1})
    assert msg == {"data": 0.10000000149011612}


async def test_times_arrive_canonical(url: str) -> None:
    """genpy canonicalizes a time when unpacking: 1 s + 2e9 ns arrives as 3 s + 0 ns."""
    msg = await _latched_publish(
        url, "/probe_time", "std_msgs/Time", {"data": {"secs": 1, "nsecs": 2000000000}}
    )
    assert msg == {"data": {"secs": 3, "nsecs": 0}}


@pytest.mark.parametrize(
    "data",
    [{"secs": -1, "nsecs": 0}, {"secs": 2**32, "nsecs": 0}, {"secs": 0, "nsecs": -5}],
)
async def test_a_time_that_does_not_pack_as_uint32_is_lost(sim_ros1: SimulatedRobot, data: Any) -> None:
    """A negative or too large time fails genpy's '<2I' pack: only logged, nobody gets the message."""
    async with await RawClient.open(sim_ros1.url) as client:
        await client.send({"op": "advertise", "topic": "/probe_bad_time", "type": "std_msgs/Time"})
        await client.send({"op": "subscribe", "topic": "/probe_bad_time"})
        await client.send({"op": "publish", "topic": "/probe_bad_time", "msg": {"data": data}})
        assert await client.frames_before_barrier() == []


async def test_the_turtle_pose_is_float32(sim_ros1: SimulatedRobot) -> None:
    """turtlesim's Pose is float32: the pose on the wire is the world's pose rounded to float32."""
    sim_ros1.world.turtle.x = 1.1
    async with await RawClient.open(sim_ros1.url) as client:
        await client.send({"op": "subscribe", "topic": "/turtle1/pose"})
        pose = (await client.next_publish("/turtle1/pose"))["msg"]
    assert pose["x"] == struct.unpack("<f", struct.pack("<f", 1.1))[0]


# --- 8. actionlib's SimpleActionServer ------------------------------------------------------------------

ACCEPTED = "This goal has been accepted by the simple action server"


async def _action_client(url: str) -> RawClient:
    client = await RawClient.open(url)
    for leaf in ("status", "feedback", "result"):
        await client.send({"op": "subscribe", "topic": f"/fibonacci/{leaf}"})
    await client.send(
        {"op": "advertise", "topic": "/fibonacci/goal", "type": "actionlib_tutorials/FibonacciActionGoal"}
    )
    await client.send({"op": "advertise", "topic": "/fibonacci/cancel", "type": "actionlib_msgs/GoalID"})
    await client.frames_before_barrier()
    return client


def _result_for(goal_id: str) -> Any:
    return lambda f: f.get("topic") == "/fibonacci/result" and f["msg"]["status"]["goal_id"]["id"] == goal_id


async def test_a_cancel_that_arrives_before_its_goal_recalls_it(url: str) -> None:
    """ActionServer keeps the early cancel (RECALLING); the goal then ends RECALLED (8), empty, stamp 0."""
    goal_id = f"early-{uuid.uuid4().hex}"
    client = await _action_client(url)
    try:
        await client.send({"op": "publish", "topic": "/fibonacci/cancel", "msg": {"id": goal_id}})
        # The early cancel shows in the status list as RECALLING (7) until its goal comes.
        await client.recv_until(
            lambda f: (
                f.get("topic") == "/fibonacci/status"
                and any(s["goal_id"]["id"] == goal_id and s["status"] == 7 for s in f["msg"]["status_list"])
            ),
            wait=10.0,
        )
        await client.send(
            {
                "op": "publish",
                "topic": "/fibonacci/goal",
                "msg": {"goal_id": {"id": goal_id}, "goal": {"order": 5}},
            }
        )
        result = (await client.recv_until(_result_for(goal_id), wait=10.0))["msg"]
    finally:
        await client.close()
    assert result["status"]["status"] == 8
    assert result["status"]["goal_id"]["stamp"] == {"secs": 0, "nsecs": 0}
    assert result["result"] == {"sequence": []}


async def test_an_accepted_goal_goes_straight_to_active_with_the_simple_servers_text(url: str) -> None:
    """No PENDING (0) before ACTIVE (1); status and feedback say the simple action server accepted it."""
    goal_id = f"text-{uuid.uuid4().hex}"
    client = await _action_client(url)
    try:
        await client.send(
            {
                "op": "publish",
                "topic": "/fibonacci/goal",
                "msg": {"goal_id": {"id": goal_id}, "goal": {"order": 3}},
            }
        )
        statuses: list[dict[str, Any]] = []
        feedback = await client.recv_until(
            lambda f: (
                f.get("topic") == "/fibonacci/feedback" and f["msg"]["status"]["goal_id"]["id"] == goal_id
            ),
            wait=10.0,
        )
        result = (await client.recv_until(_result_for(goal_id), wait=10.0))["msg"]
        statuses = [
            s
            for f in client.backlog
            if f.get("topic") == "/fibonacci/status"
            for s in f["msg"]["status_list"]
            if s["goal_id"]["id"] == goal_id
        ]
    finally:
        await client.close()
    assert statuses, "the goal showed up in the status list"
    assert statuses[0]["status"] == 1
    assert statuses[0]["text"] == ACCEPTED
    assert feedback["msg"]["status"]["text"] == ACCEPTED
    assert result["status"]["status"] == 3
    assert result["status"]["text"] == ""


async def test_a_goal_without_id_gets_actionlibs_generated_id(url: str) -> None:
    """GoalIDGenerator: '/fibonacci_server-<n>-<secs>.<nsecs>', stamped when generated."""
    client = await _action_client(url)
    try:
        await client.send({"op": "publish", "topic": "/fibonacci/goal", "msg": {"goal": {"order": 2}}})
        result = await client.recv_until(lambda f: f.get("topic") == "/fibonacci/result", wait=10.0)
    finally:
        await client.close()
    goal_id = result["msg"]["status"]["goal_id"]
    match = re.fullmatch(r"/fibonacci_server-(\d+)-(\d+)\.(\d+)", goal_id["id"])
    assert match is not None, goal_id
    assert (int(match[2]), int(match[3])) == (goal_id["stamp"]["secs"], goal_id["stamp"]["nsecs"])


# --- 9. services hosted by a client ---------------------------------------------------------------------


async def _take_away(url: str, host: RawClient, services: list[str]) -> None:
    """On a real bridge, unadvertise the services a test advertised, and wait until the bridge did.

    0.11.17 keeps a client's services after it disconnects, and drops the frames it has not handled yet when a
    connection closes (each unadvertise_service takes it 1 s): without this, every run leaves services behind.
    """
    if url != REAL_URL:
        return
    for service in services:
        await host.send({"op": "unadvertise_service", "service": service})
    await host.frames_before_barrier()  # bounded: 5 s


async def test_request_ids_count_per_advertised_service(url: str) -> None:
    """Each advertisement counts its own requests from 1: service_request:/svc:1 for every service."""
    names = [f"/probe_count_{uuid.uuid4().hex[:8]}" for _ in range(2)]
    async with await RawClient.open(url) as host, await RawClient.open(url) as caller:
        for name in names:
            await host.send(
                {"op": "advertise_service", "service": name, "type": "rospy_tutorials/AddTwoInts"}
            )
        await host.frames_before_barrier()
        ids = []
        for name in names:
            await caller.send({"op": "call_service", "id": name, "service": name, "args": {"a": 1, "b": 2}})
            request = await host.recv_until(lambda f: f.get("op") == "call_service")
            ids.append(request["id"])
            await host.send(
                {
                    "op": "service_response",
                    "service": name,
                    "id": request["id"],
                    "values": {"sum": 3},
                    "result": True,
                }
            )
            assert (await caller.reply(name))["values"] == {"sum": 3}
        await _take_away(url, host, names)
    assert ids == [f"service_request:{name}:1" for name in names]


async def test_unadvertising_a_service_with_a_call_pending_fails_that_call(url: str) -> None:
    """The pending caller gets rospy's 'service handler returned None'; after 1 s the service is gone."""
    name = f"/probe_gone_{uuid.uuid4().hex[:8]}"
    async with await RawClient.open(url) as host, await RawClient.open(url) as caller:
        await host.send({"op": "advertise_service", "service": name, "type": "rospy_tutorials/AddTwoInts"})
        await host.frames_before_barrier()
        await caller.send({"op": "call_service", "id": "pending", "service": name, "args": {"a": 1, "b": 2}})
        await host.recv_until(lambda f: f.get("op") == "call_service")
        await host.send({"op": "unadvertise_service", "service": name})
        failed = await caller.reply("pending")
        # The host's reading busy-waits 1 s inside unadvertise_service; this barrier is answered after it.
        await host.frames_before_barrier()
        gone = await caller.call(name, {"a": 1, "b": 2})
    assert failed["result"] is False
    assert failed["values"] == (
        f"service [{name}] responded with an error: "
        "b'service cannot process request: service handler returned None'"
    )
    assert gone["values"] == f"Service {name} does not exist"


# --- 11. list order -------------------------------------------------------------------------------------


async def test_rosapi_lists_come_in_registration_order(url: str) -> None:
    """The ROS 1 master and parameter server list in registration order: what a client adds comes last."""
    suffix = uuid.uuid4().hex[:8]
    topic, service, param = f"/a_probe_{suffix}", f"/a_probe_srv_{suffix}", f"/a_probe_param_{suffix}"
    async with await RawClient.open(url) as client:
        await client.send({"op": "advertise", "topic": topic, "type": "std_msgs/String"})
        await client.send({"op": "advertise_service", "service": service, "type": "std_srvs/Trigger"})
        await client.values("/rosapi/set_param", {"name": param, "value": "1"})
        topics = (await client.values("/rosapi/topics"))["topics"]
        services = (await client.values("/rosapi/services"))["services"]
        names = (await client.values("/rosapi/get_param_names"))["names"]
        await client.values("/rosapi/delete_param", {"name": param})
        await _take_away(url, client, [service])
    assert topics[-1] == topic
    assert services[-1] == service
    assert names[-1] == param
    assert topics != sorted(topics)


async def test_an_unadvertised_publisher_lingers_for_unregister_timeout(sim_ros1: SimulatedRobot) -> None:
    """0.11.17 unregisters rosbridge's publisher 10 s after the last unadvertise (shortened here)."""
    sim_ros1.bridge.unregister_timeout = 0.05
    async with await RawClient.open(sim_ros1.url) as client:
        await client.send({"op": "advertise", "topic": "/probe_linger", "type": "std_msgs/String"})
        await client.send({"op": "unadvertise", "topic": "/probe_linger"})
        lingering = await client.values("/rosapi/publishers", {"topic": "/probe_linger"})
        await sim_ros1.wait_for(lambda _: "/probe_linger" not in sim_ros1.graph.topic_types)
        gone = await client.values("/rosapi/publishers", {"topic": "/probe_linger"})
        remembered = await client.values("/rosapi/topic_type", {"topic": "/probe_linger"})
    assert lingering == {"publishers": ["/rosbridge_websocket"]}
    assert gone == {"publishers": []}
    assert remembered == {"type": "std_msgs/String"}


async def test_advertising_again_while_lingering_takes_the_publisher_over(sim_ros1: SimulatedRobot) -> None:
    """A client advertising the topic again within the timeout keeps the one publisher alive."""
    async with await RawClient.open(sim_ros1.url) as client:
        await client.send({"op": "advertise", "topic": "/probe_again", "type": "std_msgs/String"})
        await client.send({"op": "unadvertise", "topic": "/probe_again"})
        await client.send({"op": "advertise", "topic": "/probe_again", "type": "std_msgs/String"})
        await client.frames_before_barrier()
    assert sim_ros1.graph.node("/rosbridge_websocket").publishes["/probe_again"] == 1


async def test_frames_are_written_the_way_ujson_writes_them(url: str) -> None:
    """0.11.17 writes with ujson: compact separators, every '/' escaped as '\\/'."""
    async with await RawClient.open(url) as client:
        await client.send(
            {"op": "call_service", "id": "u", "service": "/add_two_ints", "args": {"a": 1, "b": 1}}
        )
        text = await client.ws.recv()
    assert text == (
        '{"op":"service_response","service":"\\/add_two_ints","values":{"sum":2},"result":true,"id":"u"}'
    )
