"""tools/list: every tool with annotations, described parameters and output schemas; --tools picks some."""

from __future__ import annotations

import json
import re
import socket
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from mcp_harness import guarded, open_session, text_of

from mcp import Client
from rosbridge_mcp_server.catalogue import ALL_TOOL_NAMES, CATALOGUE, ORIGINAL_TOOL_NAMES
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config, ConfigError, load_config
from rosbridge_mcp_server.server import INSTRUCTIONS, build_server
from rosbridge_mcp_server.tools import TOOL_MODULES

REPO = Path(__file__).resolve().parents[2]
#: The parameters each tool has had since it came: a contract with hosts and models (a new tool's own test
#: says its parameters; every tool listed is the catalogue's, in its order).
EXPECTED_PARAMETERS = {
    "list_topics": ["filter", "limit", "offset"],
    "get_topic_info": ["topic"],
    "publish_topic": ["topic", "message_type", "message", "rate_hz", "duration"],
    "list_services": ["filter", "limit", "offset"],
    "publish_service": ["service", "service_type", "request", "timeout"],
    "list_actions": ["filter", "limit", "offset"],
    "publish_action": ["action_name", "action_type", "goal", "timeout"],
    "cancel_action": ["action_name", "goal_id"],
    "subscribe_topic": ["topic", "message_type", "count", "duration", "timeout", "fields", "qos"],
    "get_image": ["topic", "max_size", "format", "timeout"],
    "describe_type": ["type_name"],
    "list_nodes": ["filter", "limit", "offset"],
    "get_node_info": ["node", "filter"],
    "list_parameters": ["node", "filter", "limit", "offset"],
    "get_parameter": ["name"],
    "set_parameter": ["name", "value"],
    "get_transform": ["target_frame", "source_frame", "timeout", "namespace"],
    "read_logs": ["level", "node", "text", "since", "limit", "offset"],
    "diagnose": ["focus", "namespace"],
    "view_map": [
        "topic",
        "base_frame",
        "path_topic",
        "scan_topic",
        "around_robot",
        "max_size",
        "timeout",
        "namespace",
    ],
    "view_scan": ["topic", "radius", "clearance", "max_size", "timeout", "namespace"],
    "plot_topic": ["series", "duration", "max_size"],
    "stop_robot": [],
    "navigate_to": ["goal", "frame", "forward", "left", "turn", "timeout", "namespace"],
    "record": ["topics", "duration", "max_megabytes", "name", "stop"],
    "read_recording": ["file", "mode", "fields", "at", "window", "topics"],
    "view_arm": ["frame", "timeout"],
    "move_arm": ["joints", "pose", "relative", "controller", "timeout"],
    "move_gripper": ["command", "position", "max_effort", "action", "timeout"],
}
#: The tools that only read, as the catalogue says.
READ_ONLY = {entry.name for entry in CATALOGUE if not entry.acts}
#: Acting tools that leave the robot as they found it when called twice with the same arguments.
IDEMPOTENT_ACTS = {"set_parameter"}
ORIGINAL = list(ORIGINAL_TOOL_NAMES)
#: The stop, served whenever a tool that acts is (its spec says ``stops``).
STOPS = [module.SPEC.name for module in TOOL_MODULES if module.SPEC.stops]
#: Budgets for the tools/list answer (compact JSON): what a host pays in context for every session, at most
#: 1 KB per tool on average (it was 29 KB for the 18 tools before issue 16; since issue 37's namespace
#: argument, the 1,024-byte KB of the original eight's budget).
ALL_TOOLS_BUDGET = len(ALL_TOOL_NAMES) * 1_024
#: The original eight come with the e-stop (stop_robot), which is listed wherever acting tools are.
ORIGINAL_TOOLS_BUDGET = (len(ORIGINAL) + len(STOPS)) * 1_024


#: Ports held bound (never listened on) while this module's tests run: a connection there is refused, and no
#: other test of a parallel run can take the port in the meantime, as it could a port bound and let go.
_HELD: list[socket.socket] = []


