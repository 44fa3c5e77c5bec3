"""Hostile arguments: each refused with a sentence naming the argument and the limit; nothing is sent."""

from __future__ import annotations

import json
from typing import Any

import pytest
from mcp_harness import Session, text_of, types_for

from rosbridge_mcp_server.sim import SimulatedRobot

CHATTER = "/chatter"


async def _still_works(session: Session) -> None:
    """The session and its single rosbridge connection are intact."""
    await session.ok("list_topics")
    assert session.ros.connections_made == 1


async def test_every_input_schema_refuses_unknown_keys(session_ros2: Session) -> None:
    """Each tool's input schema says additionalProperties: false."""
    listed = await session_ros2.mcp.list_tools()
    assert listed.tools
    assert all(tool.input_schema.get("additionalProperties") is False for tool in listed.tools)


async def test_a_misspelt_argument_is_named_and_nothing_is_published(
    session: Session, sim: SimulatedRobot
) -> None:
    """``mesage`` for ``message`` is an error naming it and the likely meant one, not an empty publish."""
    text = await session.error(
        "publish_topic",
        {"topic": CHATTER, "message_type": types_for(sim)["string"], "mesage": {"data": "hi"}},
    )
    assert "unknown argument 'mesage' (did you mean message?)" in text
    assert "It takes: topic, message_type, message (optional)" in text
    assert CHATTER not in sim.world.published
    await _still_works(session)


async def test_a_boolean_is_not_a_number(session: Session, sim: SimulatedRobot) -> None:
    """``timeout: true`` is refused, naming the argument, instead of being taken as 1 s."""
    text = await session.error(
        "publish_service",
        {"service": "/add_two_ints", "service_type": types_for(sim)["add_two_ints"], "timeout": True},
    )
    assert "timeout: expected a number, got true (a boolean is not a number)" in text


@pytest.mark.parametrize("name", ["/tür", "../..", "/robot/🤖", "/a b", "~/private", "/a-b", "/x.y"])
async def test_a_name_outside_the_ros_rules_is_refused_and_nothing_is_published(
    session: Session, sim: SimulatedRobot, name: str
) -> None:
    """Names with characters ROS does not allow are errors, not "published" messages the bridge drops."""
    text = await session.error(
        "publish_topic", {"topic": name, "message_type": types_for(sim)["string"], "message": {"data": "x"}}
    )
    assert "The topic name" in text
    assert not sim.world.published


async def test_a_name_part_led_by_a_digit_is_refused_by_ros2_only(
    sim_ros2: SimulatedRobot, session_ros2: Session, sim_ros1: SimulatedRobot, session_ros1: Session
) -> None:
    """``/camera/2d`` is a valid ROS 1 name and an invalid ROS 2 one."""
    ros2 = await session_ros2.error(
        "publish_topic", {"topic": "/camera/2d", "message_type": "std_msgs/msg/String", "message": {}}
    )
    assert "starting with a digit ('2d')" in ros2
    await session_ros1.ok("publish_topic", {"topic": "/camera/2d", "message_type": "std_msgs/String"})
    await sim_ros1.world.wait_for(lambda w: "/camera/2d" in w.published)


@pytest.mark.parametrize(
    ("label", "name"), [("6 MB name", "/" + "a" * 6_000_000), ("1 MB of NUL", "\0" * 1_000_000)]
)
async def test_a_huge_topic_name_costs_neither_the_session_nor_the_connection(
    session: Session, sim: SimulatedRobot, label: str, name: str
) -> None:
    """Refused before anything is sent, naming the argument and the limit; the connection is never dropped."""
    text = await session.error(
        "publish_topic", {"topic": name, "message_type": types_for(sim)["string"], "message": {"data": "x"}}
    )
    assert "topic:" in text
    assert "more than the 1000 this argument may have" in text, label
    await _still_works(session)


async def test_a_name_just_over_the_ros_limit_is_refused(session: Session, sim: SimulatedRobot) -> None:
    """A 300-character name passes the argument limit and fails ROS's 247-character rule."""
    text = await session.error(
        "publish_topic", {"topic": "/" + "a" * 300, "message_type": types_for(sim)["string"], "message": {}}
    )
    assert "more than the 247 a ROS name can have" in text


async def test_a_message_over_the_bridge_frame_limit_is_refused_not_reported_as_published(
    session: Session, sim: SimulatedRobot
) -> None:
    """A 12 MB message: an error naming the 10 MiB limit, never "Published ..."; the connection stays."""
    text = await session.error(
        "publish_topic",
        {"topic": CHATTER, "message_type": types_for(sim)["string"], "message": {"data": "x" * 12_000_000}},
    )
    assert "message: is larger than 10 MiB" in text
    assert CHATTER not in sim.world.published
    await _still_works(session)


