"""Type outlines from rosapi TypeDefs: nesting, array bounds, constants, slot names, and an example."""

from __future__ import annotations

from typing import Any

from rosbridge_mcp_server.robot.type_outline import clean_typedefs, outline_type


def typedef(
    type_name: str, fields: list[tuple[str, str, int]], consts: dict[str, str] | None = None
) -> dict[str, Any]:
    return {
        "type": type_name,
        "fieldnames": [f[0] for f in fields],
        "fieldtypes": [f[1] for f in fields],
        "fieldarraylen": [f[2] for f in fields],
        "examples": [],
        "constnames": list((consts or {}).keys()),
        "constvalues": list((consts or {}).values()),
    }


VECTOR3 = typedef("geometry_msgs/Vector3", [("x", "float64", -1), ("y", "float64", -1), ("z", "float64", -1)])


def test_a_nested_message_is_outlined_once_per_type() -> None:
    """Twist shows linear with its fields and angular as the same type, plus an example to publish."""
    raw = [
        typedef(
            "geometry_msgs/Twist",
            [("linear", "geometry_msgs/Vector3", -1), ("angular", "geometry_msgs/Vector3", -1)],
        ),
        VECTOR3,
    ]
    outline = outline_type("geometry_msgs/msg/Twist", raw, ros_version=2)
    assert outline.lines == (
        "linear: geometry_msgs/Vector3",
        "  x: float64",
        "  y: float64",
        "  z: float64",
        "angular: geometry_msgs/Vector3  (fields as above)",
    )
    assert outline.example == {
        "linear": {"x": 0.0, "y": 0.0, "z": 0.0},
        "angular": {"x": 0.0, "y": 0.0, "z": 0.0},
    }


def test_arrays_show_their_bounds_and_constants_are_listed() -> None:
    """Variable, fixed and bounded arrays read float32[], float64[9], int32[<=3]; constants come first."""
    raw = [
        typedef(
            "pkg/Scan",
            [("ranges", "float32", 0), ("covariance", "float64", 9), ("few", "sequence<int32, 3>", 0)],
            {"MODE_FAST": "1"},
        )
    ]
    outline = outline_type("pkg/Scan", raw, ros_version=2)
    assert outline.lines == (
        "MODE_FAST = 1  (constant)",
        "ranges: float32[]",
        "covariance: float64[9]",
        "few: int32[<=3]",
    )
    assert outline.constants == {"MODE_FAST": "1"}
    assert outline.example == {"ranges": [], "covariance": [0.0] * 9, "few": []}


def test_rosapi_slot_names_lose_their_underscore() -> None:
    """rosapi 2.1.0 answers _linear/_angular and IDL's double; the outline says linear and float64."""
    slots = typedef(
        "geometry_msgs/Twist",
        [("_linear", "geometry_msgs/Vector3", -1), ("_angular", "geometry_msgs/Vector3", -1)],
    )
    vector = typedef(
        "geometry_msgs/Vector3", [("_x", "double", -1), ("_y", "double", -1), ("_z", "double", -1)]
    )
    raw = clean_typedefs({"typedefs": [slots, vector]})
    outline = outline_type("geometry_msgs/msg/Twist", raw, ros_version=2)
    assert outline.lines[0:2] == ("linear: geometry_msgs/Vector3", "  x: float64")
    assert outline.example["angular"] == {"x": 0.0, "y": 0.0, "z": 0.0}


def test_ros1_time_fields_get_a_ros1_example() -> None:
    """A ROS 1 header's stamp is time, shown with secs/nsecs in the example."""
    header = typedef(
        "std_msgs/Header", [("seq", "uint32", -1), ("stamp", "time", -1), ("frame_id", "string", -1)]
    )
    outline = outline_type("std_msgs/Header", [header], ros_version=1)
    assert outline.example == {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}


def test_ros2_pseudo_constants_are_dropped() -> None:
    """ROS 2 rosapi's SLOT_TYPES, field properties and X__DEFAULT members are not shown as constants."""
    raw = typedef(
        "pkg/Mode",
        [("mode", "uint8", -1)],
        {"MODE__DEFAULT": "0", "SLOT_TYPES": "(<rosidl_parser...>,)", "mode": "0", "FAST": "1"},
    )
    outline = outline_type("pkg/msg/Mode", clean_typedefs([raw]), ros_version=2)
    assert outline.constants == {"FAST": "1"}
    assert outline.lines == ("FAST = 1  (constant)", "mode: uint8")


def test_a_bounded_sequence_in_rosapi_2_spelling_shows_its_bound() -> None:
    """rosapi 2.x writes sequence<int32, 3> as 'int32, 3'; the outline reads int32[<=3]."""
    raw = typedef("pkg/Few", [("few", "int32, 3", 0)])
    assert outline_type("pkg/Few", [raw], ros_version=2).lines == ("few: int32[<=3]",)