@pytest.fixture(autouse=True, scope="module")
def _release_held_ports() -> Iterator[None]:
    yield
    while _HELD:
        _HELD.pop().close()


def _closed_port_url() -> str:
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    _HELD.append(sock)
    return f"ws://127.0.0.1:{sock.getsockname()[1]}"


async def test_every_tool_is_listed_with_annotations_and_described_parameters() -> None:
    """Each tool keeps its original name and parameters, and has hints, an example and an output schema."""
    async with open_session(_closed_port_url(), wait=False) as session:
        listed = (await session.mcp.list_tools()).tools
    assert [tool.name for tool in listed] == list(ALL_TOOL_NAMES)
    assert set(EXPECTED_PARAMETERS) <= set(ALL_TOOL_NAMES)
    for tool in listed:
        if tool.name in EXPECTED_PARAMETERS:
            assert list(tool.input_schema.get("properties", {})) == EXPECTED_PARAMETERS[tool.name], tool.name
        for name, schema in tool.input_schema.get("properties", {}).items():
            assert "e.g." in schema.get("description", ""), f"{tool.name}.{name} has no example"
        assert "Example" in tool.description or "call it with {}" in tool.description
        assert tool.title
        assert tool.output_schema is not None
        assert tool.output_schema.get("type") == "object"
        hints = tool.annotations
        assert hints is not None
        # A hint left out means MCP's default: read-only false, destructive true, idempotent false, open world
        # true; destructive and idempotent are given only for tools that act.
        assert hints.open_world_hint is None
        if tool.name == "stop_robot":
            # It acts, but only takes motion away, and repeating it is harmless.
            assert (hints.read_only_hint, hints.destructive_hint, hints.idempotent_hint) == (
                None,
                False,
                True,
            )
        elif tool.name == "record":
            # It writes a file on the server's host, never destroys one, and sends nothing to the robot.
            assert (hints.read_only_hint, hints.destructive_hint, hints.idempotent_hint) == (
                None,
                False,
                None,
            )
        elif tool.name in READ_ONLY:
            assert (hints.read_only_hint, hints.destructive_hint, hints.idempotent_hint) == (True, None, None)
        else:
            idempotent = True if tool.name in IDEMPOTENT_ACTS else None
            assert (hints.read_only_hint, hints.destructive_hint, hints.idempotent_hint) == (
                None,
                None,
                idempotent,
            )


async def test_output_schemas_are_self_contained() -> None:
    """No output schema sends clients chasing $ref into $defs: every nested model is written in place."""
    async with open_session(_closed_port_url(), wait=False) as session:
        listed = (await session.mcp.list_tools()).tools
    nested = {tool.name for tool in listed if "items" in json.dumps(tool.output_schema)}
    assert {"list_topics", "list_services", "list_actions"} <= nested
    for tool in listed:
        text = json.dumps(tool.output_schema)
        assert "$ref" not in text, tool.name
        assert "$defs" not in text, tool.name


async def test_required_parameters_are_the_ones_without_defaults() -> None:
    """Messages, requests, goals and timeouts are optional; names and types are required."""
    async with open_session(_closed_port_url(), wait=False) as session:
        listed = {tool.name: tool for tool in (await session.mcp.list_tools()).tools}
    assert listed["publish_topic"].input_schema["required"] == ["topic", "message_type"]
    assert listed["publish_service"].input_schema["required"] == ["service", "service_type"]
    assert listed["publish_action"].input_schema["required"] == ["action_name", "action_type"]
    assert listed["cancel_action"].input_schema["required"] == ["action_name"]
    assert "required" not in listed["list_topics"].input_schema
    assert "required" not in listed["list_parameters"].input_schema


