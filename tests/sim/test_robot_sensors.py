"""The robot's sensors and state: /scan, /tf, latched /tf_static and /robot_description, a depth image,
and the parameters of their nodes, in both dialects."""

from __future__ import annotations

import base64
import json
import math
import struct
from typing import Any

import pytest
from rawclient import RawClient

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.world import TURTLE_ARENA, TURTLE_HOME


def param_name(robot: SimulatedRobot, node: str, name: str) -> str:
    """A parameter name in the robot's dialect (ROS 2 ``/node:name``, ROS 1 ``/node/name``)."""
    return f"{node}:{name}" if robot.dialect == "ros2" else f"{node}/{name}"


def seconds(stamp: dict[str, Any]) -> float:
    """A header stamp in either spelling, as seconds."""
    return stamp.get("sec", stamp.get("secs", 0)) + stamp.get("nanosec", stamp.get("nsecs", 0)) / 1e9


async def test_scan_sweeps_the_room_with_360_ranges_straight_ahead_at_index_180(sim: SimulatedRobot) -> None:
    """From its start the turtle looks along +x: the wall ahead is ARENA - HOME away; the mast is NaN."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/scan", "id": "scan"})
        scan = (await client.next_publish("/scan"))["msg"]
    ranges = scan["ranges"]
    assert len(ranges) == 360
    assert len(scan["intensities"]) == 360
    assert scan["angle_min"] == pytest.approx(-math.pi)
    assert scan["angle_increment"] == pytest.approx(2 * math.pi / 360)
    assert ranges[180] == pytest.approx(TURTLE_ARENA - TURTLE_HOME, abs=1e-3)
    assert ranges[90] == pytest.approx(TURTLE_HOME, abs=1e-3)  # the wall on the right (y = 0)
    assert ranges[0] is None  # NaN (the mast) travels as null
    assert scan["header"]["frame_id"] == "base_scan"
    assert sim.world.scans >= 1


async def test_scan_reports_beyond_range_max_as_null_and_range_max_is_a_parameter(
    sim: SimulatedRobot,
) -> None:
    """Setting the lidar's range_max below the wall's distance turns that reading into inf (null)."""
    async with await RawClient.open(sim.url) as client:
        await client.values(
            "/rosapi/set_param", {"name": param_name(sim, "/lidar", "range_max"), "value": "3.0"}
        )
        await client.send({"op": "subscribe", "topic": "/scan", "id": "scan"})
        scan = (await client.next_publish("/scan"))["msg"]
    assert scan["range_max"] == 3.0
    assert scan["ranges"][180] is None
    assert all(r is None or r <= 3.0 for r in scan["ranges"])


async def test_tf_follows_the_turtle_from_odom_to_base_link_at_20_hz(sim: SimulatedRobot) -> None:
    """odom -> base_link is the turtle's pose relative to its start; 6 messages' stamps rise, about 20 Hz."""
    sim.world.turtle.x, sim.world.turtle.theta = TURTLE_HOME + 1.5, math.pi / 2
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/tf", "id": "tf"})
        messages = [(await client.next_publish("/tf"))["msg"] for _ in range(6)]
    transform = messages[-1]["transforms"][0]
    assert transform["header"]["frame_id"] == "odom"
    assert transform["child_frame_id"] == "base_link"
    assert transform["transform"]["translation"]["x"] == pytest.approx(1.5)
    assert transform["transform"]["translation"]["y"] == pytest.approx(0.0, abs=1e-9)
    rotation = transform["transform"]["rotation"]
    assert (rotation["z"], rotation["w"]) == pytest.approx((math.sin(math.pi / 4), math.cos(math.pi / 4)))
    stamps = [seconds(m["transforms"][0]["header"]["stamp"]) for m in messages]
    assert stamps == sorted(set(stamps))
    # Five periods of a 20 Hz loop are 0.25 s; the bound is four times that, so a loaded machine's late ticks
    # still pass while a loop at a few hertz (1 s or more) would not.
    assert stamps[-1] - stamps[0] <= 1.0


async def test_tf_static_is_latched_a_new_subscriber_gets_it_at_once(sim: SimulatedRobot) -> None:
    """The static frames arrive before the reply to a request sent right after the subscribe."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/tf_static", "id": "static"})
        frames = await client.frames_before_barrier()
    (static,) = [f for f in frames if f.get("topic") == "/tf_static"]
    pairs = {
        (t["header"]["frame_id"], t["child_frame_id"]): t["transform"]["translation"]
        for t in static["msg"]["transforms"]
    }
    assert set(pairs) == {
        ("map", "world"),
        ("world", "odom"),
        ("base_link", "base_scan"),
        ("base_link", "camera"),
    }
    assert pairs[("map", "world")] == {"x": 0.0, "y": 0.0, "z": 0.0}
    assert pairs[("world", "odom")]["x"] == pytest.approx(TURTLE_HOME)


