"""subscribe_topic through an MCP session on the simulated robot, in both dialects."""

from __future__ import annotations

import asyncio

import pytest
from mcp_harness import Session, text_of

from rosbridge_mcp_server.sim import SimulatedRobot


async def test_one_message_is_read_from_a_topic(session: Session) -> None:
    """By default one /chatter message comes back, with its receive time."""
    result = await session.ok("subscribe_topic", {"topic": "/chatter"})
    data = result.structured_content
    assert data is not None
    assert data["topic"] == "/chatter"
    assert len(data["messages"]) == 1
    assert data["messages"][0]["message"]["data"].startswith("Hello World: ")
    assert "1 message on /chatter" in text_of(result)


async def test_several_messages_report_the_observed_rate(session: Session) -> None:
    """Three /chatter messages (10 Hz) come in order, with a rate near 10 Hz and progress reported."""
    result = await session.ok("subscribe_topic", {"topic": "chatter", "count": 3})
    data = result.structured_content
    assert data is not None
    numbers = [int(m["message"]["data"].rsplit(" ", 1)[1]) for m in data["messages"]]
    assert numbers == sorted(numbers)
    assert len(numbers) == 3
    assert 5 < data["rate_hz"] < 20
    assert [p[0] for p in session.progress] == [1, 2, 3]


async def test_a_duration_collects_for_that_long(session: Session) -> None:
    """duration 0.5 s on a 10 Hz topic collects about five messages, all within the window."""
    result = await session.ok("subscribe_topic", {"topic": "/chatter", "duration": 0.5})
    data = result.structured_content
    assert data is not None
    assert 3 <= len(data["messages"]) <= 7
    assert all(m["received"] <= 1.5 for m in data["messages"])


async def test_a_duration_ends_its_progress_at_its_total(session: Session) -> None:
    """duration 0.5 s collects ~5 of up to 100 messages: the last progress says done (progress == total), so a
    host's bar ends full, not at 5 %."""
    result = await session.ok("subscribe_topic", {"topic": "/chatter", "duration": 0.5})
    data = result.structured_content
    assert data is not None
    progress, total, message = session.progress[-1]
    assert progress == total, session.progress
    assert message is not None
    assert f"{len(data['messages'])} messages" in message
    assert [p for p, _, _ in session.progress] == sorted(p for p, _, _ in session.progress)


async def test_fields_keep_only_the_paths_asked_for(session: Session) -> None:
    """fields ["x"] on the turtle's pose returns only x."""
    result = await session.ok("subscribe_topic", {"topic": "/turtle1/pose", "fields": ["x"]})
    data = result.structured_content
    assert data is not None
    assert list(data["messages"][0]["message"]) == ["x"]


async def test_a_camera_frame_is_summarised_not_dumped(session: Session) -> None:
    """An Image message's pixel bytes are replaced by their count, and the cut is reported."""
    result = await session.ok("subscribe_topic", {"topic": "/camera/image_raw"})
    data = result.structured_content
    assert data is not None
    message = data["messages"][0]
    assert message["message"]["data"] == {"bytes": 160 * 120 * 3}
    assert message["cut"] == [f"data: {160 * 120 * 3} bytes omitted"]
    assert len(text_of(result)) < 700


async def test_a_latched_topic_answers_at_once(session: Session) -> None:
    """/client_count is latched (transient local on ROS 2): its last value arrives without waiting."""
    result = await session.ok("subscribe_topic", {"topic": "/client_count", "timeout": 1})
    data = result.structured_content
    assert data is not None
    assert data["messages"][0]["message"]["data"] >= 1


async def test_a_silent_topic_ends_at_its_timeout(session: Session, sim: SimulatedRobot) -> None:
    """A topic nobody publishes (given a type) ends after the timeout with a clear answer and no messages."""
    msg_type = "std_msgs/msg/String" if sim.dialect == "ros2" else "std_msgs/String"
    result = await session.ok(
        "subscribe_topic", {"topic": "/nobody_talks", "message_type": msg_type, "timeout": 0.3}
    )
    data = result.structured_content
    assert data is not None
    assert data["timed_out"] is True
    assert data["messages"] == []
    assert "No message on /nobody_talks" in text_of(result)


