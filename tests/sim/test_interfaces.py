"""The simulated robot's interface registry answers like rosbridge's ros_loader, conversion and rosapi.

Expected values are written out from the rosbridge_suite sources (ROS 1 0.11.17, ROS 2 2.0.8-4.2.1), not
computed by the code under test.
"""

from __future__ import annotations

import base64
import math
from typing import Any

import pytest

from rosbridge_mcp_server.sim.interfaces import ConversionError, InterfaceError, InterfaceRegistry

NOW = 1234.5  # seconds; stamps become 1234 s + 500000000 ns
NOW_ROS1 = {"secs": 1234, "nsecs": 500_000_000}
NOW_ROS2 = {"sec": 1234, "nanosec": 500_000_000}
ZERO_ROS1 = {"secs": 0, "nsecs": 0}
ZERO_ROS2 = {"sec": 0, "nanosec": 0}


@pytest.fixture(scope="module")
def ros1() -> InterfaceRegistry:
    return InterfaceRegistry("ros1")


@pytest.fixture(scope="module")
def ros2() -> InterfaceRegistry:
    return InterfaceRegistry("ros2")


@pytest.fixture(scope="module", params=["ros1", "ros2"])
def registry(request: pytest.FixtureRequest) -> InterfaceRegistry:
    return InterfaceRegistry(request.param)


def conversion_error(registry: InterfaceRegistry, msg_type: str, value: Any) -> str:
    with pytest.raises(ConversionError) as caught:
        registry.from_json(msg_type, value, now=NOW)
    return str(caught.value)


def interface_error(registry: InterfaceRegistry, name: str, kind: Any) -> str:
    with pytest.raises(InterfaceError) as caught:
        registry.resolve(name, kind)
    return str(caught.value)


# --------------------------------------------------------------------------- resolution


@pytest.mark.parametrize(
    ("name", "kind", "canonical"),
    [
        ("std_msgs/msg/String", "msg", "std_msgs/msg/String"),
        ("std_msgs/String", "msg", "std_msgs/msg/String"),
        ("/geometry_msgs//Twist/", "msg", "geometry_msgs/msg/Twist"),
        ("std_srvs/SetBool", "srv", "std_srvs/srv/SetBool"),
        ("example_interfaces/srv/AddTwoInts", "srv", "example_interfaces/srv/AddTwoInts"),
        ("example_interfaces/Fibonacci", "action", "example_interfaces/action/Fibonacci"),
        ("std_msgs/foo/String", "msg", "std_msgs/msg/String"),
    ],
)
def test_ros2_resolves_short_and_full_names_to_the_full_form(
    ros2: InterfaceRegistry, name: str, kind: Any, canonical: str
) -> None:
    """ROS 2 takes pkg/Type and pkg/kind/Type (falling back to the kind's module), answers pkg/kind/Type."""
    assert ros2.resolve(name, kind) == canonical


def test_ros2_unknown_package_names_the_missing_python_module(ros2: InterfaceRegistry) -> None:
    """An uninstalled ROS 2 package fails like importlib does inside ros_loader."""
    assert interface_error(ros2, "bar/msg/Foo", "msg") == (
        "Unable to import bar.msg from package bar. Caused by: No module named 'bar'"
    )


def test_ros2_unknown_class_mirrors_ros_loader_text(ros2: InterfaceRegistry) -> None:
    """A missing class in a known ROS 2 package reports the attribute error (no colon after 'Caused by')."""
    assert interface_error(ros2, "std_msgs/msg/Foo", "msg") == (
        "Unable to import msg class Foo from package std_msgs. "
        "Caused by module 'std_msgs.msg' has no attribute 'Foo'"
    )


def test_ros2_package_without_the_kinds_module_fails_on_the_import(ros2: InterfaceRegistry) -> None:
    """std_srvs has no msg module, so asking it for a message fails at the import."""
    assert interface_error(ros2, "std_srvs/Empty", "msg") == (
        "Unable to import std_srvs.msg from package std_srvs. Caused by: No module named 'std_srvs.msg'"
    )


@pytest.mark.parametrize(("dialect", "name"), [("ros2", "String"), ("ros2", "a/b/c/D"), ("ros1", "String")])
def test_type_strings_of_the_wrong_shape_are_invalid(dialect: Any, name: str) -> None:
    """Names with too few or too many parts are rejected as invalid type strings."""
    registry = InterfaceRegistry(dialect)
    assert interface_error(registry, name, "msg") == f"{name} is not a valid type string"


def test_ros1_rejects_the_three_part_name(ros1: InterfaceRegistry) -> None:
    """ROS 1 knows only pkg/Type."""
    assert interface_error(ros1, "std_msgs/msg/String", "msg") == (
        "std_msgs/msg/String is not a valid type string"
    )
    assert ros1.resolve("std_msgs/String", "msg") == "std_msgs/String"


def test_ros1_unknown_package_fails_to_load_its_manifest(ros1: InterfaceRegistry) -> None:
    """ROS 1 rosbridge loads the package manifest first, so an unknown package names the ROS path."""
    assert interface_error(ros1, "bar/Foo", "msg") == (
        "Unable to load the manifest for package bar. Caused by: bar\nROS path [0]=/opt/ros/noetic/share"
    )


