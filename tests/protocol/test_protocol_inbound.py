"""Classifying inbound frames and reassembling fragments, fed as text without a socket."""

from __future__ import annotations

import json
from array import array

import cbor2
import pytest

from rosbridge_mcp_server.errors import ProtocolError
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.fragments import FragmentAssembler


def fragments(message: dict[str, object], size: int, fid: object) -> list[dict[str, object]]:
    """Split a message the way rosbridge does: by characters of its JSON text."""
    text = json.dumps(message)
    chunks = [text[i : i + size] for i in range(0, len(text), size)]
    return [
        {"op": "fragment", "id": fid, "data": chunk, "num": num, "total": len(chunks)}
        for num, chunk in enumerate(chunks)
    ]


def test_publish_frames_are_routed_by_topic() -> None:
    """A publish frame (no id) becomes a PublishEvent with its topic and message."""
    event = protocol.InboundDecoder().feed('{"op":"publish","topic":"/chatter","msg":{"data":"hi"}}')
    assert event == protocol.PublishEvent("/chatter", {"data": "hi"})


@pytest.mark.parametrize("op", ["service_response", "action_feedback", "action_result"])
def test_replies_are_routed_by_id(op: str) -> None:
    """service_response / action_feedback / action_result become ReplyEvents keyed by id."""
    frame = {"op": op, "id": "call_service:/x:1", "result": True, "values": {}}
    event = protocol.InboundDecoder().feed(json.dumps(frame))
    assert isinstance(event, protocol.ReplyEvent)
    assert event.op == op
    assert event.id == "call_service:/x:1"
    assert event.frame == frame


def test_an_error_status_naming_a_request_is_routed_to_it() -> None:
    """rosbridge-server-rs answers a refused op with an error status carrying the op's id: a reply."""
    frame = {"op": "status", "level": "error", "msg": "unknown active goal", "id": "goal:/f:1"}
    event = protocol.InboundDecoder().feed(json.dumps(frame))
    assert isinstance(event, protocol.ReplyEvent)
    assert (event.op, event.id, event.frame) == ("status", "goal:/f:1", frame)


def test_a_status_that_is_not_an_error_stays_a_notice() -> None:
    """Only an error names a refusal; an info or warning status with an id is logged."""
    frame = {"op": "status", "level": "warning", "msg": "slow", "id": "call_service:/x:1"}
    event = protocol.InboundDecoder().feed(json.dumps(frame))
    assert isinstance(event, protocol.Notice)
    assert "bridge status (warning): slow" in event.text


@pytest.mark.parametrize(
    ("data", "expected"),
    [
        ('{"op":"status","level":"error","msg":"boom"}', "bridge status (error): boom"),
        ('{"op":"set_level","level":"info"}', "unsupported op 'set_level'"),
        ('{"op":"service_response","result":true}', "without an id"),
        ('{"level":"x"}', "without an op"),
        ("[1, 2]", "not a JSON object"),
        ("{not json", "malformed JSON"),
        (b"\xa2\x62op", "binary frame"),
        ('{"op":"png","data":"AAAA"}', "png frame"),
        ('{"op":"publish","topic":"/x"}', "without topic or msg"),
    ],
)
def test_frames_we_do_not_act_on_become_notices(data: str | bytes, expected: str) -> None:
    """status, unknown ops, malformed JSON and binary frames are reported, never raised."""
    event = protocol.InboundDecoder().feed(data)
    assert isinstance(event, protocol.Notice)
    assert expected in event.text


def test_fragmented_publish_is_reassembled_and_routed() -> None:
    """The fragments of a publish (id "0", as ROS 2 sends them) come out as one PublishEvent."""
    message = {"op": "publish", "topic": "/map", "msg": {"data": list(range(200))}}
    decoder = protocol.InboundDecoder()
    events = [decoder.feed(json.dumps(f)) for f in fragments(message, 97, "0")]
    assert all(isinstance(e, protocol.Notice) and e.level == "debug" for e in events[:-1])
    assert events[-1] == protocol.PublishEvent("/map", message["msg"])  # type: ignore[arg-type]
    assert decoder.assembler.pending == 0


def test_fragment_ids_may_be_the_integer_zero() -> None:
    """ROS 1 sends id 0 (an int) for fragments of id-less messages."""
    message = {"op": "service_response", "id": "c:1", "result": True, "values": {"x": "y" * 300}}
    decoder = protocol.InboundDecoder()
    events = [decoder.feed(json.dumps(f)) for f in fragments(message, 50, 0)]
    assert isinstance(events[-1], protocol.ReplyEvent)
    assert events[-1].id == "c:1"


