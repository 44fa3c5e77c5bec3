"""Nav2's graph laid out (Jazzy names): one robot's nodes, its action servers, the topics each node publishes
and subscribes, the lifecycle managers and the ros2_control controllers. Names are relative to the robot's
namespace; types in ROS 2 form (the world spells them for the dialect)."""

from __future__ import annotations

__all__ = [
    "CONTROLLERS",
    "LIFECYCLE_NODES",
    "MANAGERS",
    "NAV2_ACTIONS",
    "NAV2_NODES",
    "OTHER_NODES",
    "published",
    "subscribed",
]

#: Nav2's lifecycle nodes (each with change_state, get_state, ... and a transition_event topic).
LIFECYCLE_NODES = (
    "controller_server",
    "planner_server",
    "bt_navigator",
    "behavior_server",
    "smoother_server",
    "waypoint_follower",
    "velocity_smoother",
    "collision_monitor",
    "docking_server",
    "map_server",
    "amcl",
    "global_costmap/global_costmap",
    "local_costmap/local_costmap",
    "map_saver",
    "costmap_filter_info_server",
    "filter_mask_server",
)
#: The other nodes of one robot.
OTHER_NODES = (
    "lifecycle_manager_navigation",
    "lifecycle_manager_localization",
    "lifecycle_manager_costmap_filters",
    "bt_navigator_navigate_to_pose_rclcpp_node",
    "bt_navigator_navigate_through_poses_rclcpp_node",
    "robot_state_publisher",
    "controller_manager",
    "diff_drive_controller",
    "joint_state_broadcaster",
    "imu_sensor_broadcaster",
    "ekf_filter_node",
    "rplidar_node",
    "camera/camera",
    "imu_driver",
    "twist_mux",
    "joy_node",
    "teleop_twist_joy_node",
)
NAV2_NODES = LIFECYCLE_NODES + OTHER_NODES

#: (action name, nav2_msgs action, node serving it).
NAV2_ACTIONS = (
    ("navigate_to_pose", "NavigateToPose", "bt_navigator"),
    ("navigate_through_poses", "NavigateThroughPoses", "bt_navigator"),
    ("follow_path", "FollowPath", "controller_server"),
    ("compute_path_to_pose", "ComputePathToPose", "planner_server"),
    ("compute_path_through_poses", "ComputePathThroughPoses", "planner_server"),
    ("smooth_path", "SmoothPath", "smoother_server"),
    ("spin", "Spin", "behavior_server"),
    ("backup", "BackUp", "behavior_server"),
    ("drive_on_heading", "DriveOnHeading", "behavior_server"),
    ("wait", "Wait", "behavior_server"),
    ("assisted_teleop", "AssistedTeleop", "behavior_server"),
    ("follow_waypoints", "FollowWaypoints", "waypoint_follower"),
    ("dock_robot", "DockRobot", "docking_server"),
    ("undock_robot", "UndockRobot", "docking_server"),
)

MANAGERS = (
    "lifecycle_manager_navigation",
    "lifecycle_manager_localization",
    "lifecycle_manager_costmap_filters",
)
CONTROLLERS = (
    ("diff_drive_controller", "diff_drive_controller/DiffDriveController"),
    ("joint_state_broadcaster", "joint_state_broadcaster/JointStateBroadcaster"),
    ("imu_sensor_broadcaster", "imu_sensor_broadcaster/IMUSensorBroadcaster"),
)


