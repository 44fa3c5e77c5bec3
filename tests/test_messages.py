"""Checking messages against rosapi TypeDefs: every wrong field named by path, with rosbridge's strictness."""

from __future__ import annotations

from typing import Any

import pytest

from rosbridge_mcp_server.errors import InvalidMessageError
from rosbridge_mcp_server.robot.messages import (
    check_message,
    example_message,
    find_problems,
    short_type_name,
    typedefs_from_rosapi,
)


def _typedef(type_name: str, fields: list[tuple[str, str, int]]) -> dict[str, Any]:
    return {
        "type": type_name,
        "fieldnames": [f[0] for f in fields],
        "fieldtypes": [f[1] for f in fields],
        "fieldarraylen": [f[2] for f in fields],
        "examples": [],
        "constnames": [],
        "constvalues": [],
    }


# As ROS 2 rosapi answers message_details: type names without /msg/, primitive names of the IDL.
TWIST = typedefs_from_rosapi(
    {
        "typedefs": [
            _typedef(
                "geometry_msgs/Twist",
                [("linear", "geometry_msgs/Vector3", -1), ("angular", "geometry_msgs/Vector3", -1)],
            ),
            _typedef(
                "geometry_msgs/Vector3", [("x", "double", -1), ("y", "double", -1), ("z", "double", -1)]
            ),
        ]
    }
)

MIXED = typedefs_from_rosapi(
    {
        "typedefs": [
            _typedef(
                "demo_msgs/Mixed",
                [
                    ("flag", "bool", -1),
                    ("count", "uint8", -1),
                    ("name", "string", -1),
                    ("covariance", "float64", 9),
                    ("data", "uint8", 0),
                    ("points", "geometry_msgs/Vector3", 0),
                    ("stamp", "time", -1),
                ],
            ),
            _typedef(
                "geometry_msgs/Vector3", [("x", "float64", -1), ("y", "float64", -1), ("z", "float64", -1)]
            ),
        ]
    }
)


def test_a_fitting_message_passes_and_missing_fields_are_fine() -> None:
    """A partial Twist fits: rosbridge fills the rest with zeros."""
    partial = {"linear": {"x": 0.5}, "angular": {"z": 0.3}}
    assert find_problems(partial, "geometry_msgs/msg/Twist", TWIST, ros_version=2) == []
    assert find_problems({}, "geometry_msgs/Twist", TWIST, ros_version=2) == []
    check_message(partial, "geometry_msgs/msg/Twist", TWIST, ros_version=2)


def test_a_string_where_a_number_belongs_is_named_by_path() -> None:
    """linear.x: "fast" is reported with the expected type and the value given."""
    problems = find_problems({"linear": {"x": "fast"}}, "geometry_msgs/Twist", TWIST, ros_version=2)
    assert problems == ['linear.x: expected a number (float64), got "fast"']


def test_an_unknown_field_gets_a_suggestion_and_the_valid_fields() -> None:
    """A misspelt field names the close match and lists every valid field."""
    problems = find_problems({"lineer": {"x": 1.0}}, "geometry_msgs/Twist", TWIST, ros_version=2)
    assert len(problems) == 1
    assert problems[0].startswith("lineer: no such field in geometry_msgs/Twist (did you mean linear?)")
    assert "its fields are linear, angular" in problems[0]


def test_every_wrong_field_is_reported_at_once() -> None:
    """All problems come back together, not only the first."""
    message = {"linear": {"x": None, "w": 1}, "angular": 3}
    problems = find_problems(message, "geometry_msgs/Twist", TWIST, ros_version=2)
    assert problems == [
        "linear.x: expected a number (float64), got null",
        "linear.w: no such field in geometry_msgs/Vector3; its fields are x, y, z",
        "angular: expected an object (geometry_msgs/Vector3), got 3",
    ]


@pytest.mark.parametrize(
    ("message", "problem"),
    [
        ({"flag": 1}, "flag: expected true or false (bool), got 1"),
        ({"count": 1.5}, "count: expected an integer (uint8), got 1.5"),
        ({"count": 256}, "count: 256 is out of range for uint8 (0..255)"),
        ({"count": True}, "count: expected an integer (uint8), got true"),
        ({"name": 5}, "name: expected a string (string), got 5"),
        ({"covariance": [0.0] * 8}, "covariance: expected exactly 9 elements (float64[9]), got 8"),
        ({"covariance": 0.0}, "covariance: expected an array of 9 numbers (float64), got 0.0"),
        ({"points": [{"x": 1}, {"x": "a"}]}, 'points[1].x: expected a number (float64), got "a"'),
        ({"stamp": {"sec": 1}}, "stamp.sec: no such field in time (ROS 1 reads only secs and nsecs"),
    ],
)
def test_json_types_are_held_to_rosbridge_strictness(message: dict[str, Any], problem: str) -> None:
    """Bools, integer ranges, strings, fixed array lengths, nested arrays and ROS 1 time keys are checked."""
    problems = find_problems(message, "demo_msgs/Mixed", MIXED, ros_version=1)
    assert len(problems) == 1
    assert problems[0].startswith(problem)


