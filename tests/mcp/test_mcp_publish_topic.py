"""publish_topic: checked against the type, published once, and never delivered late."""

from __future__ import annotations

import json

from mcp_harness import Session, text_of, types_for

from rosbridge_mcp_server.sim import SimulatedRobot

CMD_VEL = "/turtle1/cmd_vel"


async def test_a_twist_reaches_the_robot_and_the_turtle_moves(session: Session, sim: SimulatedRobot) -> None:
    """The message arrives on /turtle1/cmd_vel as sent and the simulated turtle starts moving."""
    twist = {"linear": {"x": 0.5}, "angular": {"z": 0.3}}
    result = await session.ok(
        "publish_topic", {"topic": CMD_VEL, "message_type": types_for(sim)["twist"], "message": twist}
    )
    assert result.structured_content == {
        "topic": CMD_VEL,
        "message_type": types_for(sim)["twist"],
        "message": twist,
        "published": True,
        "count": 1,
        "rate_hz": None,
        "duration": None,
        "zero_sent": False,
        "ended_by_stop": False,
        "adjusted": None,
        "subscribers": 1,
    }
    await sim.world.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) == 1)
    received = sim.world.published[CMD_VEL][0].msg
    assert received["linear"]["x"] == 0.5
    assert received["angular"]["z"] == 0.3
    await sim.world.wait_for(lambda w: w.turtle.commands >= 1)


async def test_both_type_spellings_and_a_json_string_message_are_accepted(
    sim_ros2: SimulatedRobot, session_ros2: Session
) -> None:
    """pkg/Type works on ROS 2, and a message sent as JSON text is parsed."""
    await session_ros2.ok(
        "publish_topic",
        {
            "topic": CMD_VEL,
            "message_type": "geometry_msgs/Twist",
            "message": json.dumps({"linear": {"x": 1.0}}),
        },
    )
    await sim_ros2.world.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) == 1)
    assert sim_ros2.world.published[CMD_VEL][0].msg["linear"]["x"] == 1.0


async def test_a_message_that_does_not_fit_names_each_wrong_field_and_is_not_sent(
    session: Session, sim: SimulatedRobot
) -> None:
    """A string for a float and a misspelt field are both named, with the valid fields; nothing is sent."""
    text = await session.error(
        "publish_topic",
        {
            "topic": CMD_VEL,
            "message_type": types_for(sim)["twist"],
            "message": {"linear": {"x": "fast"}, "angulr": {"z": 1}},
        },
    )
    assert 'linear.x: expected a number (float64), got "fast"' in text
    assert "angulr: no such field" in text
    assert "did you mean angular?" in text
    assert "its fields are linear, angular" in text
    assert "Nothing was published" in text
    assert '{"linear": {"x": 0.0, "y": 0.0, "z": 0.0}' in text
    await session.ok("list_topics")  # a round trip later, still nothing arrived
    assert CMD_VEL not in sim.world.published


async def test_an_unknown_message_type_is_an_error_naming_it(session: Session) -> None:
    """A type the bridge does not know is reported as such."""
    text = await session.error(
        "publish_topic", {"topic": "/new_topic", "message_type": "geometry_msgs/Twistt", "message": {}}
    )
    assert "rosbridge does not know the type 'geometry_msgs/Twistt'" in text


async def test_a_malformed_type_name_is_explained(session: Session) -> None:
    """A type name without a package says what a type name looks like."""
    text = await session.error("publish_topic", {"topic": "/x", "message_type": "Twist", "message": {}})
    assert "pkg/Type" in text


async def test_a_type_that_conflicts_with_the_topic_is_refused(session: Session, sim: SimulatedRobot) -> None:
    """Publishing a String on the Twist topic is an error naming the topic's real type."""
    text = await session.error(
        "publish_topic",
        {"topic": CMD_VEL, "message_type": types_for(sim)["string"], "message": {"data": "hi"}},
    )
    assert f"Topic {CMD_VEL} has type {types_for(sim)['twist']}" in text
    assert CMD_VEL not in sim.world.published


