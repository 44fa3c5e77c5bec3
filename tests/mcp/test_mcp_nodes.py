"""list_nodes and get_node_info through an MCP session, in both dialects."""

from __future__ import annotations

from mcp_harness import Session, text_of, types_for

from rosbridge_mcp_server.sim import SimulatedRobot


async def test_the_running_nodes_are_listed(session: Session) -> None:
    """The simulated robot's nodes are listed, sorted, in the structured content."""
    result = await session.ok("list_nodes")
    nodes = (result.structured_content or {})["nodes"]
    assert {"/turtlesim", "/talker", "/camera", "/rosapi"} <= set(nodes)
    assert nodes == sorted(nodes)
    assert "/turtlesim" in text_of(result)


async def test_a_node_shows_its_topics_and_services_with_types(session: Session, sim: SimulatedRobot) -> None:
    """/turtlesim publishes its pose, subscribes to cmd_vel with the Twist type, and serves /reset."""
    result = await session.ok("get_node_info", {"node": "/turtlesim"})
    data = result.structured_content
    assert data is not None
    subscriptions = {item["name"]: item["type"] for item in data["subscriptions"]}
    assert subscriptions["/turtle1/cmd_vel"] == types_for(sim)["twist"]
    assert "/turtle1/pose" in {item["name"] for item in data["publications"]}
    services = {item["name"]: item["type"] for item in data["services"]}
    assert services["/reset"] == types_for(sim)["empty_srv"]
    assert "/turtle1/cmd_vel [" in text_of(result)


async def test_a_node_name_without_slash_is_made_absolute(session: Session) -> None:
    """'talker' is read as /talker."""
    result = await session.ok("get_node_info", {"node": "talker"})
    assert (result.structured_content or {})["node"] == "/talker"


async def test_an_unknown_node_is_an_error_with_a_suggestion(session: Session) -> None:
    """A misspelt node is an error suggesting the real one (ROS 2 node_details never answers for it)."""
    text = await session.error("get_node_info", {"node": "/turtlesimm"})
    assert "Node /turtlesimm is not running" in text
    assert "Did you mean /turtlesim?" in text