def test_ros1_unknown_class_and_missing_module_mirror_ros_loader(ros1: InterfaceRegistry) -> None:
    """ROS 1 reports a missing class and a package without the kind's module like its ros_loader."""
    assert interface_error(ros1, "std_msgs/Foo", "msg") == (
        "Unable to import msg class Foo from package std_msgs. "
        "Caused by module 'std_msgs.msg' has no attribute 'Foo'"
    )
    assert interface_error(ros1, "std_msgs/String", "srv") == (
        "Unable to import std_msgs.srv from package std_msgs. Caused by: No module named 'std_msgs.srv'"
    )


def test_ros2_feedback_message_resolves_but_other_action_parts_do_not(ros2: InterfaceRegistry) -> None:
    """Only X_FeedbackMessage is importable as a message (the _action/feedback topic type)."""
    assert ros2.resolve("example_interfaces/action/Fibonacci_FeedbackMessage", "msg") == (
        "example_interfaces/action/Fibonacci_FeedbackMessage"
    )
    assert not ros2.has("example_interfaces/action/Fibonacci_Goal", "msg")
    assert not ros2.has("example_interfaces/srv/AddTwoInts_Request", "msg")


def test_ros1_action_resolves_by_base_name_or_action_message(ros1: InterfaceRegistry) -> None:
    """A ROS 1 .action is found by its base name or its XAction message name."""
    assert ros1.resolve("actionlib_tutorials/Fibonacci", "action") == "actionlib_tutorials/Fibonacci"
    assert ros1.resolve("actionlib_tutorials/FibonacciAction", "action") == "actionlib_tutorials/Fibonacci"
    assert not ros1.has("actionlib_tutorials/Nope", "action")


def test_all_interfaces_lists_every_kind_in_canonical_form(
    ros2: InterfaceRegistry, ros1: InterfaceRegistry
) -> None:
    """ROS 2 lists pkg/msg|srv|action/X (rosapi interfaces); ROS 1 lists pkg/X."""
    names = ros2.all_interfaces()
    for expected in (
        "geometry_msgs/msg/Twist",
        "std_srvs/srv/Trigger",
        "example_interfaces/action/Fibonacci",
        "rosapi_msgs/srv/Interfaces",
        "action_msgs/srv/CancelGoal",
    ):
        assert expected in names
    assert "example_interfaces/action/Fibonacci_Goal" not in names
    assert names == sorted(names)
    assert "actionlib_tutorials/FibonacciActionGoal" in ros1.all_interfaces()
    assert all(name.count("/") == 1 for name in ros1.all_interfaces())


# --------------------------------------------------------------------------- rosapi TypeDefs


def test_ros2_twist_typedefs_match_rosapi(ros2: InterfaceRegistry) -> None:
    """ROS 2 Twist: pkg/Type names, IDL primitive names, and rclpy's pseudo-constants in constnames."""
    twist, vector = ros2.message_typedefs("geometry_msgs/msg/Twist")
    assert twist["type"] == "geometry_msgs/Twist"
    assert twist["fieldnames"] == ["linear", "angular"]
    assert twist["fieldtypes"] == ["geometry_msgs/Vector3", "geometry_msgs/Vector3"]
    assert twist["fieldarraylen"] == [-1, -1]
    assert twist["examples"] == ["{}", "{}"]
    assert twist["constnames"] == ["SLOT_TYPES", "angular", "linear"]
    assert twist["constvalues"][1:] == ["geometry_msgs.msg.Vector3(x=0.0, y=0.0, z=0.0)"] * 2
    assert twist["constvalues"][0].startswith("(<rosidl_parser.definition.NamespacedType object at 0x")
    assert vector["type"] == "geometry_msgs/Vector3"
    assert vector["fieldtypes"] == ["double", "double", "double"]
    assert vector["examples"] == ["0.0", "0.0", "0.0"]
    assert vector["constnames"] == ["SLOT_TYPES", "x", "y", "z"]


def test_ros1_twist_typedefs_match_rosapi(ros1: InterfaceRegistry) -> None:
    """ROS 1 Twist: genpy slot types and no constants."""
    assert ros1.message_typedefs("geometry_msgs/Twist") == [
        {
            "type": "geometry_msgs/Twist",
            "fieldnames": ["linear", "angular"],
            "fieldtypes": ["geometry_msgs/Vector3", "geometry_msgs/Vector3"],
            "fieldarraylen": [-1, -1],
            "examples": ["{}", "{}"],
            "constnames": [],
            "constvalues": [],
        },
        {
            "type": "geometry_msgs/Vector3",
            "fieldnames": ["x", "y", "z"],
            "fieldtypes": ["float64", "float64", "float64"],
            "fieldarraylen": [-1, -1, -1],
            "examples": ["0.0", "0.0", "0.0"],
            "constnames": [],
            "constvalues": [],
        },
    ]


def test_ros2_image_typedefs_follow_header_down_to_time(ros2: InterfaceRegistry) -> None:
    """ROS 2 Image lists Image, std_msgs/Header, builtin_interfaces/Time; uint8[] is 'uint8' with length 0."""
    image, header, stamp = ros2.message_typedefs("sensor_msgs/Image")
    assert [image["type"], header["type"], stamp["type"]] == [
        "sensor_msgs/Image",
        "std_msgs/Header",
        "builtin_interfaces/Time",
    ]
    assert image["fieldnames"] == ["header", "height", "width", "encoding", "is_bigendian", "step", "data"]
    assert image["fieldtypes"] == [
        "std_msgs/Header",
        "uint32",
        "uint32",
        "string",
        "uint8",
        "uint32",
        "uint8",
    ]
    assert image["fieldarraylen"] == [-1, -1, -1, -1, -1, -1, 0]
    assert image["examples"] == ["{}", "0", "0", "", "0", "0", "[]"]
    consts = dict(zip(image["constnames"], image["constvalues"], strict=True))
    assert consts["data"] == "array('B')"
    assert consts["header"] == (
        "std_msgs.msg.Header(stamp=builtin_interfaces.msg.Time(sec=0, nanosec=0), frame_id='')"
    )
    assert header["fieldtypes"] == ["builtin_interfaces/Time", "string"]
    assert stamp["fieldnames"] == ["sec", "nanosec"]
    assert stamp["fieldtypes"] == ["int32", "uint32"]


