"""The simulated world: every command has an effect a client can observe, and rosapi describes it all."""

from __future__ import annotations

import base64
import json
import struct
import zlib

import pytest
from rawclient import MakeSim, RawClient

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.png import encode_png
from rosbridge_mcp_server.sim.world import TURTLE_HOME


def ros_type(robot: SimulatedRobot, pkg: str, kind: str, name: str) -> str:
    """A type name in the robot's dialect."""
    return f"{pkg}/{kind}/{name}" if robot.dialect == "ros2" else f"{pkg}/{name}"


async def test_cmd_vel_moves_the_turtle_and_the_pose_topic_shows_it(sim: SimulatedRobot) -> None:
    """A Twist on /turtle1/cmd_vel moves the turtle forward; /turtle1/pose reports the motion."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/turtle1/pose", "id": "pose"})
        await client.send({"op": "publish", "topic": "/turtle1/cmd_vel", "msg": {"linear": {"x": 2.0}}})
        while True:
            pose = (await client.next_publish("/turtle1/pose"))["msg"]
            if pose["x"] > TURTLE_HOME + 0.1:
                break
    assert pose["linear_velocity"] == 2.0
    assert pose["y"] == pytest.approx(TURTLE_HOME)
    assert sim.world.published["/turtle1/cmd_vel"][-1].msg["linear"]["x"] == 2.0


async def test_a_velocity_command_holds_about_a_second_then_the_turtle_stops(sim: SimulatedRobot) -> None:
    """Like a diff-drive's command timeout: the turtle stops on its own after ~1 s without commands."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "publish", "topic": "/turtle1/cmd_vel", "msg": {"angular": {"z": 1.0}}})
        await sim.wait_for(lambda w: w.turtle.angular == 1.0)
        await sim.wait_for(lambda w: w.turtle.angular == 0.0, timeout=15.0)
    turned = sim.world.turtle.theta
    assert 0.7 < turned < 2.0  # ~1 rad; generous above for a loaded machine


async def test_set_enabled_false_makes_the_turtle_ignore_commands(sim: SimulatedRobot) -> None:
    """/set_enabled (SetBool) false: cmd_vel still arrives but the turtle does not move."""
    async with await RawClient.open(sim.url) as client:
        reply = await client.values("/set_enabled", {"data": False})
        await client.send({"op": "publish", "topic": "/turtle1/cmd_vel", "msg": {"linear": {"x": 1.0}}})
        await sim.wait_for(lambda w: "/turtle1/cmd_vel" in w.published)
        enabled_again = await client.values("/set_enabled", {"data": True})
    assert reply == {"success": True, "message": "robot disabled"}
    assert enabled_again["message"] == "robot enabled"
    assert sim.world.turtle.commands == 0


async def test_teleport_absolute_moves_the_turtle_at_once(sim: SimulatedRobot) -> None:
    """turtlesim's /turtle1/teleport_absolute sets the pose."""
    async with await RawClient.open(sim.url) as client:
        await client.values("/turtle1/teleport_absolute", {"x": 1.0, "y": 2.0, "theta": 0.5})
    assert (sim.world.turtle.x, sim.world.turtle.y, sim.world.turtle.theta) == (1.0, 2.0, 0.5)


