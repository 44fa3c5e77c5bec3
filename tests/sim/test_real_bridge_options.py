"""What the real bridges showed, as options of the simulated robot: rosapi latency, rosapi 2.1.0, the distro,
and the per-node services of a real graph."""

from __future__ import annotations

import time
from typing import Any

import pytest
from rawclient import MakeSim, RawClient

from rosbridge_mcp_server.sim import SimulatedRobot

LATENCY = 0.05


async def test_rosapi_latency_serves_one_call_at_a_time(make_sim: MakeSim) -> None:
    """Four rosapi calls sent side by side take four latencies: a real rosapi answers one after another."""
    robot = await make_sim(dialect="ros2", rosapi_latency=LATENCY)
    async with await RawClient.open(robot.url) as client:
        started = time.monotonic()
        for n in range(4):
            await client.send({"op": "call_service", "service": "/rosapi/topics", "id": f"t{n}"})
        answers = [await client.reply(f"t{n}") for n in range(4)]
        elapsed = time.monotonic() - started
    assert all("/chatter" in a["values"]["topics"] for a in answers)
    assert elapsed >= 4 * LATENCY * 0.95


async def test_rosapi_latencies_are_taken_in_turn(make_sim: MakeSim) -> None:
    """(fast, fast, fast, slow): every fourth rosapi call is the slow one, as a real ROS 2 rosapi's p90."""
    robot = await make_sim(dialect="ros2", rosapi_latency=(0.0, 0.0, 0.0, 0.25))
    durations = []
    async with await RawClient.open(robot.url) as client:
        for _ in range(8):
            started = time.monotonic()
            await client.values("/rosapi/get_time")
            durations.append(time.monotonic() - started)
    slow = [n for n, d in enumerate(durations) if d >= 0.25 * 0.95]
    assert slow == [3, 7]


async def test_rosapi_latency_does_not_slow_other_services(make_sim: MakeSim) -> None:
    """A world service answers while rosapi is busy with a slow queue."""
    robot = await make_sim(dialect="ros1", rosapi_latency=1.0)
    async with await RawClient.open(robot.url) as client:
        await client.send({"op": "call_service", "service": "/rosapi/nodes", "id": "queued"})
        total = await client.values("/add_two_ints", {"a": 2, "b": 3})
        # The rosapi call sent first is still unanswered when the world service has answered.
        assert not any(frame.get("id") == "queued" for frame in client.backlog)
    assert total == {"sum": 5}