async def test_robot_description_is_a_latched_urdf(sim: SimulatedRobot) -> None:
    """/robot_description answers a late subscriber at once with a URDF naming the robot's links."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/robot_description", "id": "urdf"})
        frames = await client.frames_before_barrier()
    (description,) = [f for f in frames if f.get("topic") == "/robot_description"]
    urdf = description["msg"]["data"]
    assert urdf.startswith("<?xml")
    assert '<link name="base_scan"/>' in urdf
    assert '<child link="camera"/>' in urdf


async def test_a_topic_that_is_not_latched_sends_nothing_until_its_next_message(sim: SimulatedRobot) -> None:
    """/chatter (10 Hz, not latched) has no message waiting for a new subscriber: whatever arrives was
    published after the subscription (its count is higher than the world's when subscribing)."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/turtle1/color_sensor", "id": "color"})
        published_before = sim.world.chatter_count
        await client.send({"op": "subscribe", "topic": "/chatter", "id": "chatter"})
        frames = await client.frames_before_barrier()
    counts = [int(f["msg"]["data"].rsplit(" ", 1)[1]) for f in frames if f.get("topic") == "/chatter"]
    assert all(count > published_before for count in counts), (published_before, counts)


async def test_depth_image_is_16uc1_millimetres_of_the_wall_ahead_and_the_floor(sim: SimulatedRobot) -> None:
    """The centre pixel sees the wall ahead (planar depth from the camera 0.1 m ahead); the bottom row the
    floor, nearer."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/camera/depth/image_raw", "id": "depth"})
        image = (await client.next_publish("/camera/depth/image_raw"))["msg"]
    width, height = image["width"], image["height"]
    assert (image["encoding"], image["step"], image["is_bigendian"]) == ("16UC1", width * 2, 0)
    data = base64.b64decode(image["data"])
    assert len(data) == width * height * 2
    depth = struct.unpack(f"<{width * height}H", data)
    centre = depth[(height // 2) * width + width // 2]
    bottom = depth[(height - 1) * width + width // 2]
    assert centre == pytest.approx((TURTLE_ARENA - TURTLE_HOME - 0.1) * 1000, abs=30)
    assert 0 < bottom < centre
    assert image["header"]["frame_id"] == "camera"
    assert sim.world.depth_frames >= 1


async def test_the_new_nodes_show_their_publishers_in_node_details(sim: SimulatedRobot) -> None:
    """rosapi knows who publishes the new topics, with their types."""
    async with await RawClient.open(sim.url) as client:
        lidar = await client.values("/rosapi/node_details", {"node": "/lidar"})
        state = await client.values("/rosapi/node_details", {"node": "/robot_state_publisher"})
        odometry = await client.values("/rosapi/node_details", {"node": "/odometry"})
        camera = await client.values("/rosapi/node_details", {"node": "/camera"})
        topics = await client.values("/rosapi/topics")
    assert "/scan" in lidar["publishing"]
    assert {"/tf_static", "/robot_description"} <= set(state["publishing"])
    assert "/tf" in odometry["publishing"]
    assert "/camera/depth/image_raw" in camera["publishing"]
    types = dict(zip(topics["topics"], topics["types"], strict=True))
    ros2 = sim.dialect == "ros2"
    assert types["/scan"] == ("sensor_msgs/msg/LaserScan" if ros2 else "sensor_msgs/LaserScan")
    assert types["/tf"] == types["/tf_static"] == ("tf2_msgs/msg/TFMessage" if ros2 else "tf2_msgs/TFMessage")


async def test_message_details_describe_the_new_types(sim: SimulatedRobot) -> None:
    """TFMessage nests TransformStamped; LaserScan has its ranges as an unbounded float32 array."""
    ros2 = sim.dialect == "ros2"
    async with await RawClient.open(sim.url) as client:
        tf = await client.values(
            "/rosapi/message_details", {"type": "tf2_msgs/msg/TFMessage" if ros2 else "tf2_msgs/TFMessage"}
        )
        scan = await client.values(
            "/rosapi/message_details",
            {"type": "sensor_msgs/msg/LaserScan" if ros2 else "sensor_msgs/LaserScan"},
        )
    assert tf["typedefs"][0]["fieldtypes"] == ["geometry_msgs/TransformStamped"]
    assert "geometry_msgs/Quaternion" in [t["type"] for t in tf["typedefs"]]
    root = scan["typedefs"][0]
    ranges = root["fieldnames"].index("ranges")
    # ROS 2 rosapi names primitives in IDL spelling (float32 is "float").
    float32 = "float" if ros2 else "float32"
    assert (root["fieldtypes"][ranges], root["fieldarraylen"][ranges]) == (float32, 0)


async def test_ros1_robot_description_is_also_a_global_parameter(sim_ros1: SimulatedRobot) -> None:
    """ROS 1 launch files put the URDF on the parameter server as /robot_description."""
    async with await RawClient.open(sim_ros1.url) as client:
        value = await client.values("/rosapi/get_param", {"name": "/robot_description"})
    assert '<robot name="sim_turtle">' in json.loads(value["value"])


async def test_ros2_list_parameters_lists_a_nodes_parameters_in_declaration_order(
    sim_ros2: SimulatedRobot,
) -> None:
    """<node>/list_parameters answers from the same store as rosapi: use_sim_time first, as rclpy does."""
    async with await RawClient.open(sim_ros2.url) as client:
        listed = await client.values("/turtlesim/list_parameters", {"prefixes": [], "depth": 0})
        prefixed = await client.values("/turtlesim/list_parameters", {"prefixes": ["background"], "depth": 0})
        lidar = await client.values("/lidar/list_parameters", {})
    assert listed["result"]["names"] == [
        "use_sim_time",
        "start_type_description_service",
        "background_r",
        "background_g",
        "background_b",
    ]
    assert prefixed["result"] == {"names": [], "prefixes": []}  # a prefix matches whole dotted parts
    assert {"frame_id", "range_max"} <= set(lidar["result"]["names"])


async def test_ros2_get_parameters_answers_typed_values_or_nothing_for_an_unknown_name(
    sim_ros2: SimulatedRobot,
) -> None:
    """Values as ParameterValue messages; one undeclared name empties the whole answer, as rclpy does."""
    async with await RawClient.open(sim_ros2.url) as client:
        values = await client.values("/turtlesim/get_parameters", {"names": ["background_r", "use_sim_time"]})
        unknown = await client.values("/turtlesim/get_parameters", {"names": ["background_r", "nope"]})
        types = await client.values(
            "/turtlesim/get_parameter_types", {"names": ["background_r", "use_sim_time"]}
        )
        description = await client.values("/turtlesim/describe_parameters", {"names": ["background_r"]})
    first, second = values["values"]
    assert (first["type"], first["integer_value"]) == (2, 69)
    assert (second["type"], second["bool_value"]) == (1, False)
    assert unknown["values"] == []
    assert base64.b64decode(types["types"]) == bytes([2, 1])
    assert description["descriptors"][0]["name"] == "background_r"
    assert description["descriptors"][0]["type"] == 2


async def test_ros2_set_parameters_changes_the_value_rosapi_reads_and_refuses_another_type(
    sim_ros2: SimulatedRobot,
) -> None:
    """set_parameters with the right type takes effect; another type or an undeclared name is refused."""
    async with await RawClient.open(sim_ros2.url) as client:
        ok = await client.values(
            "/turtlesim/set_parameters",
            {"parameters": [{"name": "background_r", "value": {"type": 2, "integer_value": 10}}]},
        )
        wrong = await client.values(
            "/turtlesim/set_parameters",
            {"parameters": [{"name": "background_g", "value": {"type": 4, "string_value": "x"}}]},
        )
        undeclared = await client.values(
            "/turtlesim/set_parameters_atomically",
            {"parameters": [{"name": "nope", "value": {"type": 2, "integer_value": 1}}]},
        )
        read = await client.values("/rosapi/get_param", {"name": "/turtlesim:background_r"})
    assert ok["results"] == [{"successful": True, "reason": ""}]
    assert wrong["results"] == [{"successful": False, "reason": "Wrong parameter type, expected '2' got '4'"}]
    assert undeclared["result"]["successful"] is False
    assert read["value"] == "10"
    assert sim_ros2.world.params["/turtlesim:background_g"] == 86