async def test_chatter_says_hello_world_with_a_counter(sim: SimulatedRobot) -> None:
    """/chatter carries std_msgs String 'Hello World: N', N counting up."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/chatter"})
        first = (await client.next_publish("/chatter"))["msg"]["data"]
        second = (await client.next_publish("/chatter"))["msg"]["data"]
    assert int(second.split(": ")[1]) == int(first.split(": ")[1]) + 1


async def test_fast_counter_counts_up_by_one_per_message(make_sim: MakeSim) -> None:
    """/fast_counter (only with fast_topic) numbers its messages consecutively, so losses can be counted."""
    robot = await make_sim(dialect="ros2", fast_topic=True)
    async with await RawClient.open(robot.url) as client:
        await client.send({"op": "subscribe", "topic": "/fast_counter"})
        values = [(await client.next_publish("/fast_counter"))["msg"]["data"] for _ in range(50)]
    assert values == list(range(values[0], values[0] + 50))


async def test_fast_counter_is_off_by_default(sim: SimulatedRobot) -> None:
    """Without fast_topic, /fast_counter is not in the graph."""
    async with await RawClient.open(sim.url) as client:
        topics = await client.values("/rosapi/topics")
    assert "/fast_counter" not in topics["topics"]


async def test_camera_publishes_rgb8_frames_that_change_over_time(sim: SimulatedRobot) -> None:
    """/camera/image_raw: 160x120 rgb8, data base64 of width*height*3 bytes, different from frame to frame."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/camera/image_raw"})
        first = (await client.next_publish("/camera/image_raw"))["msg"]
        second = (await client.next_publish("/camera/image_raw"))["msg"]
    assert (first["width"], first["height"], first["encoding"], first["step"]) == (160, 120, "rgb8", 480)
    pixels = base64.b64decode(first["data"])
    assert len(pixels) == 160 * 120 * 3
    assert pixels != base64.b64decode(second["data"])
    assert first["header"]["frame_id"] == "camera"


async def test_compressed_camera_frames_are_valid_png(sim: SimulatedRobot) -> None:
    """/camera/image_raw/compressed: format png, data a PNG whose IHDR says 160x120 RGB."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/camera/image_raw/compressed"})
        message = (await client.next_publish("/camera/image_raw/compressed"))["msg"]
    png = base64.b64decode(message["data"])
    assert message["format"] == "png"
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert struct.unpack(">II", png[16:24]) == (160, 120)


async def test_camera_paints_with_turtlesims_background_parameter(sim: SimulatedRobot) -> None:
    """Setting the background colour through rosapi changes the camera's pixels."""
    sep = ":" if sim.dialect == "ros2" else "/"
    async with await RawClient.open(sim.url) as client:
        await client.values("/rosapi/set_param", {"name": f"/turtlesim{sep}background_r", "value": "10"})
        await client.values("/rosapi/set_param", {"name": f"/turtlesim{sep}background_g", "value": "20"})
        await client.values("/rosapi/set_param", {"name": f"/turtlesim{sep}background_b", "value": "30"})
        await client.send({"op": "subscribe", "topic": "/camera/image_raw"})
        message = (await client.next_publish("/camera/image_raw"))["msg"]
    pixels = base64.b64decode(message["data"])
    assert (10, 20, 30) in {tuple(pixels[i : i + 3]) for i in range(0, len(pixels), 3)}


def test_png_encoder_round_trips_pixels_through_zlib() -> None:
    """encode_png writes IHDR/IDAT/IEND whose filtered rows decompress to the input pixels."""
    pixels = bytes(range(2 * 3 * 3)) * 1
    png = encode_png(3, 2, pixels[: 3 * 2 * 3])
    idat_len = struct.unpack(">I", png[33:37])[0]
    raw = zlib.decompress(png[41 : 41 + idat_len])
    assert raw == b"\x00" + pixels[:9] + b"\x00" + pixels[9:18]
    assert png.endswith(b"IEND\xaeB`\x82")