async def test_a_message_under_the_character_limit_but_over_the_byte_limit_is_refused_by_the_client(
    session: Session, sim: SimulatedRobot
) -> None:
    """4 M euro signs are 12 MB of UTF-8: the frame check before sending refuses it; nothing is published."""
    text = await session.error(
        "publish_topic",
        {"topic": CHATTER, "message_type": types_for(sim)["string"], "message": {"data": "€" * 4_000_000}},
    )
    assert "frame would be 12.0 MB, more than the 10 MiB" in text
    assert "nothing was sent" in text
    assert CHATTER not in sim.world.published
    await _still_works(session)


async def test_a_message_nested_too_deep_is_refused_naming_the_limit(
    session: Session, sim: SimulatedRobot
) -> None:
    """An object nested 100 levels deep, or JSON text nested 5,000 deep, is refused at 64 levels."""
    deep: dict[str, object] = {}
    for _ in range(100):
        deep = {"a": deep}
    as_object = await session.error(
        "publish_topic", {"topic": CHATTER, "message_type": types_for(sim)["string"], "message": deep}
    )
    assert "message: nests deeper than 64 levels" in as_object
    as_text = await session.error(
        "publish_service",
        {
            "service": "/add_two_ints",
            "service_type": types_for(sim)["add_two_ints"],
            "request": "[" * 5000 + "]" * 5000,
        },
    )
    assert "nests deeper than 64 levels" in as_text
    await _still_works(session)


async def test_a_lone_surrogate_in_json_text_is_refused(session: Session, sim: SimulatedRobot) -> None:
    """``"\\ud800"`` in a message given as JSON text cannot be encoded: an error, not a crash."""
    text = await session.error(
        "publish_topic",
        {
            "topic": CHATTER,
            "message_type": types_for(sim)["string"],
            "message": json.dumps({"data": "\ud800"}, ensure_ascii=True),
        },
    )
    assert "unpaired UTF-16 surrogate (\\ud800)" in text
    await _still_works(session)


async def test_two_wrong_arguments_one_of_them_json_text_are_both_named(
    session: Session, sim: SimulatedRobot
) -> None:
    """``"request": "null"`` (JSON text the SDK reads as null) and a bad timeout: our sentence naming both,
    not the SDK's "2 validation errors"; nothing is called."""
    text = await session.error(
        "publish_service",
        {
            "service": "/add_two_ints",
            "service_type": types_for(sim)["add_two_ints"],
            "request": "null",
            "timeout": -1,
        },
    )
    assert text.startswith(
        "Invalid arguments for publish_service: request: expected a JSON object; the text 'null' holds null "
        '(it takes: Request fields as a JSON object, e.g. {"a": 2, "b": 3}; {} for std_srvs/srv/Trigger);'
    )
    assert "timeout: input should be greater than 0 (got -1)" in text
    assert "validation error" not in text
    assert "/add_two_ints" not in sim.world.service_calls
    await _still_works(session)


@pytest.mark.parametrize("text", ["null", "true", "[1, 2]", "{}"])
async def test_json_text_for_any_parameter_that_is_not_text_is_worded(
    session_ros2: Session, text: str
) -> None:
    """For every tool, every parameter that is not plain text given JSON text: each error is our sentence
    (or the tool's own), never the SDK's raw validation error."""
    listed = await session_ros2.mcp.list_tools()
    tried = 0
    for tool in listed.tools:
        properties: dict[str, Any] = tool.input_schema.get("properties", {})
        required = tool.input_schema.get("required", [])
        for key, prop in properties.items():
            if prop.get("type") == "string" and "enum" not in prop:
                continue
            arguments = {name: "/chatter" for name in required if name != key} | {key: text}
            result = await session_ros2.call(tool.name, arguments)
            tried += 1
            if result.is_error:
                said = text_of(result)
                assert "validation error" not in said, f"{tool.name}.{key}: {said[:200]}"
                assert "Error executing tool" not in said, f"{tool.name}.{key}: {said[:200]}"
    assert tried > 20
    await _still_works(session_ros2)


async def test_a_misspelt_setting_inside_an_object_argument_is_named(session_ros2: Session) -> None:
    """``qos: {"depht": 5}`` is refused naming the key and the likely meant one, not silently dropped (the
    subscription would have had the default depth); ``depth: "5"`` is no number."""
    misspelt = await session_ros2.error(
        "subscribe_topic", {"topic": CHATTER, "timeout": 1, "qos": {"depht": 5}}
    )
    assert "qos: unknown key 'depht' (did you mean depth?)" in misspelt
    as_text = await session_ros2.error(
        "subscribe_topic", {"topic": CHATTER, "timeout": 1, "qos": {"depth": "5"}}
    )
    assert "qos.depth: expected an integer (got '5')" in as_text
    await _still_works(session_ros2)


async def test_a_number_given_as_text_is_refused_naming_it(session: Session, sim: SimulatedRobot) -> None:
    """``"timeout": "30"`` is refused (strict types: a JSON client sends numbers as numbers), not taken as
    30 s."""
    text = await session.error(
        "publish_service",
        {"service": "/add_two_ints", "service_type": types_for(sim)["add_two_ints"], "timeout": "30"},
    )
    assert "timeout: expected a number (got '30')" in text
    assert "/add_two_ints" not in sim.world.service_calls