def test_fragments_with_a_fractional_total_from_noetic_are_reassembled() -> None:
    """Noetic (0.11.17) sends total as a float (5.5 for five parts); the message still arrives."""
    message = {"op": "service_response", "id": "c:2", "result": True, "values": {"x": "y" * 230}}
    text = json.dumps(message)
    size = 50
    count = len(range(0, len(text), size))
    # The server's own arithmetic: ((len - 1) / size) + 1 with true division.
    noetic_total = ((len(text) - 1) / size) + 1
    assert int(noetic_total) == count
    assert noetic_total != count
    decoder = protocol.InboundDecoder()
    events = [
        decoder.feed(
            json.dumps(
                {"op": "fragment", "id": 0, "data": text[i : i + size], "num": n, "total": noetic_total}
            )
        )
        for n, i in enumerate(range(0, len(text), size))
    ]
    assert isinstance(events[-1], protocol.ReplyEvent)
    assert events[-1].id == "c:2"


def test_fragment_buffer_restarts_when_part_zero_arrives_again() -> None:
    """Two messages sharing id "0": the second part 0 discards the first, unfinished message."""
    first = fragments({"op": "publish", "topic": "/a", "msg": {"d": "a" * 100}}, 40, "0")
    second = fragments({"op": "publish", "topic": "/b", "msg": {"d": "b" * 100}}, 40, "0")
    assembler = FragmentAssembler()
    assert assembler.add(first[0]) is None
    results = [assembler.add(f) for f in second]
    assert json.loads(results[-1] or "")["topic"] == "/b"
    assert assembler.pending == 0


def test_fragment_with_a_changed_total_is_dropped() -> None:
    """A part whose total differs from part 0's raises and drops the buffer."""
    parts = fragments({"op": "publish", "topic": "/a", "msg": {"d": "a" * 100}}, 40, "m")
    assembler = FragmentAssembler()
    assembler.add(parts[0])
    bad = dict(parts[1], total=parts[1]["total"] + 1)  # type: ignore[operator]
    with pytest.raises(ProtocolError, match="changed total"):
        assembler.add(bad)
    assert assembler.pending == 0


def test_fragment_out_of_order_is_dropped() -> None:
    """A gap in the numbering drops the message rather than joining it wrongly."""
    parts = fragments({"op": "publish", "topic": "/a", "msg": {"d": "a" * 200}}, 40, "m")
    assembler = FragmentAssembler()
    assembler.add(parts[0])
    with pytest.raises(ProtocolError, match="was due"):
        assembler.add(parts[2])
    assert assembler.pending == 0


def test_fragment_without_part_zero_is_rejected() -> None:
    """A middle part with nothing buffered is reported, not kept."""
    parts = fragments({"op": "publish", "topic": "/a", "msg": {"d": "a" * 200}}, 40, "m")
    with pytest.raises(ProtocolError, match="without part 0"):
        FragmentAssembler().add(parts[1])


@pytest.mark.parametrize(
    "frame",
    [
        {"op": "fragment", "id": "x", "data": 5, "num": 0, "total": 2},
        {"op": "fragment", "id": "x", "data": "a", "num": "0", "total": 2},
        {"op": "fragment", "id": "x", "data": "a", "num": 0, "total": True},
        {"op": "fragment", "data": "a", "num": 0, "total": 2},
        {"op": "fragment", "id": "x", "data": "a", "num": 3, "total": 2},
    ],
)
def test_malformed_fragments_raise_protocol_errors(frame: dict[str, object]) -> None:
    """Fragments with missing or mistyped fields are rejected with a ProtocolError."""
    with pytest.raises(ProtocolError):
        FragmentAssembler().add(frame)


def test_fragment_memory_is_bounded_by_dropping_the_oldest() -> None:
    """Beyond max_buffers partial messages, the oldest partial message is dropped."""
    assembler = FragmentAssembler(max_buffers=3)
    for n in range(10):
        assembler.add({"op": "fragment", "id": f"m{n}", "data": "x", "num": 0, "total": 2})
    assert assembler.pending == 3
    with pytest.raises(ProtocolError):
        assembler.add({"op": "fragment", "id": "m0", "data": "y", "num": 1, "total": 2})
    assert assembler.add({"op": "fragment", "id": "m9", "data": "y", "num": 1, "total": 2}) == "xy"


def test_a_connections_decoder_holds_at_most_32_partial_messages_and_64_mi_characters() -> None:
    """100 MB of fragments that never complete, fed to a connection's decoder with its default bounds."""
    decoder = protocol.InboundDecoder()
    chunk = "x" * 1_000_000
    for n in range(100):
        decoder.feed(json.dumps({"op": "fragment", "id": f"f{n}", "data": chunk, "num": 0, "total": 9}))
    assert decoder.assembler.pending <= 32
    assert 0 < decoder.assembler.held_chars <= 64 * 1024 * 1024


def test_a_fragmented_message_larger_than_the_character_bound_is_dropped() -> None:
    """One message bigger than max_chars is dropped with a ProtocolError."""
    assembler = FragmentAssembler(max_chars=100)
    assembler.add({"op": "fragment", "id": "big", "data": "x" * 60, "num": 0, "total": 3})
    with pytest.raises(ProtocolError, match="exceeds"):
        assembler.add({"op": "fragment", "id": "big", "data": "x" * 60, "num": 1, "total": 3})
    assert assembler.held_chars == 0


