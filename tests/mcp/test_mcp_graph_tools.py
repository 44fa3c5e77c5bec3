"""list_topics, get_topic_info, list_services, list_actions against the simulated robots of both dialects."""

from __future__ import annotations

from mcp_harness import Session, open_session, service_rows, text_of, types_for, unreadable_services

from rosbridge_mcp_server.sim import SimulatedRobot


async def test_list_topics_shows_every_topic_with_its_type(session: Session, sim: SimulatedRobot) -> None:
    """The turtle's topics are listed with their dialect's type names, in text and structured content."""
    result = await session.ok("list_topics")
    data = result.structured_content
    assert data is not None
    topics = {row["name"]: row["type"] for row in data["topics"]}
    assert data["count"] == len(topics)
    assert topics["/turtle1/cmd_vel"] == types_for(sim)["twist"]
    assert topics["/chatter"] == types_for(sim)["string"]
    assert f"/turtle1/cmd_vel ({types_for(sim)['twist']})" in text_of(result)
    assert list(topics) == sorted(topics)


async def test_get_topic_info_names_type_publishers_and_subscribers(
    session: Session, sim: SimulatedRobot
) -> None:
    """/chatter is published by /talker; turtle1/cmd_vel/ (sloppily written) is subscribed by /turtlesim."""
    chatter = (await session.ok("get_topic_info", {"topic": "/chatter"})).structured_content
    assert chatter is not None
    assert chatter["type"] == types_for(sim)["string"]
    assert "/talker" in chatter["publishers"]
    cmd_vel = (await session.ok("get_topic_info", {"topic": "turtle1/cmd_vel/"})).structured_content
    assert cmd_vel is not None
    assert cmd_vel["topic"] == "/turtle1/cmd_vel"
    assert "/turtlesim" in cmd_vel["subscribers"]


async def test_doubled_slashes_in_a_name_are_collapsed_as_ros_resolves_them(
    session: Session, sim: SimulatedRobot
) -> None:
    """//turtle1//pose is /turtle1/pose (rospy resolves names so; a real 0.11.17 bridge answers for it)."""
    pose = (await session.ok("get_topic_info", {"topic": "//turtle1//pose"})).structured_content
    assert pose is not None
    assert pose["topic"] == "/turtle1/pose"
    assert "/turtlesim" in pose["publishers"]
    answer = await session.ok(
        "publish_service",
        {
            "service": "//add_two_ints",
            "service_type": types_for(sim)["add_two_ints"],
            "request": {"a": 1, "b": 2},
        },
    )
    assert answer.structured_content is not None
    assert answer.structured_content["service"] == "/add_two_ints"


async def test_get_topic_info_on_an_unknown_topic_says_so_and_suggests_list_topics(session: Session) -> None:
    """A misspelt topic is an error naming it, with the close match and a pointer to list_topics."""
    text = await session.error("get_topic_info", {"topic": "/turtle1/poses"})
    assert "Topic /turtle1/poses is not in the ROS graph" in text
    assert "Did you mean /turtle1/pose?" in text
    assert "list_topics" in text


async def test_list_services_shows_every_service_with_its_type(session: Session, sim: SimulatedRobot) -> None:
    """/add_two_ints and /reset are listed with their types."""
    data = (await session.ok("list_services")).structured_content
    assert data is not None
    services = {row["name"]: row["type"] for row in service_rows(data)}
    assert services["/add_two_ints"] == types_for(sim)["add_two_ints"]
    assert services["/reset"] == types_for(sim)["empty_srv"]
    assert all(services.values()), "every simulated service has a known type"


async def test_list_services_text_is_short_yet_names_every_service_and_type(session: Session) -> None:
    """The per-node and rosapi services are grouped in the text; each row can still be read from it."""
    result = await session.ok("list_services")
    assert result.structured_content is not None
    rows = service_rows(result.structured_content)
    lines = text_of(result).splitlines()
    assert len(lines) < len(rows) / 2, lines
    assert unreadable_services(result) == []


async def test_list_services_looks_each_type_up_once_and_never_for_per_node_services(
    session: Session, sim: SimulatedRobot
) -> None:
    """Per-node and rosapi services are typed by name; the next listing only asks for the names again."""
    first = (await session.ok("list_services")).structured_content
    assert first is not None
    services = {row["name"]: row["type"] for row in service_rows(first)}
    per_node = "/turtlesim/get_parameters" if sim.dialect == "ros2" else "/turtlesim/get_loggers"
    assert services[per_node] in ("rcl_interfaces/srv/GetParameters", "roscpp/GetLoggers")
    assert services["/rosapi/topics"] in ("rosapi_msgs/srv/Topics", "rosapi/Topics")
    assert all(services.values()), "every service is typed"
    looked_up = sim.world.service_calls.get("/rosapi/service_type", 0)
    assert looked_up < len(services) / 2, "per-node and rosapi services need no look-up"
    calls = dict(sim.world.service_calls)
    second = (await session.ok("list_services")).structured_content
    assert second == first
    asked = {
        name: n - calls.get(name, 0) for name, n in sim.world.service_calls.items() if n != calls.get(name)
    }
    assert asked == {"/rosapi/services": 1}


async def test_list_actions_lists_each_server_once_with_its_type(
    session: Session, sim: SimulatedRobot
) -> None:
    """The Fibonacci server appears once, typed (ROS 2: rosapi action_type; ROS 1: the <ns>/goal type)."""
    result = await session.ok("list_actions")
    data = result.structured_content
    assert data is not None
    assert data["actions"] == [{"name": "/fibonacci", "type": types_for(sim)["fibonacci"]}]
    assert data["count"] == 1
    assert "/fibonacci" in text_of(result)


async def test_list_actions_asks_an_action_type_once_per_connection(
    session: Session, sim: SimulatedRobot
) -> None:
    """The next listing asks only for the action servers: a server's type is kept while it is listed."""
    first = (await session.ok("list_actions")).structured_content
    calls = dict(sim.world.service_calls)
    second = (await session.ok("list_actions")).structured_content
    assert second == first
    asked = {
        name: n - calls.get(name, 0) for name, n in sim.world.service_calls.items() if n != calls.get(name)
    }
    assert asked == {"/rosapi/action_servers": 1}


async def test_listings_and_a_service_call_work_on_a_humble_in_order_bridge(
    sim_humble: SimulatedRobot,
) -> None:
    """On Humble's one-connection-in-order bridge, the listings and a service call answer as on Jazzy."""
    async with open_session(sim_humble.url) as session:
        topics = (await session.ok("list_topics")).structured_content
        services = (await session.ok("list_services")).structured_content
        actions = (await session.ok("list_actions")).structured_content
        added = (
            await session.ok(
                "publish_service",
                {
                    "service": "/add_two_ints",
                    "service_type": "example_interfaces/srv/AddTwoInts",
                    "request": {"a": 40, "b": 2},
                },
            )
        ).structured_content
    assert topics is not None
    assert services is not None
    assert actions is not None
    assert added is not None
    assert {"name": "/turtle1/cmd_vel", "type": "geometry_msgs/msg/Twist"} in topics["topics"]
    assert {"name": "/add_two_ints", "type": "example_interfaces/srv/AddTwoInts"} in services["services"]
    assert actions["actions"] == [{"name": "/fibonacci", "type": "example_interfaces/action/Fibonacci"}]
    assert added["response"] == {"sum": 42}