@pytest.mark.parametrize(
    ("dialect", "expected_types"),
    [
        # ROS 2: pkg/msg/Type names, /rosout and /parameter_events listed too.
        pytest.param(
            "ros2",
            {
                "/turtle1/cmd_vel": "geometry_msgs/msg/Twist",
                "/turtle1/pose": "turtlesim/msg/Pose",
                "/rosout": "rcl_interfaces/msg/Log",
                "/parameter_events": "rcl_interfaces/msg/ParameterEvent",
            },
            id="ros2",
        ),
        # ROS 1: pkg/Type names and the /fibonacci actionlib topics.
        pytest.param(
            "ros1",
            {
                "/turtle1/cmd_vel": "geometry_msgs/Twist",
                "/fibonacci/goal": "actionlib_tutorials/FibonacciActionGoal",
                "/fibonacci/status": "actionlib_msgs/GoalStatusArray",
            },
            id="ros1",
        ),
    ],
)
async def test_rosapi_topics_spell_types_as_the_dialect_does(
    make_sim: MakeSim, dialect: str, expected_types: dict[str, str]
) -> None:
    """/rosapi/topics pairs each topic with its type in the dialect's spelling, hiding nothing public."""
    robot = await make_sim(dialect=dialect)
    async with await RawClient.open(robot.url) as client:
        topics = await client.values("/rosapi/topics")
    pairs = dict(zip(topics["topics"], topics["types"], strict=True))
    assert {topic: pairs.get(topic) for topic in expected_types} == expected_types


async def test_service_providers_matches_service_types_not_names(sim: SimulatedRobot) -> None:
    """rosapi quirk (all versions): service_providers compares its argument with service *types*."""
    add = ros_type(
        sim, "example_interfaces" if sim.dialect == "ros2" else "rospy_tutorials", "srv", "AddTwoInts"
    )
    async with await RawClient.open(sim.url) as client:
        by_name = await client.values("/rosapi/service_providers", {"service": "/add_two_ints"})
        by_type = await client.values("/rosapi/service_providers", {"service": add})
        service_type = await client.values("/rosapi/service_type", {"service": "/add_two_ints"})
    assert by_name["providers"] == []
    assert by_type["providers"] == ["/add_two_ints_server"]
    assert service_type["type"] == add


async def test_client_topics_show_as_the_rosbridge_nodes_publishers_and_subscribers(
    sim: SimulatedRobot,
) -> None:
    """A client's advertise and subscribe appear as /rosbridge_websocket in the graph."""
    async with await RawClient.open(sim.url) as client:
        await client.send(
            {
                "op": "advertise",
                "topic": "/turtle1/cmd_vel",
                "type": ros_type(sim, "geometry_msgs", "msg", "Twist"),
            }
        )
        await client.send({"op": "subscribe", "topic": "/turtle1/pose"})
        await client.frames_before_barrier()
        publishers = await client.values("/rosapi/publishers", {"topic": "/turtle1/cmd_vel"})
        subscribers = await client.values("/rosapi/subscribers", {"topic": "/turtle1/pose"})
        details = await client.values("/rosapi/node_details", {"node": "/rosbridge_websocket"})
    assert publishers["publishers"] == ["/rosbridge_websocket"]
    assert subscribers["subscribers"] == ["/rosbridge_websocket"]
    assert "/turtle1/cmd_vel" in details["publishing"]
    assert "/turtle1/pose" in details["subscribing"]


async def test_node_details_of_turtlesim_lists_its_topics_and_services(sim: SimulatedRobot) -> None:
    """node_details names what a world node publishes, subscribes and serves."""
    async with await RawClient.open(sim.url) as client:
        nodes = await client.values("/rosapi/nodes")
        details = await client.values("/rosapi/node_details", {"node": "/turtlesim"})
    assert {"/turtlesim", "/talker", "/rosapi", "/rosbridge_websocket", "/fibonacci_server"} <= set(
        nodes["nodes"]
    )
    assert "/turtle1/pose" in details["publishing"]
    assert "/turtle1/cmd_vel" in details["subscribing"]
    assert "/reset" in details["services"]


async def test_message_details_describes_a_type_root_first(sim: SimulatedRobot) -> None:
    """message_details of Twist: the Twist TypeDef first, then Vector3."""
    async with await RawClient.open(sim.url) as client:
        details = await client.values(
            "/rosapi/message_details", {"type": ros_type(sim, "geometry_msgs", "msg", "Twist")}
        )
    typedefs = details["typedefs"]
    assert typedefs[0]["fieldnames"] == ["linear", "angular"]
    assert typedefs[1]["type"] == "geometry_msgs/Vector3"