def test_ros1_image_typedefs_include_seq_and_the_mocked_time(ros1: InterfaceRegistry) -> None:
    """ROS 1 Header has seq, stamp is the primitive 'time', and rosapi mocks a 'time' TypeDef."""
    image, header, stamp = ros1.message_typedefs("sensor_msgs/Image")
    assert image["fieldtypes"] == [
        "std_msgs/Header",
        "uint32",
        "uint32",
        "string",
        "uint8",
        "uint32",
        "uint8",
    ]
    assert image["fieldarraylen"] == [-1, -1, -1, -1, -1, -1, 0]
    assert header == {
        "type": "std_msgs/Header",
        "fieldnames": ["seq", "stamp", "frame_id"],
        "fieldtypes": ["uint32", "time", "string"],
        "fieldarraylen": [-1, -1, -1],
        "examples": ["0", "{}", ""],
        "constnames": [],
        "constvalues": [],
    }
    assert stamp == {
        "type": "time",
        "fieldnames": ["secs", "nsecs"],
        "fieldtypes": ["int32", "int32"],
        "fieldarraylen": [-1, -1],
        "examples": ["0", "0"],
        "constnames": [],
        "constvalues": [],
    }


def test_ros2_constants_sort_among_pseudo_constants(ros2: InterfaceRegistry) -> None:
    """GoalStatus constants come sorted by name together with SLOT_TYPES and the field properties."""
    status = ros2.message_typedefs("action_msgs/msg/GoalStatus")[0]
    assert status["constnames"] == [
        "SLOT_TYPES",
        "STATUS_ABORTED",
        "STATUS_ACCEPTED",
        "STATUS_CANCELED",
        "STATUS_CANCELING",
        "STATUS_EXECUTING",
        "STATUS_SUCCEEDED",
        "STATUS_UNKNOWN",
        "goal_info",
        "status",
    ]
    assert status["constvalues"][1:8] == ["6", "1", "5", "3", "2", "4", "0"]


def test_ros2_defaults_and_fixed_arrays_print_like_rclpy(ros2: InterfaceRegistry) -> None:
    """Quaternion shows its W__DEFAULT and numpy-printed covariances wrap like numpy does."""
    quaternion = ros2.message_typedefs("geometry_msgs/msg/Quaternion")[0]
    assert quaternion["examples"] == ["0.0", "0.0", "0.0", "1.0"]
    consts = dict(zip(quaternion["constnames"], quaternion["constvalues"], strict=True))
    assert consts["W__DEFAULT"] == "1.0"
    assert consts["w"] == "1.0"
    pose = ros2.message_typedefs("geometry_msgs/msg/PoseWithCovariance")[0]
    assert pose["fieldtypes"] == ["geometry_msgs/Pose", "double"]
    assert pose["fieldarraylen"] == [-1, 36]
    covariance = dict(zip(pose["constnames"], pose["constvalues"], strict=True))["covariance"]
    assert covariance == "[" + " ".join(["0."] * 24) + "\n " + " ".join(["0."] * 12) + "]"


def test_ros1_constants_are_sorted_by_name(ros1: InterfaceRegistry) -> None:
    """ROS 1 constnames come from inspect.getmembers, so alphabetically."""
    status = ros1.message_typedefs("actionlib_msgs/GoalStatus")[0]
    assert status["constnames"] == [
        "ABORTED",
        "ACTIVE",
        "LOST",
        "PENDING",
        "PREEMPTED",
        "PREEMPTING",
        "RECALLED",
        "RECALLING",
        "REJECTED",
        "SUCCEEDED",
    ]
    assert status["constvalues"] == ["4", "1", "9", "0", "2", "6", "8", "7", "5", "3"]
    assert status["fieldtypes"] == ["actionlib_msgs/GoalID", "uint8", "string"]


def test_service_and_action_typedefs_name_the_generated_parts(
    ros2: InterfaceRegistry, ros1: InterfaceRegistry
) -> None:
    """Request/response and goal/result/feedback TypeDefs carry the class names rclpy and genpy give them."""
    request = ros2.service_request_typedefs("example_interfaces/srv/AddTwoInts")
    assert [(t["type"], t["fieldnames"], t["fieldtypes"]) for t in request] == [
        ("example_interfaces/AddTwoInts_Request", ["a", "b"], ["int64", "int64"])
    ]
    response = ros1.service_response_typedefs("rospy_tutorials/AddTwoInts")
    assert [(t["type"], t["fieldnames"]) for t in response] == [
        ("rospy_tutorials/AddTwoIntsResponse", ["sum"])
    ]
    goal = ros2.action_goal_typedefs("example_interfaces/action/Fibonacci")
    result = ros2.action_result_typedefs("example_interfaces/action/Fibonacci")
    feedback = ros2.action_feedback_typedefs("example_interfaces/action/Fibonacci")
    assert goal[0]["type"] == "example_interfaces/Fibonacci_Goal"
    assert goal[0]["fieldtypes"] == ["int32"]
    assert result[0]["fieldnames"] == ["sequence"]
    assert result[0]["fieldarraylen"] == [0]
    assert feedback[0]["type"] == "example_interfaces/Fibonacci_Feedback"