async def test_an_empty_message_and_a_new_topic_are_fine(session: Session, sim: SimulatedRobot) -> None:
    """{} is a valid std_msgs String; a topic nobody uses yet is created by the publish."""
    await session.ok(
        "publish_topic", {"topic": "/notes", "message_type": types_for(sim)["string"], "message": {}}
    )
    await sim.world.wait_for(lambda w: len(w.published.get("/notes", ())) == 1)
    await session.ok("publish_topic", {"topic": "/notes", "message_type": types_for(sim)["string"]})
    await sim.world.wait_for(lambda w: len(w.published.get("/notes", ())) == 2)
    assert [message.msg for message in sim.world.published["/notes"]] == [{"data": ""}] * 2


async def test_a_message_that_is_not_json_is_an_error_with_an_example(
    session: Session, sim: SimulatedRobot
) -> None:
    """Broken JSON text is reported with the parser's complaint and an example."""
    text = await session.error(
        "publish_topic", {"topic": CMD_VEL, "message_type": types_for(sim)["twist"], "message": "{linear: 1"}
    )
    broken = "message: is not valid JSON (Expecting property name enclosed in double quotes at character 1)"
    assert broken in text
    assert '(it takes: JSON object, e.g. {"linear": {"x": 0.5}' in text


async def test_a_ros2_style_type_name_works_on_a_ros1_bridge(
    sim_ros1: SimulatedRobot, session_ros1: Session
) -> None:
    """geometry_msgs/msg/Twist is sent to ROS 1 as geometry_msgs/Twist (0.11 rejects three-part names)."""
    result = await session_ros1.ok(
        "publish_topic",
        {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "message": {"angular": {"z": -0.5}}},
    )
    assert result.structured_content is not None
    assert result.structured_content["message_type"] == "geometry_msgs/Twist"
    await sim_ros1.world.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) == 1)
    assert sim_ros1.world.published[CMD_VEL][0].msg["angular"]["z"] == -0.5


async def test_a_topic_we_publish_keeps_its_type(session: Session, sim: SimulatedRobot) -> None:
    """After publishing a String on /notes, a Twist there is refused, and Strings still go through."""
    strings = {"topic": "/notes", "message_type": types_for(sim)["string"], "message": {"data": "a"}}
    await session.ok("publish_topic", strings)
    text = await session.error(
        "publish_topic", {"topic": "/notes", "message_type": types_for(sim)["twist"], "message": {}}
    )
    assert f"Topic /notes has type {types_for(sim)['string']}" in text
    await session.ok("publish_topic", {**strings, "message": {"data": "b"}})
    await sim.world.wait_for(lambda w: len(w.published.get("/notes", ())) == 2)
    assert [m.msg["data"] for m in sim.world.published["/notes"]] == ["a", "b"]


async def test_a_float32_beyond_its_range_is_refused_and_not_sent(
    session: Session, sim: SimulatedRobot
) -> None:
    """1e40 in a Float32 is refused, naming the field; a real bridge would drop it (struct.pack overflows)."""
    float32 = "std_msgs/Float32" if sim.dialect == "ros1" else "std_msgs/msg/Float32"
    text = await session.error(
        "publish_topic", {"topic": "/mcp_test/f32", "message_type": float32, "message": {"data": 1e40}}
    )
    assert "data: 1e+40 is out of range for float32" in text
    assert "Nothing was published" in text
    assert "/mcp_test/f32" not in sim.world.published