async def test_without_latency_rosapi_answers_in_the_order_asked(sim: SimulatedRobot) -> None:
    """The default for unit tests: no rosapi latency, so a later world call does not overtake rosapi."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "call_service", "service": "/rosapi/topics", "id": "first"})
        total = await client.values("/add_two_ints", {"a": 2, "b": 3})
        assert any(frame.get("id") == "first" for frame in client.backlog)
    assert total == {"sum": 5}


async def test_rosapi_2_1_names_typedef_fields_with_a_leading_underscore(make_sim: MakeSim) -> None:
    """As rosapi 2.1.0 on the Jazzy and Kilted labs: _linear, _x; the wire still takes plain names."""
    robot = await make_sim(dialect="ros2", rosapi="2.1.0")
    async with await RawClient.open(robot.url) as client:
        twist = await client.values("/rosapi/message_details", {"type": "geometry_msgs/msg/Twist"})
        request = await client.values(
            "/rosapi/service_request_details", {"type": "example_interfaces/srv/AddTwoInts"}
        )
        total = await client.values("/add_two_ints", {"a": 2, "b": 3})
    assert twist["typedefs"][0]["fieldnames"] == ["_linear", "_angular"]
    assert twist["typedefs"][0]["constnames"] == ["SLOT_TYPES", "angular", "linear"]
    assert twist["typedefs"][1]["fieldnames"] == ["_x", "_y", "_z"]
    assert request["typedefs"][0]["type"] == "example_interfaces/AddTwoInts_Request"
    assert request["typedefs"][0]["fieldnames"] == ["_a", "_b"]
    assert total == {"sum": 5}


async def test_rosapi_2_1_has_no_action_type_and_no_interfaces(make_sim: MakeSim) -> None:
    """The services 2.1.0 does not have yet do not exist; action_servers still finds the action."""
    robot = await make_sim(dialect="ros2", rosapi="2.1.0")
    async with await RawClient.open(robot.url) as client:
        action_type = await client.call("/rosapi/action_type", {"action": "/fibonacci"})
        interfaces = await client.call("/rosapi/interfaces")
        goal = await client.call(
            "/rosapi/action_goal_details", {"type": "example_interfaces/action/Fibonacci"}
        )
        servers = await client.values("/rosapi/action_servers")
        services = await client.values("/rosapi/services")
    assert action_type["values"] == "Service /rosapi/action_type does not exist"
    assert interfaces["values"] == "Service /rosapi/interfaces does not exist"
    assert goal["result"] is False
    assert servers["action_servers"] == ["/fibonacci"]
    assert "/rosapi/action_type" not in services["services"]


async def test_rosapi_2_1_parameters_answer_values_only_and_set_only_declared_ones(make_sim: MakeSim) -> None:
    """GetParam has only `value`, SetParam answers nothing; an undeclared parameter is not created."""
    robot = await make_sim(dialect="ros2", rosapi="2.1.0")
    async with await RawClient.open(robot.url) as client:
        value = await client.values("/rosapi/get_param", {"name": "/turtlesim:background_r"})
        set_new = await client.values("/rosapi/set_param", {"name": "/turtlesim:pen_width", "value": "3"})
        set_old = await client.values("/rosapi/set_param", {"name": "/turtlesim:background_r", "value": "7"})
        missing = await client.values(
            "/rosapi/get_param", {"name": "/turtlesim:pen_width", "default_value": "0"}
        )
    assert value == {"value": "69"}
    assert set_new == set_old == {}
    assert missing == {"value": "0"}
    assert "/turtlesim:pen_width" not in robot.world.params
    assert robot.world.params["/turtlesim:background_r"] == 7


async def test_rosapi_2_1_waits_for_a_node_that_does_not_exist(make_sim: MakeSim) -> None:
    """get_param of a missing node costs rosapi 2.1.0 its parameter-service wait, then the default."""
    robot = await make_sim(dialect="ros2", rosapi="2.1.0")
    robot.rosapi_node.param_node_wait = 0.2
    async with await RawClient.open(robot.url) as client:
        started = time.monotonic()
        value = await client.values("/rosapi/get_param", {"name": "/ghost:x", "default_value": "1"})
        elapsed = time.monotonic() - started
    assert value == {"value": "1"}
    assert elapsed >= 0.2 * 0.95


async def test_rosapi_2_1_node_details_leaves_hidden_names_out(make_sim: MakeSim) -> None:
    """2.1.0 lists only the parameter and type services of /fibonacci_server, no _action names."""
    robot = await make_sim(dialect="ros2", rosapi="2.1.0", in_order=True, distro="kilted")
    async with await RawClient.open(robot.url) as client:
        node = await client.values("/rosapi/node_details", {"node": "/fibonacci_server"})
    assert not [name for name in node["publishing"] + node["services"] if "/_action/" in name]
    assert "/fibonacci_server/get_type_description" in node["services"]
    assert len(node["services"]) == 7


async def _send_unanswered(client: RawClient, service: str, args: dict[str, Any], call_id: str) -> None:
    await client.send({"op": "call_service", "service": service, "args": args, "id": call_id})


def _answered(client: RawClient, call_id: str) -> bool:
    """Whether a reply with ``call_id`` has arrived (the replies waited for since are kept in the backlog)."""
    return any(frame.get("id") == call_id for frame in client.backlog)


async def test_rosapi_2_1_dies_on_get_param_names(make_sim: MakeSim) -> None:
    """The call that kills rosapi 2.1.0 gets no answer, and every rosapi service is gone afterwards."""
    robot = await make_sim(dialect="ros2", rosapi="2.1.0")
    robot.rosapi_node.param_node_wait = 0.05
    async with await RawClient.open(robot.url) as client:
        await _send_unanswered(client, "/rosapi/get_param_names", {}, "killer")
        await robot.wait_for(lambda _: robot.rosapi_node.dead, timeout=2.0)
        topics = await client.call("/rosapi/topics")
        total = await client.values("/add_two_ints", {"a": 1, "b": 1})
        answered = _answered(client, "killer")
    assert topics["values"] == "Service /rosapi/topics does not exist"
    assert total == {"sum": 2}
    assert not answered
    assert "/rosapi" not in robot.graph.nodes


async def test_rosapi_2_1_dies_on_has_param_of_an_undeclared_parameter(make_sim: MakeSim) -> None:
    """As on the labs: has_param of a declared parameter answers; of an undeclared one it ends rosapi."""
    robot = await make_sim(dialect="ros2", rosapi="2.1.0")
    async with await RawClient.open(robot.url) as client:
        declared = await client.values("/rosapi/has_param", {"name": "/turtlesim:background_r"})
        await _send_unanswered(client, "/rosapi/has_param", {"name": "/turtlesim:nope"}, "killer")
        await robot.wait_for(lambda _: robot.rosapi_node.dead, timeout=2.0)
        topics = await client.call("/rosapi/topics")
        answered = _answered(client, "killer")
    assert declared == {"exists": True}
    assert topics["values"] == "Service /rosapi/topics does not exist"
    assert not answered


async def test_rosapi_2_1_hangs_for_good_on_a_parameter_of_rosapi_itself(make_sim: MakeSim) -> None:
    """get_param of /rosapi:use_sim_time deadlocks 2.1.0: no answer, nor to any later rosapi call."""
    robot = await make_sim(dialect="ros2", rosapi="2.1.0")
    async with await RawClient.open(robot.url) as client:
        await _send_unanswered(client, "/rosapi/get_param", {"name": "/rosapi:use_sim_time"}, "own")
        await robot.wait_for(lambda _: robot.rosapi_node.hung, timeout=2.0)
        await _send_unanswered(client, "/rosapi/topics", {}, "later")
        await robot.wait_for(lambda w: w.service_calls.get("/rosapi/topics", 0) == 1, timeout=2.0)
        total = await client.values("/add_two_ints", {"a": 1, "b": 1})
        answered = _answered(client, "own") or _answered(client, "later")
    assert total == {"sum": 2}
    assert not answered
    assert "/rosapi/topics" in robot.graph.services  # the process lives on


async def test_rosapi_2_1_dies_on_the_details_of_a_service_type_it_cannot_load(make_sim: MakeSim) -> None:
    """service_request_details of an unloadable type: no answer, rosapi gone; message_details just []."""
    robot = await make_sim(dialect="ros2", rosapi="2.1.0")
    async with await RawClient.open(robot.url) as client:
        unknown_msg = await client.values("/rosapi/message_details", {"type": "nope_msgs/msg/Nope"})
        args = {"type": "rospy_tutorials/AddTwoInts"}
        await _send_unanswered(client, "/rosapi/service_request_details", args, "killer")
        await robot.wait_for(lambda _: robot.rosapi_node.dead, timeout=2.0)
        nodes = await client.call("/rosapi/nodes")
        answered = _answered(client, "killer")
    assert unknown_msg == {"typedefs": []}
    assert nodes["values"] == "Service /rosapi/nodes does not exist"
    assert not answered


async def test_rosbridge_2_1_ignores_a_timeout_field(make_sim: MakeSim) -> None:
    """2.1.0's call_service has no timeout: a slow service answers after its time; the newest times out."""
    old = await make_sim(dialect="ros2", rosapi="2.1.0", slow_service_seconds=0.3)
    new = await make_sim(dialect="ros2", slow_service_seconds=0.3)
    async with await RawClient.open(old.url) as client:
        slow_old = await client.call("/slow_service", {}, timeout=0.05)
    async with await RawClient.open(new.url) as client:
        slow_new = await client.call("/slow_service", {}, timeout=0.05)
    assert slow_old["result"] is True
    assert slow_new["values"] == "Timeout exceeded while waiting for service response"