async def test_ros2_parameters_use_node_colon_param_names(sim_ros2: SimulatedRobot) -> None:
    """get/set/has/delete/names with '/node:param' names; values are JSON text."""
    async with await RawClient.open(sim_ros2.url) as client:
        names = await client.values("/rosapi/get_param_names")
        value = await client.values("/rosapi/get_param", {"name": "/turtlesim:background_r"})
        await client.values("/rosapi/set_param", {"name": "/turtlesim:pen_width", "value": "3"})
        exists = await client.values("/rosapi/has_param", {"name": "/turtlesim:pen_width"})
        await client.values("/rosapi/delete_param", {"name": "/turtlesim:pen_width"})
        gone = await client.values("/rosapi/has_param", {"name": "/turtlesim:pen_width"})
        missing = await client.values("/rosapi/get_param", {"name": "/turtlesim:nope", "default_value": "7"})
    assert "/turtlesim:background_r" in names["names"]
    assert value["value"] == "69"
    assert exists["exists"] is True
    assert gone["exists"] is False
    assert missing["value"] == "7"
    assert sim_ros2.world.params["/turtlesim:background_r"] == 69


async def test_ros2_set_param_refuses_a_value_of_another_type(sim_ros2: SimulatedRobot) -> None:
    """ROS 2 parameters are typed: a string for an integer parameter leaves it unchanged."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.values("/rosapi/set_param", {"name": "/turtlesim:background_r", "value": '"red"'})
        value = await client.values("/rosapi/get_param", {"name": "/turtlesim:background_r"})
    assert value["value"] == "69"


async def test_humble_delete_param_is_broken_and_never_answers(make_sim: MakeSim) -> None:
    """Humble 2.0.x rosapi delete_param fails inside the service: with a timeout field the call times out."""
    robot = await make_sim(dialect="ros2", in_order=True)
    async with await RawClient.open(robot.url) as client:
        reply = await client.call("/rosapi/delete_param", {"name": "/turtlesim:background_r"}, timeout=0.2)
    assert reply["values"] == "Timeout exceeded while waiting for service response"


async def test_ros1_parameters_are_global_names_with_namespaces(sim_ros1: SimulatedRobot) -> None:
    """ROS 1: /turtlesim/background_r, a namespace reads as a dict, a missing name reads 'null'."""
    async with await RawClient.open(sim_ros1.url) as client:
        value = await client.values("/rosapi/get_param", {"name": "/turtlesim/background_g"})
        namespace = await client.values("/rosapi/get_param", {"name": "/turtlesim"})
        missing = await client.values("/rosapi/get_param", {"name": "/nope"})
        with_default = await client.values("/rosapi/get_param", {"name": "/nope", "default": "[1, 2]"})
        found = await client.values("/rosapi/search_param", {"name": "turtlesim"})
        await client.values("/rosapi/set_param", {"name": "/robot/max_speed", "value": "1.5"})
        names = await client.values("/rosapi/get_param_names")
        host = await client.values("/rosapi/service_host", {"service": "/add_two_ints"})
    assert value["value"] == "86"
    assert json.loads(namespace["value"]) == {"background_r": 69, "background_g": 86, "background_b": 255}
    assert missing["value"] == "null"
    assert json.loads(with_default["value"]) == [1, 2]
    assert found["global_name"] == "/turtlesim"
    assert "/robot/max_speed" in names["names"]
    assert host["host"] == "localhost"


async def test_ros1_set_param_with_a_non_json_value_fails_with_rosapis_text(sim_ros1: SimulatedRobot) -> None:
    """rosapi raises for a value that is not JSON; rospy reports it as the service's error."""
    async with await RawClient.open(sim_ros1.url) as client:
        reply = await client.call("/rosapi/set_param", {"name": "/x", "value": "not json"})
    assert reply["result"] is False
    assert "must be a JSON-formatted string" in reply["values"]