def published(twist: str) -> list[tuple[str, str, str, bool]]:
    """(node, topic, type, latched) of every topic one robot publishes; *twist* is its velocity type."""
    pubs: list[tuple[str, str, str, bool]] = [
        # (node, topic, type, latched)
        ("map_server", "map", "nav_msgs/msg/OccupancyGrid", True),
        ("rplidar_node", "scan", "sensor_msgs/msg/LaserScan", False),
        ("ekf_filter_node", "odom", "nav_msgs/msg/Odometry", False),
        ("diff_drive_controller", "diff_drive_controller/odom", "nav_msgs/msg/Odometry", False),
        ("twist_mux", "diff_drive_controller/cmd_vel", twist, False),
        ("ekf_filter_node", "tf", "tf2_msgs/msg/TFMessage", False),
        ("amcl", "tf", "tf2_msgs/msg/TFMessage", False),
        ("robot_state_publisher", "tf_static", "tf2_msgs/msg/TFMessage", True),
        ("robot_state_publisher", "robot_description", "std_msgs/msg/String", True),
        ("joint_state_broadcaster", "joint_states", "sensor_msgs/msg/JointState", False),
        ("joint_state_broadcaster", "dynamic_joint_states", "control_msgs/msg/DynamicJointState", False),
        ("imu_driver", "imu/data", "sensor_msgs/msg/Imu", False),
        ("imu_sensor_broadcaster", "imu_sensor_broadcaster/imu", "sensor_msgs/msg/Imu", False),
        ("camera/camera", "camera/camera/color/image_raw", "sensor_msgs/msg/Image", False),
        ("camera/camera", "camera/camera/color/camera_info", "sensor_msgs/msg/CameraInfo", False),
        ("camera/camera", "camera/camera/depth/image_rect_raw", "sensor_msgs/msg/Image", False),
        ("camera/camera", "camera/camera/depth/camera_info", "sensor_msgs/msg/CameraInfo", False),
        ("camera/camera", "camera/camera/depth/color/points", "sensor_msgs/msg/PointCloud2", False),
        ("planner_server", "plan", "nav_msgs/msg/Path", False),
        ("smoother_server", "plan_smoothed", "nav_msgs/msg/Path", False),
        ("controller_server", "local_plan", "nav_msgs/msg/Path", False),
        ("controller_server", "received_global_plan", "nav_msgs/msg/Path", False),
        ("controller_server", "transformed_global_plan", "nav_msgs/msg/Path", False),
        ("controller_server", "cmd_vel_nav", twist, False),
        ("behavior_server", "cmd_vel_nav", twist, False),
        ("velocity_smoother", "cmd_vel_smoothed", twist, False),
        ("collision_monitor", "cmd_vel", twist, False),
        ("teleop_twist_joy_node", "cmd_vel_joy", twist, False),
        ("joy_node", "joy", "sensor_msgs/msg/Joy", False),
        ("amcl", "amcl_pose", "geometry_msgs/msg/PoseWithCovarianceStamped", True),
        ("amcl", "particle_cloud", "nav2_msgs/msg/ParticleCloud", False),
        ("bt_navigator", "behavior_tree_log", "nav2_msgs/msg/BehaviorTreeLog", False),
        ("collision_monitor", "collision_monitor_state", "nav2_msgs/msg/CollisionMonitorState", False),
        ("collision_monitor", "polygon_stop", "geometry_msgs/msg/PolygonStamped", False),
        ("ekf_filter_node", "diagnostics", "diagnostic_msgs/msg/DiagnosticArray", False),
        ("controller_manager", "diagnostics", "diagnostic_msgs/msg/DiagnosticArray", False),
        ("camera/camera", "diagnostics", "diagnostic_msgs/msg/DiagnosticArray", False),
        ("costmap_filter_info_server", "costmap_filter_info", "nav2_msgs/msg/CostmapFilterInfo", True),
        ("filter_mask_server", "keepout_filter_mask", "nav_msgs/msg/OccupancyGrid", True),
    ]
    for costmap, local in (("global_costmap", False), ("local_costmap", True)):
        node = f"{costmap}/{costmap}"
        pubs += [
            (node, f"{costmap}/costmap", "nav_msgs/msg/OccupancyGrid", True),
            (node, f"{costmap}/costmap_updates", "map_msgs/msg/OccupancyGridUpdate", False),
            (node, f"{costmap}/costmap_raw", "nav2_msgs/msg/Costmap", True),
            (node, f"{costmap}/costmap_raw_updates", "nav2_msgs/msg/CostmapUpdate", False),
            (node, f"{costmap}/published_footprint", "geometry_msgs/msg/PolygonStamped", False),
        ]
        if local:
            pubs += [
                (node, f"{costmap}/voxel_marked_cloud", "sensor_msgs/msg/PointCloud2", False),
                (node, f"{costmap}/clearing_endpoints", "sensor_msgs/msg/PointCloud2", False),
            ]
    return pubs


