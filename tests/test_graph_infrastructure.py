"""Per-node and rosapi services are typed from their names alone, and only when the evidence is complete."""

from __future__ import annotations

from rosbridge_mcp_server.robot.known_types import infrastructure_types
from rosbridge_mcp_server.tools.list_services import ServiceRow, listing_text

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


def listed(names_and_types: dict[str, str], version: int) -> list[str]:
    """list_services' text for these services, as lines."""
    rows = [ServiceRow(name=name, type=kind) for name, kind in sorted(names_and_types.items())]
    return listing_text(rows, version).splitlines()


def test_the_listing_text_groups_what_every_node_offers_and_keeps_the_robots_own_a_line_each() -> None:
    """Nodes with the same set share a line; a managed node's set is a line of its own; nothing is lost."""
    services = {f"/{node}/{leaf}": "x" for node in ("camera", "lidar", "map_server") for leaf in PARAMETERS}
    services |= {f"/map_server/{leaf}": "x" for leaf in LIFECYCLE}
    services |= {"/spawn": "turtlesim/srv/Spawn", "/mystery": "", "/rosapi/topics": "rosapi_msgs/srv/Topics"}
    lines = listed(services, 2)
    assert lines[0] == "26 services: the robot's 2, then 24 that every node and rosapi offer, grouped:"
    assert lines[1:3] == ["/mystery (type unknown)", "/spawn (turtlesim/srv/Spawn)"]
    assert lines[3].startswith("On 2 nodes (/camera, /lidar): <node>/describe_parameters (rcl_interfaces/")
    assert lines[4].startswith(
        "On 1 node (/map_server): <node>/change_state (lifecycle_msgs/srv/ChangeState),"
    )
    assert "<node>/set_parameters_atomically (rcl_interfaces/srv/SetParametersAtomically)" in lines[4]
    assert lines[5] == "rosapi's own, /rosapi/<name> (rosapi_msgs/srv/<Type>): topics (Topics)"
    assert len(lines) == 6


def test_a_listing_with_only_the_robots_own_services_is_a_plain_list() -> None:
    """No grouping to announce when there is nothing to group (ROS 1 spelling)."""
    assert listed({"/reset": "std_srvs/Empty", "/spawn": "turtlesim/Spawn"}, 1) == [
        "2 services:",
        "/reset (std_srvs/Empty)",
        "/spawn (turtlesim/Spawn)",
    ]