async def test_ros2_node_details_of_an_unknown_node_gets_no_answer(sim_ros2: SimulatedRobot) -> None:
    """ROS 2 rosapi fails inside the callback for an unknown node; rosbridge's timeout ends the call."""
    async with await RawClient.open(sim_ros2.url) as client:
        reply = await client.call("/rosapi/node_details", {"node": "/ghost"}, timeout=0.2)
    assert reply["values"] == "Timeout exceeded while waiting for service response"


async def test_ros2_interfaces_and_action_details_describe_fibonacci(sim_ros2: SimulatedRobot) -> None:
    """interfaces lists installed types; action_goal_details gives the goal's TypeDef."""
    async with await RawClient.open(sim_ros2.url) as client:
        interfaces = await client.values("/rosapi/interfaces")
        goal = await client.values(
            "/rosapi/action_goal_details", {"type": "example_interfaces/action/Fibonacci"}
        )
    assert "example_interfaces/action/Fibonacci" in interfaces["interfaces"]
    assert goal["typedefs"][0]["fieldnames"] == ["order"]


async def test_camera_messages_are_complete_and_in_wire_form(sim: SimulatedRobot) -> None:
    """The camera skips inbound conversion for speed, so its messages must already be complete wire form."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/camera/image_raw"})
        await client.send({"op": "subscribe", "topic": "/camera/image_raw/compressed"})
        raw = (await client.next_publish("/camera/image_raw"))["msg"]
        compressed = (await client.next_publish("/camera/image_raw/compressed"))["msg"]
    registry = sim.registry
    for name, message in (("Image", raw), ("CompressedImage", compressed)):
        msg_type = ros_type(sim, "sensor_msgs", "msg", name)
        assert registry.to_json(msg_type, registry.from_json(msg_type, message)) == message


async def test_topics_and_raw_types_gives_full_definition_texts(sim: SimulatedRobot) -> None:
    """topics_and_raw_types: parallel lists, each topic's full definition text (nested types included)."""
    async with await RawClient.open(sim.url) as client:
        raw = await client.values("/rosapi/topics_and_raw_types")
    texts = dict(zip(raw["topics"], raw["typedefs_full_text"], strict=True))
    assert "Vector3" in texts["/turtle1/cmd_vel"]
    assert "float64 x" in texts["/turtle1/cmd_vel"]


async def test_service_details_describe_request_and_response(sim: SimulatedRobot) -> None:
    """service_request_details / service_response_details of AddTwoInts name a, b and sum."""
    add = "example_interfaces/srv/AddTwoInts" if sim.dialect == "ros2" else "rospy_tutorials/AddTwoInts"
    async with await RawClient.open(sim.url) as client:
        request = await client.values("/rosapi/service_request_details", {"type": add})
        response = await client.values("/rosapi/service_response_details", {"type": add})
    assert request["typedefs"][0]["fieldnames"] == ["a", "b"]
    assert response["typedefs"][0]["fieldnames"] == ["sum"]


async def test_ros1_details_of_an_unknown_type_fail_with_an_error_text(sim_ros1: SimulatedRobot) -> None:
    """ROS 1 rosapi raises for a type it cannot load; rospy reports it (result false)."""
    async with await RawClient.open(sim_ros1.url) as client:
        reply = await client.call("/rosapi/message_details", {"type": "no_pkg/Nothing"})
    assert reply["result"] is False
    assert reply["values"].startswith("service [/rosapi/message_details] responded with an error")


async def test_ros2_message_details_of_an_unknown_type_is_empty(sim_ros2: SimulatedRobot) -> None:
    """ROS 2 rosapi logs the import error and answers no typedefs."""
    async with await RawClient.open(sim_ros2.url) as client:
        details = await client.values("/rosapi/message_details", {"type": "no_pkg/msg/Nothing"})
    assert details["typedefs"] == []