async def test_with_no_bridge_the_server_starts_lists_tools_and_tools_fail_naming_the_url() -> None:
    """With nothing listening, the session starts, and a tool fails with the not-connected text and URL."""
    url = _closed_port_url()
    config = Config(url=url)
    ros = RosbridgeClient(url, connect_timeout=2.0)
    async with Client(build_server(guarded(ros, config), config), mode="legacy") as mcp:
        assert mcp.instructions is not None
        assert "list_topics" in mcp.instructions
        assert len((await mcp.list_tools()).tools) == len(ALL_TOOL_NAMES)
        result = await mcp.call_tool("list_topics", {})
        publish = await mcp.call_tool(
            "publish_topic",
            {"topic": "/turtle1/cmd_vel", "message_type": "geometry_msgs/msg/Twist", "message": {}},
        )
    assert result.is_error
    assert f"Not connected to rosbridge at {url}" in text_of(result)
    assert "ROSBRIDGE_HOST" in text_of(result)
    assert publish.is_error
    assert "nothing was sent" in text_of(publish)


async def test_arguments_that_do_not_fit_are_one_readable_line_per_argument() -> None:
    """A missing or out-of-range argument is an isError result naming it, not a pydantic dump."""
    async with open_session(_closed_port_url(), wait=False) as session:
        missing = await session.error("get_topic_info", {})
        too_long = await session.error(
            "publish_service", {"service": "/x", "service_type": "std_srvs/srv/Empty", "timeout": 301}
        )
        negative = await session.error(
            "publish_action", {"action_name": "/x", "action_type": "a/B", "timeout": -1}
        )
    assert missing.startswith("Invalid arguments for get_topic_info: topic: required but missing.")
    assert "timeout: input should be less than or equal to 300 (got 301)" in too_long
    assert "It takes: service, service_type, request (optional), timeout (optional)." in too_long
    assert "timeout: input should be greater than 0" in negative
    assert "pydantic" not in missing + too_long + negative


async def test_a_message_of_the_wrong_json_kind_is_one_line_naming_what_is_expected() -> None:
    """A list where a message object belongs says an object is expected, once."""
    async with open_session(_closed_port_url(), wait=False) as session:
        text = await session.error(
            "publish_topic", {"topic": "/x", "message_type": "std_msgs/msg/Empty", "message": [1, 2]}
        )
    assert text.startswith(
        "Invalid arguments for publish_topic: message: expected a JSON object (got [1, 2])"
    )
    assert text.count("message:") == 1


def _listing_size(tools: list[Any]) -> int:
    dumped = [tool.model_dump(mode="json", by_alias=True, exclude_none=True) for tool in tools]
    return len(json.dumps(dumped, separators=(",", ":")))


async def test_tools_original_lists_only_the_first_eight_within_budget() -> None:
    """--tools original shows the eight original tools and the e-stop that goes with acting tools; both
    listings stay within their size budgets."""
    url = _closed_port_url()
    sizes = {}
    for spec in ("original", "all"):
        config = load_config({}, url=url, tools=spec)
        async with Client(build_server(guarded(RosbridgeClient(url), config), config), mode="legacy") as mcp:
            tools = (await mcp.list_tools()).tools
        sizes[spec] = _listing_size(tools)
        expected = [*ORIGINAL, *STOPS] if spec == "original" else list(ALL_TOOL_NAMES)
        assert [tool.name for tool in tools] == expected
    assert sizes["original"] <= ORIGINAL_TOOLS_BUDGET
    assert sizes["all"] <= ALL_TOOLS_BUDGET


async def test_a_comma_list_of_groups_and_names_is_honoured_in_order() -> None:
    """ROSBRIDGE_MCP_TOOLS=get_image,original lists the original eight, then get_image (and the e-stop)."""
    url = _closed_port_url()
    config = load_config({"ROSBRIDGE_MCP_TOOLS": "get_image, original"}, url=url)
    async with Client(build_server(guarded(RosbridgeClient(url), config), config), mode="legacy") as mcp:
        names = [tool.name for tool in (await mcp.list_tools()).tools]
    assert names == [*ORIGINAL, "get_image", *STOPS]


