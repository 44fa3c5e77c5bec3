"""What to try after an error: robot/ says what went wrong and carries a typed hint; the MCP edge
(server/advice.py) words it, naming the tools. The model reads the same sentences as when robot/ wrote
them."""

from __future__ import annotations

from pathlib import Path

import pytest
from mcp_harness import Session, types_for

from rosbridge_mcp_server.errors import Advice, Hint, NotSentError
from rosbridge_mcp_server.server.advice import WORDS, advised
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.tools.base import ToolFailure


def test_every_advice_has_its_words() -> None:
    """A new Advice without words would fail at the edge with a KeyError; every member is worded."""
    assert set(WORDS) == set(Advice)


def test_the_advice_follows_the_text_and_a_tools_tail_follows_the_advice() -> None:
    """The error's text, then the advice with its names, then what the tool said after the text."""
    error = NotSentError("Topic /a has type X, not Y; rosbridge would drop the message.").advise(
        Advice.TOPIC_TYPE, "X"
    )
    assert advised(error) == (
        "Topic /a has type X, not Y; rosbridge would drop the message. Publish a X message, or choose "
        "another topic (list_topics shows each topic's type)."
    )
    failure = ToolFailure.carrying(error, " Nothing was sent.")
    assert failure.hint == Hint(Advice.TOPIC_TYPE, ("X",), " Nothing was sent.")
    assert advised(failure).endswith("(list_topics shows each topic's type). Nothing was sent.")
    plain = ToolFailure.carrying(NotSentError("No."), " Nothing was sent.")
    assert (plain.hint, advised(plain)) == (None, "No. Nothing was sent.")


async def test_a_topic_of_another_type_names_the_type_and_list_topics(
    session: Session, sim: SimulatedRobot
) -> None:
    types = types_for(sim)
    text = await session.error(
        "publish_topic",
        {"topic": "/turtle1/cmd_vel", "message_type": types["string"], "message": {"data": "x"}},
    )
    assert (
        f"Topic /turtle1/cmd_vel has type {types['twist']}, not {types['string']}; rosbridge would drop the "
        f"message. Publish a {types['twist']} message, or choose another topic (list_topics shows each "
        "topic's type)."
    ) in text


async def test_an_unknown_service_and_action_point_at_their_lists(
    session: Session, sim: SimulatedRobot
) -> None:
    types = types_for(sim)
    text = await session.error(
        "publish_service", {"service": "/no_such_service", "service_type": types["trigger"], "request": {}}
    )
    assert text.startswith("Service /no_such_service is not offered by any node.")
    assert "Call list_services to see the services." in text
    text = await session.error(
        "publish_action", {"action_name": "/no_such_action", "action_type": types["fibonacci"], "goal": {}}
    )
    assert text.startswith("No action server /no_such_action is running on the robot.")
    assert "Call list_actions to see the actions." in text
    text = await session.error("cancel_action", {"action_name": "/no_such_action"})
    assert text.startswith(
        "No action server /no_such_action is running on the robot, so there is nothing to cancel."
    )
    assert "Call list_actions to see the actions." in text


async def test_an_unknown_topic_points_at_list_topics_and_message_type(session: Session) -> None:
    text = await session.error("subscribe_topic", {"topic": "/no_such_topic", "timeout": 1})
    assert text.endswith(
        " Call list_topics to see the topics, or give message_type to wait for a publisher that has not "
        "started yet."
    )


async def test_names_ros_2_refuses_point_at_the_lists(session_ros2: Session) -> None:
    text = await session_ros2.error(
        "publish_topic", {"topic": "/camera/2d", "message_type": "std_msgs/msg/String", "message": {}}
    )
    assert (
        "which ROS 2 names do not allow. Check the name with list_topics / list_services / list_actions."
        in (text)
    )
    text = await session_ros2.error("subscribe_topic", {"topic": "/" + "a" * 300})
    assert "(ROS 2's limit). Check the name with list_topics / list_services / list_actions." in text


async def test_a_parameter_name_of_the_wrong_form_points_at_list_parameters(session_ros2: Session) -> None:
    """The hint survives robot/parameters.py's wrapping and set_parameter's own tail."""
    text = await session_ros2.error("get_parameter", {"name": "background_r"})
    assert "e.g. /turtlesim:background_r (list_parameters shows them)." in text
    text = await session_ros2.error("set_parameter", {"name": "background_r", "value": 1})
    assert "e.g. /turtlesim:background_r (list_parameters shows them). Nothing was set." in text


async def test_an_unknown_type_points_at_the_types_in_use(session: Session) -> None:
    text = await session.error("describe_type", {"type_name": "no_such_msgs/msg/Nothing"})
    assert text.endswith(" list_topics, list_services and list_actions show the types in use.")


@pytest.mark.parametrize("sim", ["ros2"], indirect=True)
async def test_a_missing_or_outside_recording_points_at_read_recording(
    session_dir: tuple[Session, Path],
) -> None:
    session, directory = session_dir
    directory.mkdir(parents=True, exist_ok=True)
    text = await session.error("read_recording", {"file": "nope.mcap"})
    assert text == (
        f"There is no recording 'nope.mcap' in {str(directory.resolve())!r}; read_recording without a file "
        "lists them."
    )
    text = await session.error("read_recording", {"file": "/etc/hostname"})
    assert text == (
        f"'/etc/hostname' is outside the recording directory {str(directory.resolve())!r}; name a file "
        "inside it (read_recording without a file lists them)."
    )


async def test_a_node_that_is_not_running_points_at_list_nodes(session: Session) -> None:
    text = await session.error("get_node_info", {"node": "/no_such_node"})
    assert "Node /no_such_node is not running." in text
    assert text.endswith(" Call list_nodes to see the nodes.")


async def test_an_unknown_message_type_names_its_form_and_list_topics(
    session: Session, sim: SimulatedRobot
) -> None:
    ros2 = sim.dialect == "ros2"
    text = await session.error(
        "publish_topic",
        {"topic": "/new_topic", "message_type": "no_pkg/Nothing", "message": {}},
    )
    form = "`geometry_msgs/msg/Twist`" if ros2 else "`geometry_msgs/Twist`"
    assert f"type names look like {form}; list_topics shows the types in use." in text, text
