"""The conversation on one connection, sans I/O: frames in, events out, deadlines as data; no loop."""

from __future__ import annotations

import json
from typing import Any

import cbor2

from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.conversation import Conversation, Refused, Routed, Unawaited


def text(frame: dict[str, Any]) -> str:
    return json.dumps(frame)


def test_a_reply_goes_to_the_handle_waiting_on_its_id() -> None:
    """The table routes by id: the reply's frame comes back with the caller's own handle."""
    talk: Conversation[str] = Conversation()
    talk.wait("call_service:/a:1", "first", deadline=10.0)
    talk.wait("call_service:/b:2", "second", deadline=10.0)
    event = talk.receive(text({"op": "service_response", "id": "call_service:/b:2", "result": True}))
    assert event == Routed(
        "second", "service_response", {"op": "service_response", "id": "call_service:/b:2", "result": True}
    )


def test_a_reply_nobody_waits_on_is_unawaited_and_a_refusal_is_kept_with_its_text() -> None:
    """A late reply is named (op and id); an error status for an unknown id carries the bridge's words."""
    talk: Conversation[str] = Conversation()
    late = talk.receive(text({"op": "service_response", "id": "gone", "result": True}))
    refused = talk.receive(
        text({"op": "status", "level": "error", "id": "subscribe:/x:3", "msg": "no such type"})
    )
    assert late == Unawaited("service_response", "gone")
    assert refused == Refused("subscribe:/x:3", "no such type")


def test_publishes_and_notices_pass_through_as_the_decoder_says() -> None:
    """A message on a topic is a PublishEvent; a frame that is not JSON is a warning, not an exception."""
    talk: Conversation[str] = Conversation()
    published = talk.receive(text({"op": "publish", "topic": "/chatter", "msg": {"data": "hi"}}))
    broken = talk.receive("{not json")
    assert published == protocol.PublishEvent("/chatter", {"data": "hi"})
    assert isinstance(broken, protocol.Notice)
    assert broken.level == "warning"


def test_a_cbor_reply_is_routed_like_a_json_one() -> None:
    """A binary frame holding a reply reaches its waiter too."""
    talk: Conversation[str] = Conversation()
    talk.wait("r1", "waiter", deadline=1.0)
    event = talk.receive(cbor2.dumps({"op": "service_response", "id": "r1", "result": True, "values": {}}))
    assert isinstance(event, Routed)
    assert event.handle == "waiter"


def test_a_reply_in_fragments_is_routed_once_whole() -> None:
    """Fragments are buffered (a debug notice each) and the reassembled reply goes to its waiter."""
    talk: Conversation[str] = Conversation()
    talk.wait("r1", "waiter", deadline=1.0)
    whole = text({"op": "service_response", "id": "r1", "result": True, "values": {"x": 1}})
    parts = [whole[i : i + 10] for i in range(0, len(whole), 10)]
    events = [
        talk.receive(text({"op": "fragment", "id": "r1", "data": part, "num": n, "total": len(parts)}))
        for n, part in enumerate(parts)
    ]
    assert all(isinstance(e, protocol.Notice) and e.level == "debug" for e in events[:-1])
    assert events[-1] == Routed("waiter", "service_response", json.loads(whole))


def test_only_the_earliest_deadline_arms_the_timer() -> None:
    """wait() says when to (re)arm the one timer: for a new earliest deadline only."""
    talk: Conversation[str] = Conversation()
    assert talk.wait("a", "a", deadline=5.0) == 5.0
    assert talk.wait("b", "b", deadline=9.0) is None
    assert talk.wait("c", "c", deadline=2.0) == 2.0


def test_due_expires_each_passed_deadline_once_and_names_the_next() -> None:
    """At the timer's time the passed deadlines come out once; the rest set the next timer."""
    talk: Conversation[str] = Conversation()
    for rid, deadline in (("a", 1.0), ("b", 2.0), ("c", 3.0)):
        talk.wait(rid, rid, deadline)
    assert talk.due(2.0) == (["a", "b"], 3.0)
    # Expired requests stay in the table until their caller forgets them, but never expire twice.
    assert set(talk.pending) == {"a", "b", "c"}
    assert talk.due(2.5) == ([], 3.0)
    assert talk.due(3.0) == (["c"], None)


def test_a_forgotten_request_never_comes_due() -> None:
    """forget() takes the id and its deadline out: a timer firing later finds nothing."""
    talk: Conversation[str] = Conversation()
    talk.wait("a", "a", deadline=1.0)
    assert talk.forget("a") == "a"
    assert talk.forget("a") is None
    assert talk.due(5.0) == ([], None)
    assert talk.receive(text({"op": "service_response", "id": "a"})) == Unawaited("service_response", "a")


def test_a_stream_without_a_deadline_gets_every_frame_and_never_expires() -> None:
    """A goal's stream listens on its id: feedback and result reach it, time never does, until forgotten."""
    talk: Conversation[str] = Conversation()
    talk.listen("goal:/fib:t-1", "stream")
    talk.wait("r", "reply", deadline=1.0)
    feedback = talk.receive(text({"op": "action_feedback", "id": "goal:/fib:t-1", "values": {}}))
    result = talk.receive(text({"op": "action_result", "id": "goal:/fib:t-1", "values": {}, "result": True}))
    assert isinstance(feedback, Routed)
    assert isinstance(result, Routed)
    assert (feedback.handle, feedback.op, result.op) == ("stream", "action_feedback", "action_result")
    assert talk.due(100.0) == (["reply"], None)
    assert talk.forget("goal:/fib:t-1") == "stream"
    assert isinstance(talk.receive(text({"op": "action_result", "id": "goal:/fib:t-1"})), Unawaited)


def test_a_call_of_a_hosted_service_goes_to_its_handle_and_others_do_not() -> None:
    """The bridge's call_service for a service this connection offers is routed by the service's name."""
    talk: Conversation[str] = Conversation()
    talk.host("/probe", "calls")
    ours = talk.receive(text({"op": "call_service", "id": "x", "service": "/probe"}))
    other = talk.receive(text({"op": "call_service", "id": "y", "service": "/other"}))
    assert ours == Routed("calls", "call_service", {"op": "call_service", "id": "x", "service": "/probe"})
    assert isinstance(other, protocol.Notice)


def test_losing_the_connection_hands_back_every_handle_and_empties_the_table() -> None:
    """Replies, streams and hosted services all come back once; nothing is due afterwards."""
    talk: Conversation[str] = Conversation()
    talk.wait("a", "reply", deadline=1.0)
    talk.listen("g", "stream")
    talk.host("/probe", "calls")
    assert sorted(talk.lose_all()) == ["calls", "reply", "stream"]
    assert talk.pending == {}
    assert talk.lose_all() == []
    assert talk.due(10.0) == ([], None)


def test_the_outbound_frame_is_the_op_as_json_text() -> None:
    """What the conversation hands out to send is the op's text, read back the same."""
    op = protocol.call_service("/add", {"a": 1}, id="call_service:/add:1")
    assert json.loads(Conversation.outbound(op)) == op