async def test_the_newest_rosapi_survives_what_kills_2_1(sim_ros2: SimulatedRobot) -> None:
    """The default rosapi answers get_param_names and keeps serving."""
    async with await RawClient.open(sim_ros2.url) as client:
        names = await client.values("/rosapi/get_param_names")
        topics = await client.values("/rosapi/topics")
    assert "/turtlesim:background_r" in names["names"]
    assert "/chatter" in topics["topics"]


@pytest.mark.parametrize(("distro", "in_order"), [("kilted", True), ("jazzy", True), ("humble", False)])
async def test_the_distro_is_what_get_ros_version_says_and_decides_type_descriptions(
    make_sim: MakeSim, distro: str, in_order: bool
) -> None:
    """2.1.0's in-order defaults on Kilted or Jazzy still have type descriptions; Humble's nodes do not."""
    robot = await make_sim(dialect="ros2", in_order=in_order, distro=distro)
    async with await RawClient.open(robot.url) as client:
        version = await client.values("/rosapi/get_ros_version")
        services = (await client.values("/rosapi/services"))["services"]
        listed = await client.values("/turtlesim/list_parameters", {})
    assert version == {"version": 2, "distro": distro}
    has_descriptions = distro != "humble"
    assert ("/turtlesim/get_type_description" in services) is has_descriptions
    assert ("start_type_description_service" in listed["result"]["names"]) is has_descriptions


