"""What an act does, whichever tool carries it, under the name the robot acts on (pure: no robot)."""

from __future__ import annotations

import pytest

from rosbridge_mcp_server.errors import NotSentError
from rosbridge_mcp_server.robot.effects import Effect, service_effects, topic_effects
from rosbridge_mcp_server.robot.names import parameter_name


@pytest.mark.parametrize(
    ("topic", "type_name", "expected"),
    [
        (
            "/fibonacci/goal",
            "actionlib_tutorials/FibonacciActionGoal",
            (Effect("action", "/fibonacci", "goal"),),
        ),
        (
            "/ns/move_base/goal",
            "move_base_msgs/msg/MoveBaseActionGoal",
            (Effect("action", "/ns/move_base", "goal"),),
        ),
        ("/fibonacci/cancel", "actionlib_msgs/GoalID", (Effect("action", "/fibonacci", "cancel"),)),
        ("/fibonacci/goal", "std_msgs/String", ()),
        ("/turtle1/cmd_vel", "geometry_msgs/Twist", ()),
        ("/goal_pose", "geometry_msgs/msg/PoseStamped", (Effect("motion", "/goal_pose", "move"),)),
        (
            "/r1/move_base_simple/goal",
            "geometry_msgs/PoseStamped",
            (Effect("motion", "/r1/move_base_simple/goal", "move"),),
        ),
        ("/arm/command", "trajectory_msgs/msg/JointTrajectory", (Effect("motion", "/arm/command", "move"),)),
        ("/my_goal_pose", "geometry_msgs/msg/PoseStamped", ()),
    ],
)
def test_an_actionlib_topic_is_a_goal_or_cancel_of_its_action(
    topic: str, type_name: str, expected: tuple[Effect, ...]
) -> None:
    assert topic_effects(topic, type_name) == expected


def test_ros2_action_services_are_the_actions() -> None:
    kinds = "example_interfaces/action/Fibonacci_SendGoal"
    assert service_effects("/fibonacci/_action/send_goal", kinds, {}, 2) == (
        Effect("action", "/fibonacci", "goal"),
    )
    assert service_effects("/a/b/_action/cancel_goal", "action_msgs/srv/CancelGoal", {}, 2) == (
        Effect("action", "/a/b", "cancel"),
    )
    assert service_effects("/fibonacci/_action/get_result", "", {}, 2) == (
        Effect("action", "/fibonacci", "result"),
    )


def test_parameter_services_write_each_named_parameter_canonically() -> None:
    request = {"parameters": [{"name": "background_r", "value": {}}, {"name": "pen.width", "value": {}}]}
    assert service_effects("/turtlesim/set_parameters", "rcl_interfaces/srv/SetParameters", request, 2) == (
        Effect("parameter", "/turtlesim:background_r", "set"),
        Effect("parameter", "/turtlesim:pen.width", "set"),
    )
    assert (
        service_effects("/turtlesim/set_parameters_atomically", "", request, 2)[0].name
        == "/turtlesim:background_r"
    )
    # rosapi, both lines, by name or by type; ROS 1 writes replace what is under them.
    assert service_effects("/rosapi/set_param", "", {"name": "/turtlesim//:background_r"}, 2) == (
        Effect("parameter", "/turtlesim:background_r", "set"),
    )
    assert service_effects("/other/set_param", "rosapi/DeleteParam", {"name": "turtlesim//a/"}, 1) == (
        Effect("parameter", "/turtlesim/a", "delete", subtree=True),
    )
    # ROS 1 dynamic_reconfigure
    config = {"config": {"ints": [{"name": "speed", "value": 3}], "bools": [{"name": "on", "value": True}]}}
    assert service_effects("/camera/set_parameters", "dynamic_reconfigure/Reconfigure", config, 1) == (
        Effect("parameter", "/camera/on", "set", subtree=True),
        Effect("parameter", "/camera/speed", "set", subtree=True),
    )


@pytest.mark.parametrize(
    ("service", "request_body", "version"),
    [
        ("/turtlesim/set_parameters", {"parameters": "background_r"}, 2),
        ("/turtlesim/set_parameters", {"parameters": [{"name": 3}]}, 2),
        ("/rosapi/set_param", {"value": "1"}, 1),
        ("/camera/set_parameters", {"config": {"ints": [{"value": 1}]}}, 1),
    ],
)
def test_a_parameter_request_that_does_not_name_its_parameters_is_not_sent(
    service: str, request_body: object, version: int
) -> None:
    with pytest.raises(NotSentError, match="could not judge it"):
        service_effects(service, "", request_body, version)


def test_motion_services_by_type_or_usual_name() -> None:
    assert service_effects("/turtle1/teleport_absolute", "turtlesim/srv/TeleportAbsolute", {}, 2) == (
        Effect("motion", "/turtle1/teleport_absolute", "move"),
    )
    assert service_effects("/robot/reposition", "gazebo_msgs/SetModelState", {}, 1)[0].kind == "motion"
    assert service_effects("/t/teleport_relative", "", {}, 1)[0].kind == "motion"
    assert service_effects("/add_two_ints", "example_interfaces/srv/AddTwoInts", {}, 2) == ()


@pytest.mark.parametrize(
    ("written", "version", "canonical"),
    [
        ("/turtlesim/:background_r", 2, "/turtlesim:background_r"),
        ("/turtlesim//:background_r", 2, "/turtlesim:background_r"),
        ("turtlesim:background_r", 2, "/turtlesim:background_r"),
        ("//ns//node/:qos_overrides./tf.depth", 2, "/ns/node:qos_overrides./tf.depth"),
        ("/turtlesim/background_r/", 1, "/turtlesim/background_r"),
        ("//turtlesim/background_r", 1, "/turtlesim/background_r"),
        ("/turtlesim//background_r", 1, "/turtlesim/background_r"),
        ("turtlesim/background_r", 1, "/turtlesim/background_r"),
    ],
)
def test_a_parameter_name_is_made_the_one_the_robot_acts_on(
    written: str, version: int, canonical: str
) -> None:
    assert parameter_name(written, version) == canonical