def test_stale_fragment_buffers_expire() -> None:
    """A partial message untouched for longer than the ttl is forgotten."""
    now = [100.0]
    assembler = FragmentAssembler(ttl=5.0, clock=lambda: now[0])
    assembler.add({"op": "fragment", "id": "old", "data": "x", "num": 0, "total": 2})
    now[0] += 6.0
    assembler.add({"op": "fragment", "id": "new", "data": "x", "num": 0, "total": 2})
    assert assembler.pending == 1
    with pytest.raises(ProtocolError):
        assembler.add({"op": "fragment", "id": "old", "data": "y", "num": 1, "total": 2})


def test_reassembled_garbage_is_a_notice() -> None:
    """Fragments that join into something that is not a rosbridge op are reported and dropped."""
    decoder = protocol.InboundDecoder()
    decoder.feed('{"op":"fragment","id":"g","data":"{\\"a\\":","num":0,"total":2}')
    event = decoder.feed('{"op":"fragment","id":"g","data":"oops","num":1,"total":2}')
    assert isinstance(event, protocol.Notice)
    assert "not JSON" in event.text


def test_a_binary_cbor_publish_is_routed_with_its_typed_arrays_as_arrays() -> None:
    """A CBOR publish (int8 tag 72, float32 tag 85, uint16 tag 69) becomes a PublishEvent of arrays."""
    msg = {
        "data": cbor2.CBORTag(72, array("b", [-1, 0, 100]).tobytes()),
        "ranges": cbor2.CBORTag(85, array("f", [0.5, 1.25]).tobytes()),
        "ids": cbor2.CBORTag(69, array("H", [1, 65535]).tobytes()),
        "raw": b"\x01\x02",
        "nested": [{"values": cbor2.CBORTag(86, array("d", [1e-9]).tobytes())}],
    }
    event = protocol.InboundDecoder().feed(cbor2.dumps({"op": "publish", "topic": "/x", "msg": msg}))
    assert isinstance(event, protocol.PublishEvent)
    assert event.topic == "/x"
    data = event.msg["data"]
    assert isinstance(data, array)
    assert (data.typecode, data.tolist()) == ("b", [-1, 0, 100])
    assert event.msg["ranges"].tolist() == [0.5, 1.25]
    assert event.msg["ids"].tolist() == [1, 65535]
    assert event.msg["raw"] == b"\x01\x02"
    assert event.msg["nested"][0]["values"].tolist() == [1e-9]


@pytest.mark.parametrize(
    ("item", "expected"),
    [
        (cbor2.CBORTag(99, b"\x00"), "unsupported CBOR tag 99"),
        (cbor2.CBORTag(78, b"\x00\x00\x00"), "not whole items"),
        ([1, 2], "not a CBOR map"),
    ],
)
def test_binary_frames_that_are_not_a_usable_cbor_op_become_notices(item: object, expected: str) -> None:
    """An unknown tag, a typed array cut short, or a CBOR array is reported, never raised."""
    frame = (
        {"op": "publish", "topic": "/x", "msg": {"data": item}} if isinstance(item, cbor2.CBORTag) else item
    )
    event = protocol.InboundDecoder().feed(cbor2.dumps(frame))
    assert isinstance(event, protocol.Notice)
    assert expected in event.text


def test_subscribe_asks_for_cbor_only_when_told() -> None:
    """compression="cbor" adds the key; without it the op stays as before."""
    assert protocol.subscribe("/map", None, id="s", compression="cbor")["compression"] == "cbor"
    assert "compression" not in protocol.subscribe("/map", None, id="s")


def test_an_unpaired_surrogate_in_a_frame_becomes_the_replacement_character() -> None:
    """JSON may carry ``"\\ud800"``, which no text can hold (the MCP SDK's writer refuses it, and the stdio
    server with it): anywhere in a frame, key or value, it is read as U+FFFD; an escaped pair stays the one
    character it spells."""
    text = (
        '{"op":"publish","topic":"/t","msg":{"data":"a\\ud800b","k\\udfff":["\\uDBFF"],'
        '"pair":"\\ud83d\\ude00"}}'
    )
    event = protocol.InboundDecoder().feed(text)
    assert event == protocol.PublishEvent("/t", {"data": "a\ufffdb", "k\ufffd": ["\ufffd"], "pair": "😀"})


def test_an_unpaired_surrogate_in_reassembled_fragments_becomes_the_replacement_character() -> None:
    """The same holds for a message the bridge sent in fragments (its text is decoded once whole)."""
    text = '{"op":"publish","topic":"/t","msg":{"data":"x\\ud800y"}}'
    decoder = protocol.InboundDecoder()
    parts = [
        {"op": "fragment", "id": "f", "data": text[:20], "num": 0, "total": 2},
        {"op": "fragment", "id": "f", "data": text[20:], "num": 1, "total": 2},
    ]
    events = [decoder.feed(json.dumps(part)) for part in parts]
    assert events[-1] == protocol.PublishEvent("/t", {"data": "x\ufffdy"})