async def test_ros2_nodes_have_six_parameter_services_and_rosapi_params_only_its_type_description(
    sim_ros2: SimulatedRobot,
) -> None:
    """As on the Jazzy and Kilted labs: 7 services per node; rosapi's helper node starts without the six."""
    async with await RawClient.open(sim_ros2.url) as client:
        services = (await client.values("/rosapi/services"))["services"]
        kind = await client.values("/rosapi/service_type", {"service": "/talker/set_parameters_atomically"})
    assert sorted(s for s in services if s.startswith("/talker/")) == [
        "/talker/describe_parameters",
        "/talker/get_parameter_types",
        "/talker/get_parameters",
        "/talker/get_type_description",
        "/talker/list_parameters",
        "/talker/set_parameters",
        "/talker/set_parameters_atomically",
    ]
    assert [s for s in services if s.startswith("/rosapi_params/")] == ["/rosapi_params/get_type_description"]
    assert kind["type"] == "rcl_interfaces/srv/SetParametersAtomically"


async def test_ros1_nodes_have_their_logger_services(sim_ros1: SimulatedRobot) -> None:
    """Every rospy node offers get_loggers and set_logger_level (roscpp types), /rosout and /rosapi too."""
    async with await RawClient.open(sim_ros1.url) as client:
        services = (await client.values("/rosapi/services"))["services"]
        kind = await client.values("/rosapi/service_type", {"service": "/rosout/get_loggers"})
    assert {"/talker/get_loggers", "/talker/set_logger_level", "/rosapi/get_loggers"} <= set(services)
    assert kind["type"] == "roscpp/GetLoggers"


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_node_services_can_be_left_out(make_sim: MakeSim, dialect: str) -> None:
    """node_services=False: a small graph with only the world's own services and rosapi's."""
    robot = await make_sim(dialect=dialect, node_services=False)
    async with await RawClient.open(robot.url) as client:
        services = (await client.values("/rosapi/services"))["services"]
    leaves = ("get_parameters", "get_type_description", "get_loggers", "set_logger_level")
    assert not [s for s in services if s.rsplit("/", 1)[-1] in leaves]
    assert "/add_two_ints" in services


@pytest.mark.parametrize(
    "kwargs",
    [
        {"dialect": "ros1", "rosapi": "2.1.0"},
        {"dialect": "ros1", "distro": "jazzy"},
        {"dialect": "ros2", "distro": "iron-ish"},
        {"dialect": "ros2", "rosapi": "1.0"},
        {"dialect": "ros2", "rosapi_latency": -1.0},
        {"dialect": "ros2", "rosapi_latency": (0.01, -0.01)},
    ],
)
def test_options_that_do_not_fit_the_dialect_are_refused(kwargs: dict[str, object]) -> None:
    """A ROS 2 setting on ROS 1, an unknown distro or release, a negative latency: ValueError at once."""
    with pytest.raises(ValueError, match=r"distro|rosapi"):
        SimulatedRobot(**kwargs)  # type: ignore[arg-type]
