"""Fewest round trips on the happy path, on the Nav2 world in both dialects: each graph tool asks only what
its answer needs (counted by the simulated robot), and checks that only word an error run after a failure."""

from __future__ import annotations

import json
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import pytest
import websockets
from mcp_harness import Session, open_session, service_rows, warmed_up

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.graph import ServiceEntry

MakeSim = Callable[..., Awaitable[SimulatedRobot]]


@pytest.fixture(params=["ros2", "ros1"])
async def nav2(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    """A Nav2 robot of each dialect."""
    return await make_sim(dialect=request.param, world="nav2")


@pytest.fixture
async def session(nav2: SimulatedRobot) -> AsyncIterator[Session]:
    """An MCP session on it, once the server has learnt the service types (so only the tools' calls count)."""
    async with open_session(nav2.url) as opened:
        await warmed_up(opened.ros)
        yield opened


async def asked(
    robot: SimulatedRobot, session: Session, tool: str, arguments: dict[str, Any]
) -> dict[str, int]:
    """The services one successful tool call asked, with how often."""
    before = dict(robot.world.service_calls)
    await session.ok(tool, arguments)
    return {
        name: count - before.get(name, 0)
        for name, count in robot.world.service_calls.items()
        if count != before.get(name, 0)
    }


def param(robot: SimulatedRobot, node: str, name: str) -> str:
    """A parameter's full name in the robot's dialect."""
    return f"{node}:{name}" if robot.dialect == "ros2" else f"{node}/{name.replace('.', '/')}"


async def test_get_parameter_is_one_call(session: Session, nav2: SimulatedRobot) -> None:
    """ROS 2 asks the node's get_parameters alone; ROS 1 rosapi's get_param alone (no has_param first)."""
    calls = await asked(nav2, session, "get_parameter", {"name": param(nav2, "/amcl", "max_particles")})
    expected = "/amcl/get_parameters" if nav2.dialect == "ros2" else "/rosapi/get_param"
    assert calls == {expected: 1}


async def test_a_missing_parameter_is_explained_after_the_failed_read(
    session: Session, nav2: SimulatedRobot
) -> None:
    """The error still says the parameter does not exist and offers what does."""
    text = await session.error("get_parameter", {"name": param(nav2, "/amcl", "max_particle")})
    assert "max_particle" in text
    assert "max_particles" in text


async def test_list_parameters_of_a_node_is_one_call(session: Session, nav2: SimulatedRobot) -> None:
    """ROS 2 asks the node's list_parameters alone (no service list first); ROS 1 get_param_names."""
    calls = await asked(nav2, session, "list_parameters", {"node": "/controller_server"})
    expected = "/controller_server/list_parameters" if nav2.dialect == "ros2" else "/rosapi/get_param_names"
    assert calls == {expected: 1}


async def test_list_parameters_of_an_unknown_node_still_names_the_likely_one(session: Session) -> None:
    """A misspelt node: the answer is an error that suggests the node meant."""
    text = await session.error("list_parameters", {"node": "/controler_server"})
    assert "/controller_server" in text


async def test_get_node_info_asks_no_service_types_it_can_tell(
    session: Session, nav2: SimulatedRobot
) -> None:
    """Parameter, lifecycle and (after list_actions) action services are typed by name; ROS 1 asks no node
    list unless the node turns out unknown."""
    await session.ok("list_actions")
    calls = await asked(nav2, session, "get_node_info", {"node": "/controller_server"})
    listings = {name: calls.pop(name) for name in ("/rosapi/nodes", "/rosapi/topics") if name in calls}
    assert calls == {"/rosapi/node_details": 1}
    # A node list or topic list seen within the last second (the log keeper's look, say) is reused.
    assert listings.get("/rosapi/topics", 0) <= 1
    # rosapi 2.x never answers node_details for an unknown node: there a node list decides first.
    assert listings.get("/rosapi/nodes", 0) <= (1 if nav2.dialect == "ros2" else 0)


async def test_get_node_info_of_an_unknown_node_says_so(session: Session) -> None:
    """An unknown node is still an error naming the likely meant one."""
    text = await session.error("get_node_info", {"node": "/controler_server"})
    assert "Did you mean /controller_server?" in text


@pytest.mark.parametrize(
    ("tool", "service"),
    [("list_topics", "/rosapi/topics"), ("list_nodes", "/rosapi/nodes")],
)
async def test_one_call_listings_ask_once(
    session: Session, nav2: SimulatedRobot, tool: str, service: str
) -> None:
    """list_topics and list_nodes each ask rosapi one question, whatever the page."""
    assert await asked(nav2, session, tool, {"filter": "costmap", "limit": 5, "offset": 2}) == {service: 1}


async def test_later_listings_of_services_and_actions_ask_only_for_names(
    session: Session, nav2: SimulatedRobot
) -> None:
    """Types learnt on this connection are kept while listed: the next listing is one call."""
    await session.ok("list_services")
    await session.ok("list_actions")
    assert await asked(nav2, session, "list_services", {}) == {"/rosapi/services": 1}
    assert await asked(nav2, session, "list_actions", {}) == {"/rosapi/action_servers": 1}


async def test_describe_type_asks_once_per_connection(session: Session, nav2: SimulatedRobot) -> None:
    """A type's definition (and, on ROS 2, the installed types) is kept for the connection: asked once."""
    name = "nav_msgs/msg/OccupancyGrid" if nav2.dialect == "ros2" else "nav_msgs/OccupancyGrid"
    first = await asked(nav2, session, "describe_type", {"type_name": name})
    assert first["/rosapi/message_details"] == 1
    assert await asked(nav2, session, "describe_type", {"type_name": name}) == {}


async def test_a_type_missing_from_the_kept_list_is_looked_up_again(make_sim: MakeSim) -> None:
    """ROS 2: an unknown type is refused only after the installed types were asked afresh."""
    robot = await make_sim(dialect="ros2", world="nav2")
    async with open_session(robot.url) as session:
        await session.ok("describe_type", {"type_name": "nav_msgs/msg/OccupancyGrid"})
        before = robot.world.service_calls.get("/rosapi/interfaces", 0)
        text = await session.error("describe_type", {"type_name": "nav_msgs/msg/OccupancyGridd"})
    assert "OccupancyGridd" in text
    assert robot.world.service_calls["/rosapi/interfaces"] == before + 1


async def test_get_node_info_on_rosbridge_server_rs_is_one_round_trip(make_sim: MakeSim) -> None:
    """rosbridge-server-rs: node_details and topics side by side (or a topic list seen within the last
    second), no node list first."""
    robot = await make_sim(dialect="ros2", world="nav2", server="rs")
    async with open_session(robot.url) as opened:
        await warmed_up(opened.ros)
        await opened.ok("list_actions")
        calls = await asked(robot, opened, "get_node_info", {"node": "/controller_server"})
    topics = calls.pop("/rosapi/topics", 0)
    assert calls == {"/rosapi/node_details": 1}
    assert topics <= 1


async def test_an_unknown_node_on_rosbridge_server_rs_is_worded_from_the_node_list(make_sim: MakeSim) -> None:
    """rs never answers node_details for an unknown node: the node list, asked after its silence, words it."""
    robot = await make_sim(dialect="ros2", world="nav2", server="rs")
    async with open_session(robot.url) as opened:
        # The server's own first look at the graph (diagnose's node list at connect) is not the tool's.
        before = robot.world.service_calls.get("/rosapi/nodes", 0)
        text = await opened.error("get_node_info", {"node": "/controler_server"})
    assert "Did you mean /controller_server?" in text
    assert robot.world.service_calls.get("/rosapi/nodes") == before + 1


async def test_an_in_order_rosbridge_suite_is_never_asked_details_of_an_unknown_node(
    make_sim: MakeSim,
) -> None:
    """rosbridge_suite ROS 2 (2.1.0, in order): the node list first; never node_details of an unknown node."""
    robot = await make_sim(dialect="ros2", world="nav2", in_order=True, rosapi="2.1.0")
    async with open_session(robot.url) as opened:
        text = await opened.error("get_node_info", {"node": "/controler_server"})
        assert "Did you mean /controller_server?" in text
        assert "/rosapi/node_details" not in robot.world.service_calls
        await opened.ok("get_node_info", {"node": "/controller_server"})
    assert robot.world.service_calls["/rosapi/node_details"] == 1


async def test_a_later_listing_shows_a_service_offered_and_withdrawn_meanwhile(make_sim: MakeSim) -> None:
    """A listing reused while the services stay the same still follows the graph when they change."""
    robot = await make_sim(dialect="ros2", world="nav2")
    async with open_session(robot.url) as opened, websockets.connect(robot.url) as provider:
        first = service_rows((await opened.ok("list_services")).structured_content)
        assert first == service_rows((await opened.ok("list_services")).structured_content)
        offer = {"op": "advertise_service", "service": "/dock_now", "type": "std_srvs/srv/Trigger"}
        await provider.send(json.dumps(offer))
        # No acknowledgement exists in rosbridge: a call on the same connection comes after the offer.
        await provider.send(json.dumps({"op": "call_service", "id": "after", "service": "/rosapi/get_time"}))
        assert json.loads(await provider.recv())["id"] == "after"
        offered = service_rows((await opened.ok("list_services")).structured_content)
        assert {"name": "/dock_now", "type": "std_srvs/srv/Trigger"} in offered
        assert len(offered) == len(first) + 1
        await provider.send(json.dumps({"op": "unadvertise_service", "service": "/dock_now"}))
        await provider.send(json.dumps({"op": "call_service", "id": "gone", "service": "/rosapi/get_time"}))
        assert json.loads(await provider.recv())["id"] == "gone"
        assert service_rows((await opened.ok("list_services")).structured_content) == first


async def test_get_node_info_learns_an_actions_type_once_for_its_hidden_services(
    session: Session, nav2: SimulatedRobot
) -> None:
    """Without list_actions first: the second call asks no type of the node's hidden action services."""
    await session.ok("get_node_info", {"node": "/controller_server"})
    calls = await asked(nav2, session, "get_node_info", {"node": "/controller_server"})
    assert "/rosapi/service_type" not in calls
    info = (await session.ok("get_node_info", {"node": "/controller_server"})).structured_content
    assert info is not None
    typed = {row["name"]: row["type"] for row in info["services"]}
    if nav2.dialect == "ros2":
        assert typed["/follow_path/_action/send_goal"] == "nav2_msgs/action/FollowPath_SendGoal"


async def test_every_nodes_parameters_follow_the_service_list_from_one_listing_to_the_next(
    make_sim: MakeSim,
) -> None:
    """A later listing asks the nodes the last one named while the service list is on its way; the new list
    decides: a node that left is not in the answer, a node that came is asked and is."""

    async def new_node_names(request: dict[str, Any]) -> dict[str, Any]:
        return {"result": {"names": ["alpha", "beta"], "prefixes": []}}

    robot = await make_sim(dialect="ros2", world="nav2")
    async with open_session(robot.url) as session:
        before = (await session.ok("list_parameters", {"filter": "/amcl:*"})).structured_content
        assert before is not None
        assert before["count"] > 0
        robot.graph.remove_service("/amcl/list_parameters")
        robot.graph.add_service(
            ServiceEntry(
                "/dock_camera/list_parameters",
                "rcl_interfaces/srv/ListParameters",
                "/dock_camera",
                new_node_names,
            )
        )
        calls = await asked(robot, session, "list_parameters", {"filter": "/amcl:*"})
        after = (await session.ok("list_parameters", {"filter": "/amcl:*"})).structured_content
        came = (await session.ok("list_parameters", {"filter": "/dock_camera:*"})).structured_content
    assert after is not None
    assert after["count"] == 0
    assert came is not None
    assert came["nodes"] == [{"node": "/dock_camera", "names": ["alpha", "beta"]}]
    # One service list; every node the last listing named (/amcl too: its answer is not used) or the new one.
    assert calls["/rosapi/services"] == 1
    assert calls["/dock_camera/list_parameters"] == 1
    assert calls["/controller_server/list_parameters"] == 1


@pytest.mark.parametrize(
    ("tool", "arguments", "expected"),
    [
        ("get_transform", {"target_frame": "map", "source_frame": "base_link"}, {"/rosapi/topic_type": 2}),
        ("view_scan", {}, {"/rosapi/topic_type": 1}),
        ("view_map", {"path_topic": "/plan", "scan_topic": "/scan"}, {"/rosapi/topic_type": 7}),
    ],
)
async def test_a_robot_without_a_namespace_is_asked_nothing_more_about_namespaces(
    session: Session, nav2: SimulatedRobot, tool: str, arguments: dict[str, Any], expected: dict[str, int]
) -> None:
    """The namespace is looked for only when the plain names are missing: the tf topics' types (and the
    map's, plan's and scan's), nothing else."""
    assert await asked(nav2, session, tool, arguments) == expected