ROS1_TIMES = typedefs_from_rosapi(
    {
        "typedefs": [
            _typedef(
                "demo_msgs/Times", [("stamp", "time", -1), ("span", "duration", -1), ("f", "float32", -1)]
            ),
            # ROS 1 rosapi (0.11.17) describes both primitives as two int32.
            _typedef("time", [("secs", "int32", -1), ("nsecs", "int32", -1)]),
            _typedef("duration", [("secs", "int32", -1), ("nsecs", "int32", -1)]),
        ]
    }
)


@pytest.mark.parametrize(
    ("message", "problem"),
    [
        ({"stamp": {"secs": -1}}, "stamp.secs: -1 is out of range for uint32 in time (0..4294967295)"),
        ({"stamp": {"nsecs": -5}}, "stamp.nsecs: -5 is out of range for uint32 in time"),
        ({"span": {"secs": 2**31}}, "span.secs: 2147483648 is out of range for int32 in duration"),
        ({"f": 3.5e38}, "f: 3.5e+38 is out of range for float32 (-3.40282e+38..3.40282e+38)"),
        ({"f": -1e39}, "f: -1e+39 is out of range for float32"),
    ],
)
def test_ros1_times_and_float32_must_fit_their_wire_width(message: dict[str, Any], problem: str) -> None:
    """A negative time, a duration past int32 or a float32 past its range is refused: genpy cannot pack it."""
    problems = find_problems(message, "demo_msgs/Times", ROS1_TIMES, ros_version=1)
    assert len(problems) == 1
    assert problems[0].startswith(problem)


def test_values_that_fit_the_wire_widths_pass() -> None:
    """A negative duration, a time up to 2**32-1 and float32's largest value are fine on ROS 1."""
    message = {"stamp": {"secs": 2**32 - 1, "nsecs": 2_000_000_000}, "span": {"secs": -1}, "f": -3.4e38}
    assert find_problems(message, "demo_msgs/Times", ROS1_TIMES, ros_version=1) == []


@pytest.mark.parametrize("value", [float("inf"), float("-inf"), float("nan")])
def test_infinities_and_nan_fit_a_float32(value: float) -> None:
    """Infinity (a LaserScan's usual range_max) and NaN pack fine, so they are not out of range."""
    assert find_problems({"f": value}, "demo_msgs/Times", ROS1_TIMES, ros_version=1) == []


def test_ros2_time_fields_are_int32_seconds_and_uint32_nanoseconds() -> None:
    """On ROS 2 a negative sec fits a Time; a negative nanosec does not."""
    assert find_problems({"sec": -1}, "builtin_interfaces/Time", {}, ros_version=2) == []
    problems = find_problems({"nanosec": -1}, "builtin_interfaces/Duration", {}, ros_version=2)
    assert problems == [
        "nanosec: -1 is out of range for uint32 in builtin_interfaces/Duration (0..4294967295)"
    ]


def test_byte_arrays_may_be_base64_and_time_may_be_now() -> None:
    """uint8[] as a base64 string and a time as "now" are what rosbridge accepts."""
    message = {"data": "AAEC", "stamp": "now", "count": 3, "covariance": [0] * 9, "flag": False}
    assert find_problems(message, "demo_msgs/Mixed", MIXED, ros_version=1) == []


def test_a_message_that_is_not_an_object_is_rejected() -> None:
    """A bare list is not a message."""
    problems = find_problems([1, 2], "geometry_msgs/Twist", TWIST, ros_version=2)
    assert problems == [
        "the message must be a JSON object with the fields of geometry_msgs/Twist, got an array of 2"
    ]


def test_check_message_raises_invalid_message_error_with_every_problem() -> None:
    """The error names the type and carries the problems for the tool's answer."""
    with pytest.raises(InvalidMessageError) as caught:
        check_message({"linear": {"x": "fast"}}, "geometry_msgs/msg/Twist", TWIST, ros_version=2)
    assert caught.value.problems == ['linear.x: expected a number (float64), got "fast"']
    assert "geometry_msgs/msg/Twist" in str(caught.value)


