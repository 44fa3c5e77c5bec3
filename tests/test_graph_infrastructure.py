"""Per-node and rosapi services are typed from their names alone, and only when the evidence is complete."""

from __future__ import annotations

from rosbridge_mcp_server.robot.known_types import infrastructure_types

PARAMETERS = [
    "describe_parameters",
    "get_parameter_types",
    "get_parameters",
    "list_parameters",
    "set_parameters",
    "set_parameters_atomically",
]
LIFECYCLE = [
    "change_state",
    "get_state",
    "get_available_states",
    "get_available_transitions",
    "get_transition_graph",
]


def test_a_ros2_nodes_parameter_and_lifecycle_services_are_typed() -> None:
    """All six parameter services under /camera, all five lifecycle services under /map_server."""
    names = [f"/camera/{leaf}" for leaf in PARAMETERS] + [f"/map_server/{leaf}" for leaf in LIFECYCLE]
    found = infrastructure_types([*names, "/camera/get_type_description", "/add_two_ints"], 2)
    assert found["/camera/get_parameters"] == "rcl_interfaces/srv/GetParameters"
    assert found["/camera/get_type_description"] == "type_description_interfaces/srv/GetTypeDescription"
    assert found["/map_server/get_transition_graph"] == "lifecycle_msgs/srv/GetAvailableTransitions"
    assert "/add_two_ints" not in found


def test_a_lone_service_sharing_a_leaf_name_is_not_guessed() -> None:
    """/robot/get_parameters alone (no sibling parameter services) may be anything: it is looked up."""
    assert infrastructure_types(["/robot/get_parameters", "/robot/get_state"], 2) == {}
    assert infrastructure_types(["/robot/get_loggers"], 1) == {}


def test_ros1_logger_services_and_rosapi_services_are_typed() -> None:
    """Both logger services of a rospy node; rosapi's own services in each line's package."""
    found = infrastructure_types(["/talker/get_loggers", "/talker/set_logger_level", "/rosapi/topics"], 1)
    assert found == {
        "/talker/get_loggers": "roscpp/GetLoggers",
        "/talker/set_logger_level": "roscpp/SetLoggerLevel",
        "/rosapi/topics": "rosapi/Topics",
    }
    ros2 = infrastructure_types(["/rosapi/get_ros_version", "/rosapi/interfaces"], 2)
    assert ros2 == {"/rosapi/get_ros_version": "rosapi_msgs/srv/GetROSVersion"}, (
        "unknown rosapi names are asked"
    )