@pytest.mark.parametrize(
    ("written", "version", "fragment"),
    [
        ("~private", 1, "private name"),
        ("/a:b", 1, "ROS 2 style"),
        ("///", 1, "root"),
        ("/turtlesim", 2, "not a ROS 2 parameter name"),
        ("/:x", 2, "not a ROS 2 parameter name"),
        ("/a b:c", 2, "whitespace"),
    ],
)
def test_a_name_no_parameter_can_have_is_refused(written: str, version: int, fragment: str) -> None:
    with pytest.raises(NotSentError, match=fragment):
        parameter_name(written, version)


# --- issue 35: effects by type as well as by name --------------------------------------------------------


@pytest.mark.parametrize(
    ("topic", "type_name", "kind"),
    [
        ("/joy", "sensor_msgs/msg/Joy", "motion"),
        ("/robot1/teleop/joy_in", "sensor_msgs/Joy", "motion"),
        ("/tf", "tf2_msgs/msg/TFMessage", "fence"),
        ("/robot1/tf", "tf2_msgs/TFMessage", "fence"),
        ("/robot1/tf_static", "tf2_msgs/msg/TFMessage", "fence"),
        ("/my_transforms", "tf2_msgs/msg/TFMessage", "fence"),
        ("/tf", "std_msgs/msg/String", "fence"),
        ("/initialpose", "geometry_msgs/msg/PoseWithCovarianceStamped", "fence"),
        ("/relocalise_here", "geometry_msgs/PoseWithCovarianceStamped", "fence"),
        ("/map", "nav_msgs/msg/OccupancyGrid", "fence"),
        ("/keepout_filter_mask", "nav_msgs/msg/OccupancyGrid", "fence"),
        ("/robot2/speed_filter_mask", "std_msgs/msg/String", "fence"),
        ("/costmap_filter_info", "nav2_msgs/msg/CostmapFilterInfo", "fence"),
        ("/my_filter_info", "nav2_msgs/msg/CostmapFilterInfo", "fence"),
        ("/speed_limit", "nav2_msgs/msg/SpeedLimit", "fence"),
        ("/limits", "nav2_msgs/SpeedLimit", "fence"),
        ("/odom", "nav_msgs/msg/Odometry", "fence"),
        ("/scan", "sensor_msgs/msg/LaserScan", "fence"),
        ("/camera/points", "sensor_msgs/msg/PointCloud2", "fence"),
        ("/imu/data", "sensor_msgs/Imu", "fence"),
        ("/local_costmap/footprint", "geometry_msgs/msg/Polygon", "fence"),
    ],
)
def test_what_moves_the_robot_or_the_fence_is_known_by_type_and_by_name(
    topic: str, type_name: str, kind: str
) -> None:
    (effect,) = topic_effects(topic, type_name)
    assert (effect.kind, effect.name) == (kind, topic)
    assert effect.why  # said in words to the person and the audit


@pytest.mark.parametrize(
    ("service", "type_name", "kind"),
    [
        ("/reset", "std_srvs/srv/Empty", "motion"),
        ("/gazebo/reset_world", "std_srvs/Empty", "motion"),
        ("/reset_simulation", "std_srvs/srv/Empty", "motion"),
        ("/controller_server/change_state", "lifecycle_msgs/srv/ChangeState", "motion"),
        ("/renamed/transition", "lifecycle_msgs/srv/ChangeState", "motion"),
        ("/lifecycle_manager_navigation/manage_nodes", "nav2_msgs/srv/ManageLifecycleNodes", "motion"),
        ("/controller_manager/switch_controller", "controller_manager_msgs/srv/SwitchController", "motion"),
        ("/set_initial_pose", "nav2_msgs/srv/SetInitialPose", "fence"),
        ("/robot1/request_nomotion_update", "std_srvs/srv/Empty", "fence"),
        ("/map_server/load_map", "nav2_msgs/srv/LoadMap", "fence"),
        ("/somewhere/else", "nav2_msgs/srv/LoadMap", "fence"),
        ("/ekf/set_pose", "robot_localization/srv/SetPose", "fence"),
    ],
)
def test_services_that_move_the_robot_or_the_fence_are_known(service: str, type_name: str, kind: str) -> None:
    (effect,) = service_effects(service, type_name, {}, 2)
    assert (effect.kind, effect.name) == (kind, service)


@pytest.mark.parametrize("type_name", ["rosapi_msgs/srv/SetParam", "rosapi/SetParam"])
@pytest.mark.parametrize("service", ["/rosapi/set_param", "/robot1/rosapi/set_param", "/innocent"])
def test_rosapi_set_param_under_any_name_is_a_parameter_write(service: str, type_name: str) -> None:
    request = {"name": "/turtlesim:background_r", "value": "255"}
    assert service_effects(service, type_name, request, 2) == (
        Effect("parameter", "/turtlesim:background_r", "set"),
    )


def test_set_parameters_under_another_name_is_a_parameter_write() -> None:
    request = {"parameters": [{"name": "max_vel_x", "value": {}}]}
    assert service_effects("/controller_server/renamed", "rcl_interfaces/srv/SetParameters", request, 2) == (
        Effect("parameter", "/controller_server:max_vel_x", "set"),
    )