def test_unknown_types_give_no_typedefs_on_ros2_and_fail_on_ros1(
    ros2: InterfaceRegistry, ros1: InterfaceRegistry
) -> None:
    """rosapi 2.x logs and answers nothing for an unknown type; rosapi 0.11 lets the loader error through."""
    assert ros2.message_typedefs("nope_msgs/msg/Nope") == []
    assert ros2.service_request_typedefs("nope_msgs/srv/Nope") == []
    with pytest.raises(InterfaceError):
        ros1.message_typedefs("nope_msgs/Nope")


def test_ros1_char_field_gets_the_python_class_as_type(ros1: InterfaceRegistry) -> None:
    """rosapi 0.11 lacks a 'char' atomic, names it after the Python int, then fails to load 'builtin/int'."""
    with pytest.raises(InterfaceError, match="package builtin"):
        ros1.message_typedefs("std_msgs/Char")


# --------------------------------------------------------------------------- full text


def test_full_text_appends_each_nested_definition_once(registry: InterfaceRegistry) -> None:
    """topics_and_raw_types text: the root, then every nested type once after an 80 '=' separator."""
    name = "geometry_msgs/msg/Twist" if registry.dialect == "ros2" else "geometry_msgs/Twist"
    text = registry.full_text(name)
    assert text.startswith("Vector3 linear\nVector3 angular\n")
    assert text.count("MSG: geometry_msgs/Vector3\n") == 1
    assert f"\n{'=' * 80}\nMSG: geometry_msgs/Vector3\nfloat64 x\n" in text


def test_full_text_follows_the_stamp_only_on_ros2(ros2: InterfaceRegistry, ros1: InterfaceRegistry) -> None:
    """ROS 2 headers nest builtin_interfaces/Time; ROS 1 time is a primitive."""
    assert "MSG: builtin_interfaces/Time\n" in ros2.full_text("geometry_msgs/msg/PoseStamped")
    ros1_text = ros1.full_text("geometry_msgs/PoseStamped")
    assert "MSG: std_msgs/Header\nuint32 seq\ntime stamp\n" in ros1_text
    assert "builtin_interfaces" not in ros1_text


def test_ros2_full_text_takes_nested_types_last_pushed_first(ros2: InterfaceRegistry) -> None:
    """rosapi's stringify_field_types pops a stack: the last field's type of the root comes next."""
    text = ros2.full_text("geometry_msgs/msg/PoseStamped")
    order = [line[len("MSG: ") :] for line in text.split("\n") if line.startswith("MSG: ")]
    assert order == [
        "geometry_msgs/Pose",
        "geometry_msgs/Quaternion",
        "geometry_msgs/Point",
        "std_msgs/Header",
        "builtin_interfaces/Time",
    ]


def test_ros1_full_text_takes_dependencies_depth_first(ros1: InterfaceRegistry) -> None:
    """genpy's _full_text lists dependencies depth first in field order."""
    text = ros1.full_text("geometry_msgs/PoseStamped")
    order = [line[len("MSG: ") :] for line in text.split("\n") if line.startswith("MSG: ")]
    assert order == [
        "std_msgs/Header",
        "geometry_msgs/Pose",
        "geometry_msgs/Point",
        "geometry_msgs/Quaternion",
    ]


def test_registry_clock_stamps_when_no_time_is_given() -> None:
    """Without an explicit now, header stamps come from the registry's clock."""
    registry = InterfaceRegistry("ros2", clock=lambda: 7.25)
    assert registry.from_json("geometry_msgs/PoseStamped", {})["header"]["stamp"] == {
        "sec": 7,
        "nanosec": 250_000_000,
    }


# --------------------------------------------------------------------------- inbound conversion