async def test_an_unknown_topic_is_an_error_naming_it(session: Session) -> None:
    """A misspelt topic is an error naming it, suggesting the close one."""
    text = await session.error("subscribe_topic", {"topic": "/chatterr"})
    assert "Topic /chatterr is not in the ROS graph" in text
    assert "Did you mean /chatter?" in text


async def test_an_unknown_field_is_an_error_before_subscribing(session: Session) -> None:
    """A field the type does not have is named with the fields it does have, and nothing is subscribed."""
    text = await session.error("subscribe_topic", {"topic": "/turtle1/pose", "fields": ["pose.x"]})
    assert "there is no 'pose'" in text
    assert "x, y, theta" in text
    assert "Nothing was subscribed" in text


async def test_a_type_that_disagrees_with_the_graph_is_an_error(
    session: Session, sim: SimulatedRobot
) -> None:
    """Asking for /chatter as a Twist is refused before subscribing."""
    msg_type = "geometry_msgs/msg/Twist" if sim.dialect == "ros2" else "geometry_msgs/Twist"
    text = await session.error("subscribe_topic", {"topic": "/chatter", "message_type": msg_type})
    assert "has type" in text
    assert "not " in text


@pytest.mark.parametrize(
    "arguments", [{"topic": "/chatter", "count": 0}, {"topic": "/chatter", "count": 101}]
)
async def test_a_count_out_of_range_is_an_argument_error(
    session: Session, arguments: dict[str, object]
) -> None:
    """count must be 1 to 100."""
    text = await session.error("subscribe_topic", arguments)
    assert "count" in text


async def test_qos_is_noted_per_dialect(session: Session, sim: SimulatedRobot) -> None:
    """A qos request says it is not applied on ROS 1 and which bridges apply it on ROS 2."""
    result = await session.ok(
        "subscribe_topic", {"topic": "/chatter", "qos": {"reliability": "reliable", "depth": 5}}
    )
    note = (result.structured_content or {})["qos_note"]
    if sim.dialect == "ros1":
        assert note.startswith("QoS not applied: ROS 1")
    else:
        assert "2.7.0 (Jazzy)" in note


async def test_a_laser_scan_stays_a_few_hundred_tokens(session: Session) -> None:
    """/scan's 360 ranges are summarised with min/max/mean and the missing readings counted."""
    result = await session.ok("subscribe_topic", {"topic": "/scan"})
    data = result.structured_content
    assert data is not None
    message = data["messages"][0]
    ranges = message["message"]["ranges"]
    assert ranges["length"] == 360
    assert 0 < ranges["min"] <= ranges["mean"] <= ranges["max"]
    assert ranges["not_finite"] >= 5
    assert "ranges: 360 numbers summarised" in message["cut"]
    assert len(text_of(result)) < 1500


async def test_the_subscription_is_gone_afterwards(session: Session) -> None:
    """Once subscribe_topic answers, the bridge no longer subscribes /chatter for us."""
    await session.ok("subscribe_topic", {"topic": "/chatter", "count": 2})
    info = await session.ok("get_topic_info", {"topic": "/chatter"})
    assert "/rosbridge_websocket" not in (info.structured_content or {})["subscribers"]


async def test_while_listening_the_bridge_subscribes_for_us(session: Session) -> None:
    """During a duration listen the bridge's node subscribes /chatter (so the check above can fail)."""
    listening = asyncio.create_task(session.call("subscribe_topic", {"topic": "/chatter", "duration": 1.5}))
    # Each /chatter message is a moment to look again; progress says the listen has heard one.
    for _ in range(20):
        if session.progress:
            break
        async with session.ros.subscribe("/chatter", max_queue=1) as chatter:
            await chatter.get(5.0)
    assert session.progress
    info = await session.ok("get_topic_info", {"topic": "/chatter"})
    await listening
    assert "/rosbridge_websocket" in (info.structured_content or {})["subscribers"]