def test_ros2_sequence_spellings_are_understood() -> None:
    """sequence<T>, T[N] and bounded strings in fieldtypes read as arrays and strings."""
    typedefs = typedefs_from_rosapi(
        {
            "typedefs": [
                _typedef(
                    "demo/Seq", [("a", "sequence<int32>", -1), ("b", "double[3]", -1), ("c", "string<=5", -1)]
                )
            ]
        }
    )
    assert (
        find_problems({"a": [1, 2], "b": [0.0, 1.0, 2.0], "c": "hi"}, "demo/Seq", typedefs, ros_version=2)
        == []
    )
    assert find_problems({"a": [1.5]}, "demo/Seq", typedefs, ros_version=2) == [
        "a[0]: expected an integer (int32), got 1.5"
    ]
    assert find_problems({"b": [0.0]}, "demo/Seq", typedefs, ros_version=2) == [
        "b: expected exactly 3 elements (float64[3]), got 1"
    ]


def test_example_message_shows_every_field_at_its_default() -> None:
    """The example shows the shape a model should send."""
    assert example_message("geometry_msgs/msg/Twist", TWIST, ros_version=2) == {
        "linear": {"x": 0.0, "y": 0.0, "z": 0.0},
        "angular": {"x": 0.0, "y": 0.0, "z": 0.0},
    }


def test_short_type_name_drops_the_category() -> None:
    """pkg/msg/Type, pkg/srv/Type and pkg/action/Type compare as pkg/Type."""
    assert short_type_name("geometry_msgs/msg/Twist") == "geometry_msgs/Twist"
    assert short_type_name("std_srvs/srv/Trigger") == "std_srvs/Trigger"
    assert short_type_name("geometry_msgs/Twist") == "geometry_msgs/Twist"


# As rosapi 2.1.0 (Jazzy and Kilted) answers message_details: slot names, properties among the constants.
TWIST_SLOTS = typedefs_from_rosapi(
    {
        "typedefs": [
            {
                "type": "geometry_msgs/Twist",
                "fieldnames": ["_linear", "_angular"],
                "fieldtypes": ["geometry_msgs/Vector3", "geometry_msgs/Vector3"],
                "fieldarraylen": [-1, -1],
                "examples": ["{}", "{}"],
                "constnames": ["SLOT_TYPES", "angular", "linear"],
                "constvalues": [
                    "(<rosidl_parser.definition.NamespacedType object at 0x7f6f1c6bde70>, ...)",
                    "geometry_msgs.msg.Vector3(x=0.0, y=0.0, z=0.0)",
                    "geometry_msgs.msg.Vector3(x=0.0, y=0.0, z=0.0)",
                ],
            },
            {
                "type": "geometry_msgs/Vector3",
                "fieldnames": ["_x", "_y", "_z"],
                "fieldtypes": ["double", "double", "double"],
                "fieldarraylen": [-1, -1, -1],
                "examples": ["0.0", "0.0", "0.0"],
                "constnames": ["SLOT_TYPES", "x", "y", "z"],
                "constvalues": ["(...)", "0.0", "0.0", "0.0"],
            },
        ]
    }
)


def test_slot_named_typedefs_check_messages_by_their_plain_field_names() -> None:
    """A Twist described with _linear/_angular accepts linear/angular, as the bridge itself does."""
    message = {"linear": {"x": 1.0}, "angular": {"z": 0.5}}
    assert find_problems(message, "geometry_msgs/msg/Twist", TWIST_SLOTS, ros_version=2) == []


def test_slot_names_are_never_offered_to_the_model() -> None:
    """An underscore name is refused, and neither the suggestion nor the example shows one."""
    problems = find_problems({"_linear": {"x": 1.0}}, "geometry_msgs/Twist", TWIST_SLOTS, ros_version=2)
    assert len(problems) == 1
    assert "did you mean linear?" in problems[0]
    assert "_linear" not in problems[0].split(":", 1)[1]
    example = example_message("geometry_msgs/Twist", TWIST_SLOTS, ros_version=2)
    assert example == {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}


def test_a_typedef_with_plain_names_keeps_them() -> None:
    """Only a TypeDef whose every field starts with an underscore is in slot names."""
    typedefs = typedefs_from_rosapi(
        {"typedefs": [_typedef("pkg/Odd", [("_a", "int32", -1), ("b", "int32", -1)])]}
    )
    assert typedefs["pkg/Odd"].fieldnames == ("_a", "b")
