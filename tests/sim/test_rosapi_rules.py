"""rosapi's computations, checked without sockets: action server lists and parameter semantics."""

from __future__ import annotations

import json

import pytest

from rosbridge_mcp_server.sim.graph import ServiceFailure, is_hidden, resolve_name
from rosbridge_mcp_server.sim.params import Ros1Params, Ros2Params, parameter_value
from rosbridge_mcp_server.sim.rosapi import ros1_action_servers, ros2_action_servers

ACTIONLIB = ["/move/cancel", "/move/feedback", "/move/goal", "/move/result", "/move/status"]


def test_ros1_action_servers_needs_all_five_actionlib_topics() -> None:
    """A namespace with only four of the five leaves is not an action server."""
    assert ros1_action_servers(ACTIONLIB[:4]) == []
    assert ros1_action_servers(ACTIONLIB) == ["/move"]


def test_ros1_action_servers_repeats_a_namespace_until_another_one_starts() -> None:
    """0.11.17 quirk: later topics (even single-component ones) report the last complete namespace again."""
    topics = [*ACTIONLIB, "/rosout", "/rosout_agg", "/turtle1/pose"]
    assert ros1_action_servers(topics) == ["/move", "/move", "/move"]


def test_ros2_action_servers_uses_hidden_feedback_and_status_topics() -> None:
    """ROS 2 reports <ns> when <ns>/_action/feedback and <ns>/_action/status both exist, once."""
    topics = ["/nav/_action/feedback", "/nav/_action/status", "/only/_action/status", "/chatter"]
    assert ros2_action_servers(topics) == ["/nav"]


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("5", 5),
        ("2.5", 2.5),
        ("true", True),
        ("off", False),
        ("[1, 2]", [1, 2]),
        ("hello", "hello"),
        ('{"a": 1}', '{"a": 1}'),
    ],
)
def test_ros2_set_param_reads_strings_like_rclpy(text: str, value: object) -> None:
    """rclpy's get_parameter_value: numbers, YAML booleans and lists are typed; dictionaries stay text."""
    assert parameter_value(text) == value


def test_ros2_param_quoted_number_becomes_an_integer() -> None:
    """rosapi unquotes a JSON string and rclpy then reads '5' as the integer 5 (a real quirk)."""
    store: dict[str, object] = {}
    params = Ros2Params(store, lambda node: node == "/n")
    assert params.set("/n:p", '"5"') == (True, "")
    assert store == {"/n:p": 5}


def test_ros2_params_need_a_colon_and_an_existing_node() -> None:
    """A name without ':' is malformed; setting on a node that does not exist fails; get falls back."""
    params = Ros2Params({}, lambda node: node == "/n")
    assert params.set("no_colon", "1")[0] is False
    assert params.set("/ghost:p", "1")[0] is False
    assert params.get("/ghost:p", "3") == ("3", True, "")
    assert params.get("/ghost:p", "") == ('""', True, "")


def test_ros2_set_param_with_non_json_value_fails_inside_the_service() -> None:
    """rosapi raises for a value that is not JSON (the ROS 2 caller then gets no response)."""
    params = Ros2Params({}, lambda node: True)
    with pytest.raises(ServiceFailure, match="JSON-formatted string"):
        params.set("/n:p", "not json")


def test_ros1_namespaces_read_as_dicts_and_set_as_trees() -> None:
    """Reading /a gives the subtree; setting a dict replaces it; deleting removes it."""
    store: dict[str, object] = {"/a/b": 1, "/a/c/d": "x", "/z": True}
    params = Ros1Params(store)
    assert json.loads(params.get("/a", "")) == {"b": 1, "c": {"d": "x"}}
    params.set("/a", '{"e": 2}')
    assert store == {"/a/e": 2, "/z": True}
    params.delete("/a")
    assert store == {"/z": True}
    assert params.get("/a", "") == "null"


def test_ros1_search_param_walks_up_from_the_rosapi_namespace() -> None:
    """search_param finds /rosapi/x before /x, and returns '' when nothing matches."""
    params = Ros1Params({"/x": 1, "/rosapi/y": 2})
    assert params.search("x") == "/x"
    assert params.search("y") == "/rosapi/y"
    assert params.search("x/sub") == "/x/sub"
    assert params.search("nothing") == ""


def test_names_resolve_in_the_root_namespace_and_underscores_hide_them() -> None:
    """'chatter' is /chatter; a component starting with '_' is hidden (ROS 2)."""
    assert resolve_name("chatter") == "/chatter"
    assert is_hidden("/fibonacci/_action/status")
    assert not is_hidden("/turtle1/pose")