def test_missing_fields_take_defaults(registry: InterfaceRegistry) -> None:
    """Fields the JSON omits get their defaults; given ints for floats come back as floats."""
    twist = registry.from_json("geometry_msgs/Twist", {"linear": {"x": 1}})
    assert twist == {"linear": {"x": 1.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
    assert isinstance(twist["linear"]["x"], float)


def test_unknown_field_names_the_dotted_path(registry: InterfaceRegistry) -> None:
    """An unknown key anywhere rejects the whole message."""
    assert conversion_error(registry, "geometry_msgs/Twist", {"linear": {"w": 1.0}}) == (
        "Message type geometry_msgs/Twist does not have a field linear.w"
    )


@pytest.mark.parametrize(
    ("value", "found"),
    [(True, "bool"), (1.5, "float"), ("3", "str")],
)
def test_wrong_json_type_for_an_integer_is_rejected(
    registry: InterfaceRegistry, value: Any, found: str
) -> None:
    """Integer fields take JSON integers only: no bool, no float, no string."""
    assert conversion_error(registry, "std_msgs/Int32", {"data": value}) == (
        f"std_msgs/Int32 message requires a int32 for field data, but got a <class '{found}'>"
    )


def test_ints_are_rejected_for_bools(registry: InterfaceRegistry) -> None:
    """Bool fields take true/false only."""
    expected = "bool" if registry.dialect == "ros1" else "boolean"
    assert conversion_error(registry, "std_msgs/Bool", {"data": 1}) == (
        f"std_msgs/Bool message requires a {expected} for field data, but got a <class 'int'>"
    )


def test_bools_for_floats_are_a_ros2_only_quirk(ros2: InterfaceRegistry, ros1: InterfaceRegistry) -> None:
    """ROS 2 casts every int, bools included, to float; ROS 1 rejects the bool."""
    assert ros2.from_json("std_msgs/Float64", {"data": True}) == {"data": 1.0}
    assert conversion_error(ros1, "std_msgs/Float64", {"data": True}) == (
        "std_msgs/Float64 message requires a float64 for field data, but got a <class 'bool'>"
    )


def test_null_for_a_primitive_is_rejected(ros2: InterfaceRegistry, ros1: InterfaceRegistry) -> None:
    """null never fits a primitive; the texts differ by dialect."""
    assert conversion_error(ros1, "geometry_msgs/Twist", {"linear": {"x": None}}) == (
        "geometry_msgs/Twist message requires a float64 for field linear.x, but got a <class 'NoneType'>"
    )
    assert conversion_error(ros2, "geometry_msgs/Twist", {"linear": {"x": None}}) == (
        "msg is not a primitive type, but a <class 'NoneType'>"
    )
    assert conversion_error(ros2, "geometry_msgs/Twist", {"linear": {"x": "fast"}}) == (
        "geometry_msgs/Twist message requires a double for field linear.x, but got a <class 'str'>"
    )


def test_non_objects_for_messages_are_rejected(ros2: InterfaceRegistry, ros1: InterfaceRegistry) -> None:
    """A nested message needs an object, and so does the root."""
    assert conversion_error(ros1, "geometry_msgs/Twist", {"linear": 3}) == (
        "geometry_msgs/Twist message requires a geometry_msgs/Vector3 for field linear, "
        "but got a <class 'int'>"
    )
    assert (
        conversion_error(ros2, "geometry_msgs/Twist", {"linear": 3})
        == "msg is not a dict, but a <class 'int'>"
    )
    for registry in (ros1, ros2):
        assert conversion_error(registry, "geometry_msgs/Twist", [1, 2]) == (
            "Expected a JSON object for type geometry_msgs/Twist but received a <class 'list'>"
        )


def test_non_lists_for_arrays_are_rejected(ros2: InterfaceRegistry, ros1: InterfaceRegistry) -> None:
    """Array fields need JSON arrays."""
    assert conversion_error(ros1, "sensor_msgs/JointState", {"position": {"a": 1}}) == (
        "sensor_msgs/JointState message requires a float64[] for field position, but got a <class 'dict'>"
    )
    assert conversion_error(ros2, "sensor_msgs/JointState", {"position": 1.0}) == (
        "msg is not a list type, but a <class 'float'>"
    )


def test_wrong_fixed_array_length_is_rejected(ros2: InterfaceRegistry, ros1: InterfaceRegistry) -> None:
    """Fixed-size arrays fail on length: numpy's text on ROS 2, struct.pack's on ROS 1 serialization."""
    value = {"covariance": [0.0] * 5}
    assert conversion_error(ros2, "geometry_msgs/PoseWithCovariance", value) == (
        "could not broadcast input array from shape (5,) into shape (36,)"
    )
    assert conversion_error(ros1, "geometry_msgs/PoseWithCovariance", value) == (
        "<class 'struct.error'>: 'pack expected 36 items for packing (got 5)'"
    )
    accepted = ros2.from_json("geometry_msgs/PoseWithCovariance", {"covariance": list(range(36))})
    assert accepted["covariance"][35] == 35.0


def test_out_of_range_integers_are_rejected(ros2: InterfaceRegistry, ros1: InterfaceRegistry) -> None:
    """rclpy's setter (ROS 2) and genpy's check_type (ROS 1) refuse integers that do not fit."""
    assert conversion_error(ros2, "std_msgs/Int8", {"data": 200}) == (
        "The 'data' field must be an integer in [-128, 127]"
    )
    assert conversion_error(ros2, "std_msgs/UInt16", {"data": -1}) == (
        "The 'data' field must be an unsigned integer in [0, 65535]"
    )
    assert (
        conversion_error(ros1, "std_msgs/Int8", {"data": 200}) == "field data exceeds specified width [int8]"
    )
    assert (
        conversion_error(ros1, "std_msgs/UInt16", {"data": -1}) == "field data must be unsigned integer type"
    )


def test_ros2_numeric_sequences_fail_like_python_arrays(ros2: InterfaceRegistry) -> None:
    """ROS 2 extends an array.array, so element errors are Python's own."""
    assert conversion_error(ros2, "std_msgs/Int32MultiArray", {"data": [1, 2.5]}) == (
        "'float' object cannot be interpreted as an integer"
    )
    assert ros2.from_json("std_msgs/Float32MultiArray", {"data": [1, 2.5]})["data"] == [1.0, 2.5]


def test_byte_arrays_accept_base64_or_int_lists_and_return_base64(registry: InterfaceRegistry) -> None:
    """uint8[] takes a base64 string or a list of ints and normalizes to base64."""
    from_list = registry.from_json("sensor_msgs/Image", {"data": [1, 2, 255]})
    from_text = registry.from_json("sensor_msgs/Image", {"data": base64.b64encode(b"\x01\x02\xff").decode()})
    assert from_list["data"] == from_text["data"] == "AQL/"


def test_bad_byte_arrays_are_rejected(ros2: InterfaceRegistry, ros1: InterfaceRegistry) -> None:
    """Broken base64 and out-of-range bytes fail; ROS 2 words it as the generated setter does."""
    for registry in (ros1, ros2):
        assert conversion_error(registry, "sensor_msgs/Image", {"data": "AQL"}) == "Incorrect padding"
    assert conversion_error(ros2, "sensor_msgs/Image", {"data": [1, 256]}) == (
        "The 'data' field must be a set or sequence and each value of type 'int' "
        "and each unsigned integer in [0, 255]"
    )
    assert conversion_error(ros2, "unique_identifier_msgs/UUID", {"uuid": [1, 2]}) == (
        "The 'uuid' field must be a set or sequence with length 16 and each value of type 'int' "
        "and each unsigned integer in [0, 255]"
    )
    assert conversion_error(ros1, "sensor_msgs/Image", {"data": [1, 256]}) == "byte must be in range(0, 256)"


@pytest.mark.parametrize("bad", [[1, 2.0], [1, None], [1, "2"], [-1], [2**70], [[1]]])
def test_ros2_byte_array_fast_path_rejects_what_the_setter_rejects(ros2: InterfaceRegistry, bad: Any) -> None:
    """Floats, None, strings, negative or huge numbers and nested lists in a uint8[] all fail alike."""
    assert conversion_error(ros2, "sensor_msgs/Image", {"data": bad}) == (
        "The 'data' field must be a set or sequence and each value of type 'int' "
        "and each unsigned integer in [0, 255]"
    )


def test_a_full_size_image_converts_from_a_list_or_base64(
    ros1: InterfaceRegistry, ros2: InterfaceRegistry
) -> None:
    """A 640x480 rgb8 image's data (921 600 bytes, bools count as ints) round-trips to the same base64."""
    pixels = bytes(range(256)) * 3600
    expected = base64.b64encode(pixels).decode()
    for registry, msg_type in ((ros1, "sensor_msgs/Image"), (ros2, "sensor_msgs/msg/Image")):
        from_list = registry.from_json(msg_type, {"data": list(pixels)})
        from_text = registry.from_json(msg_type, {"data": expected})
        assert from_list["data"] == from_text["data"] == expected
    assert ros2.from_json("sensor_msgs/msg/Image", {"data": [True, False, 2]})["data"] == "AQAC"


def test_ros1_reads_only_secs_and_nsecs(ros1: InterfaceRegistry) -> None:
    """ROS 1 ignores sec/nanosec silently, and a time that is not an object stays zero."""
    assert ros1.from_json("std_msgs/Time", {"data": {"sec": 5, "nanosec": 7}}) == {"data": ZERO_ROS1}
    assert ros1.from_json("std_msgs/Time", {"data": {"secs": 5, "nsecs": 7}}) == {
        "data": {"secs": 5, "nsecs": 7}
    }
    assert ros1.from_json("std_msgs/Time", {"data": 12}) == {"data": ZERO_ROS1}


def test_ros2_reads_either_time_spelling(ros2: InterfaceRegistry) -> None:
    """ROS 2 reads sec/nanosec and falls back to secs/nsecs."""
    for stamp in ({"sec": 5, "nanosec": 7}, {"secs": 5, "nsecs": 7}):
        result = ros2.from_json("rosgraph_msgs/Clock", {"clock": stamp})
        assert result == {"clock": {"sec": 5, "nanosec": 7}}


def test_ros2_time_rejects_other_json_types(ros2: InterfaceRegistry) -> None:
    """A ROS 2 time must be an object or the string "now" (Duration: no "now")."""
    assert conversion_error(ros2, "rosgraph_msgs/Clock", {"clock": 12}) == (
        "msg is not dict or str, but a <class 'int'>"
    )
    assert conversion_error(ros2, "action_msgs/msg/GoalInfo", {"stamp": "later"}) == (
        "Invalid string for builtin_interfaces/Time: later"
    )
    assert conversion_error(ros2, "rosgraph_msgs/Clock", {"clock": {"sec": 1.5}}) == (
        "The 'sec' field must be of type 'int'"
    )


def test_now_string_stamps_a_time(registry: InterfaceRegistry) -> None:
    """The string "now" becomes the current time in the dialect's spelling."""
    expected = NOW_ROS1 if registry.dialect == "ros1" else NOW_ROS2
    assert registry.from_json("rosgraph_msgs/Clock", {"clock": "now"}, now=NOW) == {"clock": expected}


def test_ros1_stamps_every_header_present_before_its_fields(ros1: InterfaceRegistry) -> None:
    """ROS 1 stamps each Header object given (nested ones too); an omitted header stays zero."""
    assert ros1.from_json("geometry_msgs/PoseStamped", {}, now=NOW)["header"]["stamp"] == ZERO_ROS1
    stamped = ros1.from_json("geometry_msgs/PoseStamped", {"header": {"frame_id": "map"}}, now=NOW)
    assert stamped["header"] == {"seq": 0, "stamp": NOW_ROS1, "frame_id": "map"}
    partial = ros1.from_json("geometry_msgs/PoseStamped", {"header": {"stamp": {"secs": 5}}}, now=NOW)
    assert partial["header"]["stamp"] == {"secs": 5, "nsecs": 500_000_000}
    path = ros1.from_json("nav_msgs/Path", {"poses": [{"header": {}}, {}]}, now=NOW)
    assert path["header"]["stamp"] == ZERO_ROS1
    assert [pose["header"]["stamp"] for pose in path["poses"]] == [NOW_ROS1, ZERO_ROS1]


def test_ros2_stamps_only_the_root_header_without_stamp(ros2: InterfaceRegistry) -> None:
    """ROS 2 stamps the root header when it or its stamp is omitted, and no nested header."""
    assert ros2.from_json("geometry_msgs/PoseStamped", {}, now=NOW)["header"]["stamp"] == NOW_ROS2
    framed = ros2.from_json("geometry_msgs/PoseStamped", {"header": {"frame_id": "map"}}, now=NOW)
    assert framed["header"] == {"stamp": NOW_ROS2, "frame_id": "map"}
    given = ros2.from_json("geometry_msgs/PoseStamped", {"header": {"stamp": {"sec": 3}}}, now=NOW)
    assert given["header"]["stamp"] == {"sec": 3, "nanosec": 0}
    path = ros2.from_json("nav_msgs/Path", {"poses": [{"header": {}}]}, now=NOW)
    assert path["header"]["stamp"] == NOW_ROS2
    assert path["poses"][0]["header"]["stamp"] == ZERO_ROS2
    assert conversion_error(ros2, "geometry_msgs/PoseStamped", {"header": "map"}) == (
        "geometry_msgs/PoseStamped message requires a dict for field header, but got a <class 'str'>"
    )


def test_from_json_output_is_already_in_outbound_form(registry: InterfaceRegistry) -> None:
    """to_json leaves a converted message as it is."""
    converted = registry.from_json(
        "sensor_msgs/Imu", {"orientation": {"w": 1}, "angular_velocity_covariance": [1] * 9}, now=NOW
    )
    assert registry.to_json("sensor_msgs/Imu", converted) == converted


# --------------------------------------------------------------------------- generated types and parts


def test_ros1_actions_generate_actionlib_messages(ros1: InterfaceRegistry) -> None:
    """genaction's seven messages exist with header, goal_id and status fields."""
    assert ros1.default("actionlib_tutorials/FibonacciActionGoal") == {
        "header": {"seq": 0, "stamp": ZERO_ROS1, "frame_id": ""},
        "goal_id": {"stamp": ZERO_ROS1, "id": ""},
        "goal": {"order": 0},
    }
    result = ros1.message_typedefs("actionlib_tutorials/FibonacciActionResult")[0]
    assert result["fieldnames"] == ["header", "status", "result"]
    assert result["fieldtypes"] == [
        "std_msgs/Header",
        "actionlib_msgs/GoalStatus",
        "actionlib_tutorials/FibonacciResult",
    ]
    feedback = ros1.default("actionlib_tutorials/FibonacciActionFeedback")
    assert feedback["status"]["goal_id"] == {"stamp": ZERO_ROS1, "id": ""}
    assert feedback["feedback"] == {"sequence": []}
    action = ros1.message_typedefs("actionlib_tutorials/FibonacciAction")[0]
    assert action["fieldnames"] == ["action_goal", "action_result", "action_feedback"]


def test_service_parts_are_named_as_each_dialect_names_them(
    ros2: InterfaceRegistry, ros1: InterfaceRegistry
) -> None:
    """ROS 2 X_Request/X_Response, ROS 1 XRequest/XResponse, both usable for conversion."""
    assert ros2.service_parts("example_interfaces/AddTwoInts") == (
        "example_interfaces/srv/AddTwoInts_Request",
        "example_interfaces/srv/AddTwoInts_Response",
    )
    assert ros1.service_parts("rospy_tutorials/AddTwoInts") == (
        "rospy_tutorials/AddTwoIntsRequest",
        "rospy_tutorials/AddTwoIntsResponse",
    )
    assert ros1.from_json("rospy_tutorials/AddTwoIntsRequest", {"a": 2}) == {"a": 2, "b": 0}
    assert conversion_error(ros2, "example_interfaces/srv/AddTwoInts_Request", {"c": 1}) == (
        "Message type example_interfaces/AddTwoInts_Request does not have a field c"
    )


def test_action_parts_name_goal_result_and_feedback(ros2: InterfaceRegistry, ros1: InterfaceRegistry) -> None:
    """ROS 2 pkg/action/X_Goal..., ROS 1 pkg/XGoal..."""
    assert ros2.action_parts("example_interfaces/action/Fibonacci") == (
        "example_interfaces/action/Fibonacci_Goal",
        "example_interfaces/action/Fibonacci_Result",
        "example_interfaces/action/Fibonacci_Feedback",
    )
    assert ros1.action_parts("actionlib_tutorials/Fibonacci") == (
        "actionlib_tutorials/FibonacciGoal",
        "actionlib_tutorials/FibonacciResult",
        "actionlib_tutorials/FibonacciFeedback",
    )
    assert ros2.default("example_interfaces/action/Fibonacci_Goal") == {"order": 0}


def test_constants_give_the_goal_status_codes(ros2: InterfaceRegistry, ros1: InterfaceRegistry) -> None:
    """Status codes differ by dialect; CancelGoal carries its error codes."""
    assert ros1.constants("actionlib_msgs/GoalStatus")["LOST"] == 9
    assert ros1.constants("actionlib_msgs/GoalStatus")["SUCCEEDED"] == 3
    assert ros2.constants("action_msgs/msg/GoalStatus") == {
        "STATUS_UNKNOWN": 0,
        "STATUS_ACCEPTED": 1,
        "STATUS_EXECUTING": 2,
        "STATUS_CANCELING": 3,
        "STATUS_SUCCEEDED": 4,
        "STATUS_CANCELED": 5,
        "STATUS_ABORTED": 6,
    }
    _, response = ros2.service_parts("action_msgs/srv/CancelGoal")
    assert ros2.constants(response)["ERROR_UNKNOWN_GOAL_ID"] == 2
    assert list(ros2.default(response)) == ["return_code", "goals_canceling"]


def test_rosapi_services_use_each_dialects_package_and_fields(
    ros2: InterfaceRegistry, ros1: InterfaceRegistry
) -> None:
    """rosapi/GetParam has name+default; rosapi_msgs/srv/GetParam has default_value and a status reply."""
    request, response = ros1.service_parts("rosapi/GetParam")
    assert list(ros1.default(request)) == ["name", "default"]
    assert list(ros1.default(response)) == ["value"]
    request, response = ros2.service_parts("rosapi_msgs/srv/GetParam")
    assert list(ros2.default(request)) == ["name", "default_value"]
    assert list(ros2.default(response)) == ["value", "successful", "reason"]
    assert ros1.has("rosapi/ServiceHost", "srv")
    assert not ros2.has("rosapi_msgs/srv/ServiceHost", "srv")
    assert ros2.has("rosapi_msgs/srv/Interfaces", "srv")
    assert ros1.default(ros1.service_parts("rosapi/GetTime")[1]) == {"time": ZERO_ROS1}
    assert ros2.default(ros2.service_parts("rosapi_msgs/GetTime")[1]) == {"time": ZERO_ROS2}


# --------------------------------------------------------------------------- outbound conversion


def test_to_json_base64_encodes_bytes(registry: InterfaceRegistry) -> None:
    """Raw bytes and int lists for uint8[] leave as base64."""
    assert registry.to_json("std_msgs/UInt8MultiArray", {"data": b"\x00\x01"})["data"] == "AAE="
    assert registry.to_json("std_msgs/UInt8MultiArray", {"data": [0, 1]})["data"] == "AAE="


def test_to_json_spells_time_per_dialect(registry: InterfaceRegistry) -> None:
    """Times go out as secs/nsecs (ROS 1) or sec/nanosec (ROS 2), whichever spelling came in."""
    expected = {"secs": 3, "nsecs": 4} if registry.dialect == "ros1" else {"sec": 3, "nanosec": 4}
    for stamp in ({"secs": 3, "nsecs": 4}, {"sec": 3, "nanosec": 4}):
        assert registry.to_json("rosgraph_msgs/Clock", {"clock": stamp}) == {"clock": expected}


def test_to_json_nulls_non_finite_floats_per_dialect(
    ros2: InterfaceRegistry, ros1: InterfaceRegistry
) -> None:
    """Scalars always become null; ROS 2 passes NaN through in fixed-size float arrays only."""
    value = {"covariance": [math.nan] * 36}
    assert ros1.to_json("geometry_msgs/PoseWithCovariance", value)["covariance"] == [None] * 36
    assert all(math.isnan(v) for v in ros2.to_json("geometry_msgs/PoseWithCovariance", value)["covariance"])
    for registry in (ros1, ros2):
        scan = registry.to_json("sensor_msgs/LaserScan", {"range_max": math.inf, "ranges": [1.0, math.nan]})
        assert scan["range_max"] is None
        assert scan["ranges"] == [1.0, None]


def test_to_json_fills_defaults_and_rejects_unknown_keys(registry: InterfaceRegistry) -> None:
    """A partial dict is completed; a key the type lacks is a bug in the caller."""
    assert registry.to_json("turtlesim/Pose", {"x": 1}) == {
        "x": 1.0,
        "y": 0.0,
        "theta": 0.0,
        "linear_velocity": 0.0,
        "angular_velocity": 0.0,
    }
    with pytest.raises(ConversionError):
        registry.to_json("turtlesim/Pose", {"z": 1})


def test_default_returns_a_fresh_message_each_time(registry: InterfaceRegistry) -> None:
    """Mutating one default message does not change the next."""
    first = registry.default("sensor_msgs/JointState")
    first["name"].append("joint")
    assert registry.default("sensor_msgs/JointState")["name"] == []


@pytest.mark.parametrize("dialect", ["ros1", "ros2"])
def test_the_cbor_form_fails_on_fixed_size_arrays_as_rosbridges_converter_does(dialect: Any) -> None:
    """Odometry's float64[36] covariance is not in cbor_conversion's tables: the message cannot be sent."""
    registry = InterfaceRegistry(dialect)
    json_form = registry.to_json("nav_msgs/Odometry", {})
    with pytest.raises(ConversionError, match="covariance"):
        registry.to_cbor("nav_msgs/Odometry", json_form)


def test_rosbridge_server_rs_sends_fixed_size_arrays_as_cbor_lists() -> None:
    """rs 0.1.6 (seen on /odom): the covariance is a plain list, the message is sent."""
    registry = InterfaceRegistry("ros2")
    form = registry.to_cbor("nav_msgs/Odometry", registry.to_json("nav_msgs/Odometry", {}), fixed_lists=True)
    assert form["pose"]["covariance"] == [0.0] * 36