async def test_tools_watch_lists_every_reading_tool_of_the_graph_and_nothing_that_acts() -> None:
    """--tools watch ("reading the robot") lists list_topics and get_topic_info with the other readers, and
    neither set_parameter nor, since nothing acts, stop_robot."""
    url = _closed_port_url()
    config = load_config({}, url=url, tools="watch")
    async with Client(build_server(guarded(RosbridgeClient(url), config), config), mode="legacy") as mcp:
        tools = (await mcp.list_tools()).tools
    names = [tool.name for tool in tools]
    assert names[:2] == ["list_topics", "get_topic_info"]
    assert {"list_services", "list_actions", "subscribe_topic", "diagnose", "read_logs"} <= set(names)
    assert "set_parameter" not in names
    assert "stop_robot" not in names
    assert all(tool.annotations is not None and tool.annotations.read_only_hint for tool in tools), names
    assert set(names) <= READ_ONLY


def test_an_unknown_tool_name_is_a_configuration_error_listing_the_names() -> None:
    """--tools with a misspelt name fails at start with the groups and names that exist."""
    with pytest.raises(
        ConfigError, match=r"--tools: unknown tool or group 'get_imag'; use all, original, watch"
    ):
        load_config({}, tools="original,get_imag")


def test_the_flag_wins_over_the_environment() -> None:
    """--tools beats ROSBRIDGE_MCP_TOOLS; all is stored as no restriction."""
    config = load_config({"ROSBRIDGE_MCP_TOOLS": "original"}, tools="all")
    assert config.tools is None
    assert load_config({"ROSBRIDGE_MCP_TOOLS": "list_nodes"}).tools == ("list_nodes",)


async def test_no_schema_property_has_a_title_that_restates_its_name() -> None:
    """Input and output schemas leave out pydantic's per-property titles ("goal_id" -> "Goal Id")."""
    async with open_session(_closed_port_url(), wait=False) as session:
        listed = (await session.mcp.list_tools()).tools
    echoes: list[str] = []

    def walk(node: Any, where: str) -> None:
        if isinstance(node, dict):
            for name, prop in (node.get("properties") or {}).items():
                if isinstance(prop, dict) and prop.get("title") == name.title().replace("_", " "):
                    echoes.append(f"{where}.{name}")
            for value in node.values():
                walk(value, where)
        elif isinstance(node, list):
            for value in node:
                walk(value, where)

    for tool in listed:
        walk(tool.input_schema, f"{tool.name} input")
        walk(tool.output_schema, f"{tool.name} output")
    assert echoes == []
    # Output schemas keep structure and types only (issue 16: tools/list is paid on every conversation).
    assert all(tool.output_schema and "title" not in json.dumps(tool.output_schema) for tool in listed)
    assert all(tool.output_schema and tool.output_schema.get("properties") for tool in listed)


#: A row of a README's tools table: ``| `name` | ...``.
_README_ROW = re.compile(r"^\| `([a-z_]+)` \|", re.MULTILINE)


@pytest.mark.parametrize("readme", ["README.md", "README_ja.md"])
def test_each_readme_has_a_row_for_every_tool_and_none_for_a_tool_that_is_gone(readme: str) -> None:
    """Both READMEs' tools tables have one row per tool of the catalogue, in its order (and the edge's own
    list_robots before show_console), so a tool added to the catalogue without its documentation fails."""
    text = (REPO / readme).read_text()
    table = text[: text.index("`show_console` |")]
    rows = _README_ROW.findall(table)
    assert [row for row in rows if row in ALL_TOOL_NAMES] == list(ALL_TOOL_NAMES)
    assert set(rows) - set(ALL_TOOL_NAMES) == {"list_robots"}


def test_the_instructions_name_every_tool_that_acts_the_stop_and_what_else_changes() -> None:
    """The instructions are derived from the specs: every tool that acts on the robot is named as acting, the
    stop as the stop, and record as changing the host's files rather than the robot."""
    acting_sentence = INSTRUCTIONS.split(" act on the robot")[0]
    acting = [m.SPEC.name for m in TOOL_MODULES if m.SPEC.acts_on is not None]
    assert len(acting) >= 9
    assert [name for name in acting if not re.search(rf"\b{name}\b", acting_sentence)] == []
    assert "read_recording" not in acting_sentence
    assert "(record changes files on the server's host)" in INSTRUCTIONS
    assert f"5. {' and '.join(STOPS)} stops everything this server started" in INSTRUCTIONS