def subscribed(twist: str) -> list[tuple[str, str, str]]:
    """(node, topic, type) of every subscription of one robot's nodes; *twist* is its velocity type."""
    subs: list[tuple[str, str, str]] = [
        ("amcl", "map", "nav_msgs/msg/OccupancyGrid"),
        ("global_costmap/global_costmap", "map", "nav_msgs/msg/OccupancyGrid"),
        ("amcl", "scan", "sensor_msgs/msg/LaserScan"),
        ("global_costmap/global_costmap", "scan", "sensor_msgs/msg/LaserScan"),
        ("local_costmap/local_costmap", "scan", "sensor_msgs/msg/LaserScan"),
        ("collision_monitor", "scan", "sensor_msgs/msg/LaserScan"),
        ("controller_server", "odom", "nav_msgs/msg/Odometry"),
        ("velocity_smoother", "odom", "nav_msgs/msg/Odometry"),
        ("bt_navigator", "odom", "nav_msgs/msg/Odometry"),
        ("ekf_filter_node", "diff_drive_controller/odom", "nav_msgs/msg/Odometry"),
        ("ekf_filter_node", "imu/data", "sensor_msgs/msg/Imu"),
        ("diff_drive_controller", "diff_drive_controller/cmd_vel", twist),
        ("robot_state_publisher", "joint_states", "sensor_msgs/msg/JointState"),
        ("velocity_smoother", "cmd_vel_nav", twist),
        ("collision_monitor", "cmd_vel_smoothed", twist),
        ("twist_mux", "cmd_vel_joy", twist),
        ("twist_mux", "pause_navigation", "std_msgs/msg/Bool"),
        ("teleop_twist_joy_node", "joy", "sensor_msgs/msg/Joy"),
        ("joy_node", "joy/set_feedback", "sensor_msgs/msg/JoyFeedback"),
        ("behavior_server", "cmd_vel_teleop", "geometry_msgs/msg/Twist"),
        ("behavior_server", "preempt_teleop", "std_msgs/msg/Empty"),
        ("controller_server", "speed_limit", "nav2_msgs/msg/SpeedLimit"),
        ("amcl", "initialpose", "geometry_msgs/msg/PoseWithCovarianceStamped"),
        ("bt_navigator", "goal_pose", "geometry_msgs/msg/PoseStamped"),
        ("docking_server", "dock_pose", "geometry_msgs/msg/PoseStamped"),
        ("global_costmap/global_costmap", "global_costmap/footprint", "geometry_msgs/msg/Polygon"),
        ("local_costmap/local_costmap", "local_costmap/footprint", "geometry_msgs/msg/Polygon"),
        ("global_costmap/global_costmap", "costmap_filter_info", "nav2_msgs/msg/CostmapFilterInfo"),
        ("global_costmap/global_costmap", "keepout_filter_mask", "nav_msgs/msg/OccupancyGrid"),
    ]
    tf_listeners = (
        "controller_server",
        "planner_server",
        "bt_navigator",
        "behavior_server",
        "collision_monitor",
        "docking_server",
        "global_costmap/global_costmap",
        "local_costmap/local_costmap",
        "amcl",
    )
    subs += [(node, "tf", "tf2_msgs/msg/TFMessage") for node in tf_listeners]
    subs += [(node, "tf_static", "tf2_msgs/msg/TFMessage") for node in tf_listeners]
    return subs