async def test_a_negative_ros1_time_is_refused_and_a_negative_duration_is_sent(
    sim_ros1: SimulatedRobot, session_ros1: Session
) -> None:
    """ROS 1 packs a time as uint32s (rosbridge 0.11.17 drops a negative one), a duration as int32s."""
    text = await session_ros1.error(
        "publish_topic",
        {"topic": "/mcp_test/time", "message_type": "std_msgs/Time", "message": {"data": {"secs": -1}}},
    )
    assert "data.secs: -1 is out of range for uint32 in time" in text
    await session_ros1.ok(
        "publish_topic",
        {
            "topic": "/mcp_test/duration",
            "message_type": "std_msgs/Duration",
            "message": {"data": {"secs": -1}},
        },
    )
    await sim_ros1.world.wait_for(lambda w: len(w.published.get("/mcp_test/duration", ())) == 1)
    assert "/mcp_test/time" not in sim_ros1.world.published


async def test_a_ros1_time_written_sec_nanosec_is_checked_and_arrives_as_secs_nsecs(
    sim_ros1: SimulatedRobot, session_ros1: Session
) -> None:
    """The check reads the time as ROS 1 will (a negative sec is out of range); the client respells it."""
    text = await session_ros1.error(
        "publish_topic",
        {"topic": "/mcp_test/time", "message_type": "std_msgs/Time", "message": {"data": {"sec": -1}}},
    )
    assert "data.secs: -1 is out of range for uint32 in time" in text
    stamp = {"sec": 5, "nanosec": 6}
    result = await session_ros1.ok(
        "publish_topic",
        {"topic": "/mcp_test/time", "message_type": "std_msgs/Time", "message": {"data": stamp}},
    )
    assert result.structured_content is not None
    assert result.structured_content["message"] == {"data": stamp}, "the answer shows the message as given"
    await sim_ros1.world.wait_for(lambda w: len(w.published.get("/mcp_test/time", ())) == 1)
    assert sim_ros1.world.published["/mcp_test/time"][0].msg == {"data": {"secs": 5, "nsecs": 6}}


async def test_a_message_nobody_subscribes_to_is_sent_and_said_to_have_reached_nobody(
    session: Session, sim: SimulatedRobot
) -> None:
    """A misspelt velocity topic: the message is published as asked, but the answer says no node subscribes,
    so nothing received it, and names the topic meant; not an error, and never "the robot moved"."""
    twist = {"linear": {"x": 0.5}}
    arguments = {"topic": "/turtle1/cmd_vell", "message_type": types_for(sim)["twist"], "message": twist}
    result = await session.ok("publish_topic", arguments)
    text = text_of(result)
    assert '{"linear": {"x": 0.5}}. But nothing subscribes to /turtle1/cmd_vell' in text, text
    assert "no node received it" in text, text
    assert "Did you mean /turtle1/cmd_vel?" in text, text
    assert result.structured_content is not None
    assert result.structured_content["published"] is True
    assert result.structured_content["subscribers"] == 0
    await sim.world.wait_for(lambda w: len(w.published.get("/turtle1/cmd_vell", ())) == 1)
    assert sim.world.turtle.commands == 0


async def test_a_stream_nobody_subscribes_to_says_so_too(session: Session, sim: SimulatedRobot) -> None:
    """A short stream on the misspelt topic: every message sent, and the answer says nobody received them."""
    result = await session.ok(
        "publish_topic",
        {
            "topic": "/turtle1/cmd_vell",
            "message_type": types_for(sim)["twist"],
            "message": {"angular": {"z": 0.2}},
            "rate_hz": 20,
            "duration": 0.2,
        },
    )
    text = text_of(result)
    assert "nothing subscribes to /turtle1/cmd_vell" in text, text
    assert "Did you mean /turtle1/cmd_vel?" in text, text
    assert result.structured_content is not None
    assert result.structured_content["subscribers"] == 0


async def test_a_message_a_node_subscribes_to_is_plain_success(session: Session, sim: SimulatedRobot) -> None:
    """On the topic the turtle reads, the answer counts its subscribers and says nothing of nobody."""
    result = await session.ok(
        "publish_topic", {"topic": CMD_VEL, "message_type": types_for(sim)["twist"], "message": {}}
    )
    text = text_of(result)
    assert "subscribes" not in text, text
    assert result.structured_content is not None
    assert result.structured_content["subscribers"] >= 1
