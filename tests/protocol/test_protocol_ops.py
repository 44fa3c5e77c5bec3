"""Op builders, id minting and lenient JSON: what goes on the wire, without a socket."""

from __future__ import annotations

import json
import math

import pytest

from rosbridge_mcp_server.wire import protocol

FORBIDDEN_KEYS = {"png", "message_intervall", "fragment_size"}

ALL_BUILT_OPS = [
    protocol.advertise("/cmd_vel", "geometry_msgs/msg/Twist", id="advertise:/cmd_vel:1"),
    protocol.unadvertise("/cmd_vel", id="advertise:/cmd_vel:1"),
    protocol.publish("/cmd_vel", {"linear": {"x": 1.0}}),
    protocol.subscribe("/chatter", "std_msgs/msg/String", id="subscribe:/chatter:2", throttle_rate=100),
    protocol.unsubscribe("/chatter", id="subscribe:/chatter:2"),
    protocol.call_service("/add_two_ints", {"a": 1, "b": 2}, id="call_service:/add_two_ints:3", timeout=2.5),
    protocol.send_action_goal("/fibonacci", "pkg/action/Fibonacci", {"order": 3}, id="goal:/fibonacci:x-4"),
    protocol.cancel_action_goal("/fibonacci", id="goal:/fibonacci:x-4"),
]


@pytest.mark.parametrize("op", ALL_BUILT_OPS, ids=lambda op: op["op"])
def test_built_ops_never_carry_keys_that_can_kill_a_connection(op: dict[str, object]) -> None:
    """No builder emits png, message_intervall or fragment_size (they break rosbridge's reader)."""
    assert FORBIDDEN_KEYS.isdisjoint(op)
    assert isinstance(op["op"], str)


@pytest.mark.parametrize("op", ALL_BUILT_OPS, ids=lambda op: op["op"])
def test_encode_writes_one_json_object_per_frame(op: dict[str, object]) -> None:
    """encode() produces exactly one JSON object that decodes back to the op."""
    text = protocol.encode(op)
    assert "\n" not in text
    assert json.loads(text) == op


def test_subscribe_sends_integer_throttle_and_queue_fields() -> None:
    """throttle_rate/queue_length go out as ints (a float makes the server ignore the subscribe)."""
    op = protocol.subscribe("/x", None, id="s", throttle_rate=100.0, queue_length=2.0)  # type: ignore[arg-type]
    assert op["throttle_rate"] == 100
    assert type(op["throttle_rate"]) is int
    assert type(op["queue_length"]) is int
    assert "type" not in op


def test_unsubscribe_always_names_its_own_id() -> None:
    """unsubscribe carries the subscription id, so other listeners of the topic keep theirs."""
    assert protocol.unsubscribe("/chatter", id="subscribe:/chatter:9") == {
        "op": "unsubscribe",
        "id": "subscribe:/chatter:9",
        "topic": "/chatter",
    }


def test_call_service_carries_timeout_only_when_positive() -> None:
    """The ROS 2 timeout field is sent as a float when given and left out otherwise."""
    with_timeout = protocol.call_service("/s", None, id="c", timeout=3)
    assert with_timeout["timeout"] == 3.0
    assert isinstance(with_timeout["timeout"], float)
    assert "timeout" not in protocol.call_service("/s", None, id="c")
    assert "timeout" not in protocol.call_service("/s", None, id="c", timeout=0)
    assert "args" not in protocol.call_service("/s", None, id="c")


def test_send_action_goal_uses_the_action_type_field() -> None:
    """The goal op names its type in action_type (not type) and asks for feedback."""
    op = protocol.send_action_goal("/f", "pkg/action/F", {"order": 1}, id="g")
    assert op["action_type"] == "pkg/action/F"
    assert "type" not in op
    assert op["feedback"] is True
    assert op["args"] == {"order": 1}


def test_id_minter_makes_readable_unique_ids() -> None:
    """Ids read like call_service:/add_two_ints:7 and never repeat."""
    minter = protocol.IdMinter(token="abcd")
    first = minter.mint("call_service", "/add_two_ints")
    second = minter.mint("call_service", "/add_two_ints")
    assert first.startswith("call_service:/add_two_ints:")
    assert first != second
    assert len({minter.mint("subscribe", "/t") for _ in range(1000)}) == 1000


def test_goal_ids_differ_between_clients() -> None:
    """Two minters (two clients of one bridge) never mint the same goal id."""
    a, b = protocol.IdMinter(), protocol.IdMinter()
    assert a.token != b.token
    ids_a = {a.goal_id("/fibonacci") for _ in range(50)}
    ids_b = {b.goal_id("/fibonacci") for _ in range(50)}
    assert ids_a.isdisjoint(ids_b)
    assert all(a.token in gid for gid in ids_a)


def test_inbound_frames_accept_nan_and_infinity() -> None:
    """Bare NaN/Infinity tokens (ROS 2 fixed-size float arrays) parse instead of failing."""
    frame = '{"op": "publish", "topic": "/c", "msg": {"c": [NaN, Infinity, -Infinity, 1.5]}}'
    event = protocol.InboundDecoder().feed(frame)
    assert isinstance(event, protocol.PublishEvent)
    value = event.msg
    assert math.isnan(value["c"][0])
    assert value["c"][1] == math.inf
    assert value["c"][2] == -math.inf
    assert value["c"][3] == 1.5


def test_encode_writes_non_finite_floats_as_bare_tokens() -> None:
    """NaN goes out as NaN (rosbridge accepts it; it rejects null for a float)."""
    assert protocol.encode({"x": math.nan}) == '{"x":NaN}'


def test_an_id_carries_at_most_a_bounded_part_of_a_long_name() -> None:
    """A 6 MB name gives a short id (the counter keeps it unique); a normal name is kept whole."""
    minter = protocol.IdMinter(token="t")
    long_name = "/" + "a" * 6_000_000
    first, second = minter.mint("advertise", long_name), minter.mint("advertise", long_name)
    assert len(first) < protocol.ID_NAME_CHARS + 30
    assert first != second
    assert minter.mint("call_service", "/add_two_ints").startswith("call_service:/add_two_ints:")
    assert len(minter.goal_id(long_name)) < protocol.ID_NAME_CHARS + 30


def test_subscribe_carries_a_qos_object_only_when_given() -> None:
    """A ROS 2 qos object rides on subscribe as given; without one the key is absent (older bridges)."""
    qos = {"reliability": "reliable", "durability": "transient_local", "depth": 1, "history": "keep_last"}
    assert protocol.subscribe("/map", "nav_msgs/msg/OccupancyGrid", id="s1", qos=qos)["qos"] == qos
    assert "qos" not in protocol.subscribe("/map", None, id="s2")
