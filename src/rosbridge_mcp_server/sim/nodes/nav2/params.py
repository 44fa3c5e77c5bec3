"""The Nav2 world's declared parameters: nav2_bringup's ``nav2_params.yaml`` (Jazzy) and what the drivers,
ros2_control and robot_localization declare, per node (names relative to the node, ROS 2 dotted form).

Values are plausible, not a tuned robot. Every node also gets what rclcpp declares on its own
(:func:`common_parameters`).
"""

from __future__ import annotations

from typing import Any

__all__ = ["NODE_PARAMETERS", "common_parameters"]

Params = dict[str, Any]


def common_parameters(*, type_descriptions: bool) -> Params:
    """What every rclcpp node declares by itself."""
    params: Params = {
        "use_sim_time": False,
        "qos_overrides./parameter_events.publisher.depth": 1000,
        "qos_overrides./parameter_events.publisher.durability": "volatile",
        "qos_overrides./parameter_events.publisher.history": "keep_last",
        "qos_overrides./parameter_events.publisher.reliability": "reliable",
    }
    if type_descriptions:
        params["start_type_description_service"] = True
    return params


def _prefixed(prefix: str, params: Params) -> Params:
    return {f"{prefix}.{name}": value for name, value in params.items()}


_MPPI_CRITICS: dict[str, Params] = {
    "ConstraintCritic": {"enabled": True, "cost_power": 1, "cost_weight": 4.0},
    "CostCritic": {
        "enabled": True,
        "cost_power": 1,
        "cost_weight": 3.81,
        "critical_cost": 300.0,
        "consider_footprint": True,
        "collision_cost": 1000000.0,
        "near_goal_distance": 1.0,
        "trajectory_point_step": 2,
    },
    "GoalCritic": {"enabled": True, "cost_power": 1, "cost_weight": 5.0, "threshold_to_consider": 1.4},
    "GoalAngleCritic": {"enabled": True, "cost_power": 1, "cost_weight": 3.0, "threshold_to_consider": 0.5},
    "PathAlignCritic": {
        "enabled": True,
        "cost_power": 1,
        "cost_weight": 14.0,
        "max_path_occupancy_ratio": 0.05,
        "trajectory_point_step": 4,
        "threshold_to_consider": 0.5,
        "offset_from_furthest": 20,
        "use_path_orientations": False,
    },
    "PathFollowCritic": {
        "enabled": True,
        "cost_power": 1,
        "cost_weight": 5.0,
        "offset_from_furthest": 5,
        "threshold_to_consider": 1.4,
    },
    "PathAngleCritic": {
        "enabled": True,
        "cost_power": 1,
        "cost_weight": 2.0,
        "offset_from_furthest": 4,
        "threshold_to_consider": 0.5,
        "max_angle_to_furthest": 1.0,
        "mode": 0,
    },
    "PreferForwardCritic": {
        "enabled": True,
        "cost_power": 1,
        "cost_weight": 5.0,
        "threshold_to_consider": 0.5,
    },
    "ObstaclesCritic": {
        "enabled": False,
        "cost_power": 1,
        "repulsion_weight": 1.5,
        "critical_weight": 20.0,
        "consider_footprint": False,
        "collision_cost": 10000.0,
        "collision_margin_distance": 0.1,
        "near_goal_distance": 0.5,
        "inflation_radius": 0.55,
        "cost_scaling_factor": 10.0,
    },
    "TwirlingCritic": {"enabled": False, "cost_power": 1, "cost_weight": 10.0},
    "VelocityDeadbandCritic": {
        "enabled": False,
        "cost_power": 1,
        "cost_weight": 35.0,
        "deadband_velocities": [0.05, 0.05, 0.05],
    },
}

#: MPPI's critics the robot runs (the others are declared, and disabled).
_ACTIVE_CRITICS = [name for name, values in _MPPI_CRITICS.items() if values["enabled"]]


def _tf_qos(*topics: str) -> Params:
    """The QoS overrides rclcpp declares for a node's /tf (and /tf_static) publishers."""
    return {
        f"qos_overrides./{topic}.publisher.{policy}": value
        for topic in topics
        for policy, value in (
            ("depth", 100 if topic == "tf" else 1),
            ("durability", "volatile" if topic == "tf" else "transient_local"),
            ("history", "keep_last"),
            ("reliability", "reliable"),
        )
    }


def _controller_server() -> Params:
    follow_path: Params = {
        "plugin": "nav2_mppi_controller::MPPIController",
        "time_steps": 56,
        "model_dt": 0.05,
        "batch_size": 2000,
        "ax_max": 3.0,
        "ax_min": -3.0,
        "ay_max": 3.0,
        "az_max": 3.5,
        "vx_std": 0.2,
        "vy_std": 0.2,
        "wz_std": 0.4,
        "vx_max": 0.5,
        "vx_min": -0.35,
        "vy_max": 0.5,
        "wz_max": 1.9,
        "iteration_count": 1,
        "prune_distance": 1.7,
        "transform_tolerance": 0.1,
        "temperature": 0.3,
        "gamma": 0.015,
        "motion_model": "DiffDrive",
        "visualize": False,
        "regenerate_noises": True,
        "retry_attempt_limit": 1,
        "reset_period": 1.0,
        "TrajectoryVisualizer.trajectory_step": 5,
        "TrajectoryVisualizer.time_step": 3,
        "AckermannConstraints.min_turning_r": 0.2,
        "critics": _ACTIVE_CRITICS,
    }
    for critic, values in _MPPI_CRITICS.items():
        follow_path.update(_prefixed(critic, values))
    return {
        "controller_frequency": 20.0,
        "costmap_update_timeout": 0.3,
        "min_x_velocity_threshold": 0.001,
        "min_y_velocity_threshold": 0.5,
        "min_theta_velocity_threshold": 0.001,
        "failure_tolerance": 0.3,
        "odom_topic": "odom",
        "speed_limit_topic": "speed_limit",
        "publish_zero_velocity": True,
        "enable_stamped_cmd_vel": True,
        "use_realtime_priority": False,
        "progress_checker_plugins": ["progress_checker"],
        "goal_checker_plugins": ["general_goal_checker"],
        "controller_plugins": ["FollowPath", "PreciseFollow"],
        "progress_checker.plugin": "nav2_controller::SimpleProgressChecker",
        "progress_checker.required_movement_radius": 0.5,
        "progress_checker.movement_time_allowance": 10.0,
        "general_goal_checker.plugin": "nav2_controller::SimpleGoalChecker",
        "general_goal_checker.stateful": True,
        "general_goal_checker.xy_goal_tolerance": 0.25,
        "general_goal_checker.yaw_goal_tolerance": 0.25,
        "bond_heartbeat_period": 0.1,
        **_prefixed("FollowPath", follow_path),
        **_prefixed("PreciseFollow", _regulated_pure_pursuit()),
    }


def _regulated_pure_pursuit() -> Params:
    return {
        "plugin": "nav2_regulated_pure_pursuit_controller::RegulatedPurePursuitController",
        "desired_linear_vel": 0.3,
        "lookahead_dist": 0.6,
        "min_lookahead_dist": 0.3,
        "max_lookahead_dist": 0.9,
        "lookahead_time": 1.5,
        "rotate_to_heading_angular_vel": 1.8,
        "transform_tolerance": 0.1,
        "use_velocity_scaled_lookahead_dist": False,
        "min_approach_linear_velocity": 0.05,
        "approach_velocity_scaling_dist": 0.6,
        "use_collision_detection": True,
        "max_allowed_time_to_collision_up_to_carrot": 1.0,
        "use_regulated_linear_velocity_scaling": True,
        "use_fixed_curvature_lookahead": False,
        "curvature_lookahead_dist": 0.25,
        "use_cost_regulated_linear_velocity_scaling": False,
        "cost_scaling_dist": 0.3,
        "cost_scaling_gain": 1.0,
        "inflation_cost_scaling_factor": 3.0,
        "regulated_linear_scaling_min_radius": 0.9,
        "regulated_linear_scaling_min_speed": 0.25,
        "use_rotate_to_heading": True,
        "allow_reversing": False,
        "rotate_to_heading_min_angle": 0.785,
        "max_angular_accel": 3.2,
        "max_robot_pose_search_dist": 10.0,
        "interpolate_curvature_after_goal": False,
        "use_interpolation": True,
        "stateful": True,
    }


def _costmap(*, local: bool) -> Params:
    params: Params = {
        "update_frequency": 5.0 if local else 1.0,
        "publish_frequency": 2.0 if local else 1.0,
        "global_frame": "odom" if local else "map",
        "robot_base_frame": "base_link",
        "rolling_window": local,
        "width": 3 if local else 10,
        "height": 3 if local else 10,
        "resolution": 0.05,
        "robot_radius": 0.22,
        "footprint": "[]",
        "footprint_padding": 0.01,
        "origin_x": 0.0,
        "origin_y": 0.0,
        "always_send_full_costmap": True,
        "track_unknown_space": not local,
        "lethal_cost_threshold": 100,
        "trinary_costmap": True,
        "unknown_cost_value": 255,
        "use_maximum": False,
        "transform_tolerance": 0.3,
        "initial_transform_timeout": 60.0,
        "map_topic": "/map",
        "map_vis_z": 0.0,
        "clearable_layers": ["obstacle_layer", "voxel_layer", "range_layer"],
        "filters": [] if local else ["keepout_filter"],
        "subscribe_to_updates": False,
        "plugins": ["voxel_layer", "inflation_layer"]
        if local
        else ["static_layer", "obstacle_layer", "inflation_layer"],
        "inflation_layer.plugin": "nav2_costmap_2d::InflationLayer",
        "inflation_layer.enabled": True,
        "inflation_layer.cost_scaling_factor": 3.0,
        "inflation_layer.inflation_radius": 0.7 if local else 0.55,
        "inflation_layer.inflate_unknown": False,
        "inflation_layer.inflate_around_unknown": False,
    }
    observation = {
        "topic": "/scan",
        "max_obstacle_height": 2.0,
        "min_obstacle_height": 0.0,
        "clearing": True,
        "marking": True,
        "data_type": "LaserScan",
        "raytrace_max_range": 3.0,
        "raytrace_min_range": 0.0,
        "obstacle_max_range": 2.5,
        "obstacle_min_range": 0.0,
        "expected_update_rate": 0.0,
        "observation_persistence": 0.0,
        "inf_is_valid": False,
        "sensor_frame": "",
        "transport_type": "raw",
    }
    layer = "voxel_layer" if local else "obstacle_layer"
    params.update(
        {
            f"{layer}.plugin": "nav2_costmap_2d::VoxelLayer" if local else "nav2_costmap_2d::ObstacleLayer",
            f"{layer}.enabled": True,
            f"{layer}.footprint_clearing_enabled": True,
            f"{layer}.max_obstacle_height": 2.0,
            f"{layer}.combination_method": 1,
            f"{layer}.observation_sources": "scan",
            **_prefixed(f"{layer}.scan", observation),
        }
    )
    if local:
        params.update(
            {
                "voxel_layer.publish_voxel_map": True,
                "voxel_layer.origin_z": 0.0,
                "voxel_layer.z_resolution": 0.05,
                "voxel_layer.z_voxels": 16,
                "voxel_layer.mark_threshold": 0,
                "voxel_layer.unknown_threshold": 15,
            }
        )
    else:
        params.update(
            {
                "keepout_filter.plugin": "nav2_costmap_2d::KeepoutFilter",
                "keepout_filter.enabled": True,
                "keepout_filter.filter_info_topic": "costmap_filter_info",
                "keepout_filter.transform_tolerance": 0.1,
                "keepout_filter.override_lethal_cost": False,
                "keepout_filter.lethal_override_cost": 252,
                "static_layer.plugin": "nav2_costmap_2d::StaticLayer",
                "static_layer.enabled": True,
                "static_layer.map_subscribe_transient_local": True,
                "static_layer.map_topic": "",
                "static_layer.subscribe_to_updates": False,
                "static_layer.transform_tolerance": 0.0,
                "static_layer.footprint_clearing_enabled": False,
                "static_layer.restore_cleared_footprint": True,
            }
        )
    return params


def _amcl() -> Params:
    return {
        **_tf_qos("tf"),
        "alpha1": 0.2,
        "alpha2": 0.2,
        "alpha3": 0.2,
        "alpha4": 0.2,
        "alpha5": 0.2,
        "base_frame_id": "base_footprint",
        "beam_skip_distance": 0.5,
        "beam_skip_error_threshold": 0.9,
        "beam_skip_threshold": 0.3,
        "do_beamskip": False,
        "global_frame_id": "map",
        "lambda_short": 0.1,
        "laser_likelihood_max_dist": 2.0,
        "laser_max_range": 100.0,
        "laser_min_range": -1.0,
        "laser_model_type": "likelihood_field",
        "max_beams": 60,
        "max_particles": 2000,
        "min_particles": 500,
        "odom_frame_id": "odom",
        "pf_err": 0.05,
        "pf_z": 0.99,
        "recovery_alpha_fast": 0.0,
        "recovery_alpha_slow": 0.0,
        "resample_interval": 1,
        "robot_model_type": "nav2_amcl::DifferentialMotionModel",
        "save_pose_rate": 0.5,
        "sigma_hit": 0.2,
        "tf_broadcast": True,
        "transform_tolerance": 1.0,
        "update_min_a": 0.2,
        "update_min_d": 0.25,
        "z_hit": 0.5,
        "z_max": 0.05,
        "z_rand": 0.5,
        "z_short": 0.05,
        "scan_topic": "scan",
        "map_topic": "map",
        "set_initial_pose": False,
        "always_reset_initial_pose": False,
        "first_map_only": False,
        "initial_pose.x": 0.0,
        "initial_pose.y": 0.0,
        "initial_pose.z": 0.0,
        "initial_pose.yaw": 0.0,
        "bond_heartbeat_period": 0.1,
    }


_BT_NODES = [
    "nav2_compute_path_to_pose_action_bt_node",
    "nav2_compute_path_through_poses_action_bt_node",
    "nav2_smooth_path_action_bt_node",
    "nav2_follow_path_action_bt_node",
    "nav2_spin_action_bt_node",
    "nav2_wait_action_bt_node",
    "nav2_assisted_teleop_action_bt_node",
    "nav2_back_up_action_bt_node",
    "nav2_drive_on_heading_bt_node",
    "nav2_clear_costmap_service_bt_node",
    "nav2_is_stuck_condition_bt_node",
    "nav2_goal_reached_condition_bt_node",
    "nav2_goal_updated_condition_bt_node",
    "nav2_globally_updated_goal_condition_bt_node",
    "nav2_is_path_valid_condition_bt_node",
    "nav2_initial_pose_received_condition_bt_node",
    "nav2_reinitialize_global_localization_service_bt_node",
    "nav2_rate_controller_bt_node",
    "nav2_distance_controller_bt_node",
    "nav2_speed_controller_bt_node",
    "nav2_truncate_path_action_bt_node",
    "nav2_goal_updater_node_bt_node",
    "nav2_recovery_node_bt_node",
    "nav2_pipeline_sequence_bt_node",
    "nav2_round_robin_node_bt_node",
    "nav2_transform_available_condition_bt_node",
    "nav2_time_expired_condition_bt_node",
    "nav2_path_expiring_timer_condition",
    "nav2_distance_traveled_condition_bt_node",
    "nav2_single_trigger_bt_node",
    "nav2_remove_passed_goals_action_bt_node",
    "nav2_planner_selector_bt_node",
    "nav2_controller_selector_bt_node",
    "nav2_goal_checker_selector_bt_node",
    "nav2_controller_cancel_bt_node",
    "nav2_path_longer_on_approach_bt_node",
    "nav2_wait_cancel_bt_node",
    "nav2_spin_cancel_bt_node",
    "nav2_back_up_cancel_bt_node",
    "nav2_drive_on_heading_cancel_bt_node",
]


def _bt_navigator() -> Params:
    return {
        "global_frame": "map",
        "robot_base_frame": "base_link",
        "odom_topic": "/odom",
        "bt_loop_duration": 10,
        "default_server_timeout": 20,
        "wait_for_service_timeout": 1000,
        "action_server_result_timeout": 900.0,
        "transform_tolerance": 0.1,
        "filter_duration": 0.3,
        "always_reload_bt_xml": False,
        "navigators": ["navigate_to_pose", "navigate_through_poses"],
        "navigate_to_pose.plugin": "nav2_bt_navigator::NavigateToPoseNavigator",
        "navigate_to_pose.enable_groot_monitoring": False,
        "navigate_to_pose.groot_server_port": 1667,
        "navigate_through_poses.plugin": "nav2_bt_navigator::NavigateThroughPosesNavigator",
        "navigate_through_poses.enable_groot_monitoring": False,
        "navigate_through_poses.groot_server_port": 1669,
        "default_nav_to_pose_bt_xml": (
            "/opt/ros/jazzy/share/nav2_bt_navigator/behavior_trees/"
            "navigate_to_pose_w_replanning_and_recovery.xml"
        ),
        "default_nav_through_poses_bt_xml": (
            "/opt/ros/jazzy/share/nav2_bt_navigator/behavior_trees/"
            "navigate_through_poses_w_replanning_and_recovery.xml"
        ),
        "plugin_lib_names": _BT_NODES,
        "error_code_names": ["compute_path_error_code", "follow_path_error_code"],
        "bond_heartbeat_period": 0.1,
    }


def _behavior_server() -> Params:
    return {
        "local_costmap_topic": "local_costmap/costmap_raw",
        "global_costmap_topic": "global_costmap/costmap_raw",
        "local_footprint_topic": "local_costmap/published_footprint",
        "global_footprint_topic": "global_costmap/published_footprint",
        "cycle_frequency": 10.0,
        "behavior_plugins": ["spin", "backup", "drive_on_heading", "assisted_teleop", "wait"],
        "spin.plugin": "nav2_behaviors::Spin",
        "backup.plugin": "nav2_behaviors::BackUp",
        "drive_on_heading.plugin": "nav2_behaviors::DriveOnHeading",
        "wait.plugin": "nav2_behaviors::Wait",
        "assisted_teleop.plugin": "nav2_behaviors::AssistedTeleop",
        "local_frame": "odom",
        "global_frame": "map",
        "robot_base_frame": "base_link",
        "transform_tolerance": 0.1,
        "simulate_ahead_time": 2.0,
        "max_rotational_vel": 1.0,
        "min_rotational_vel": 0.4,
        "rotational_acc_lim": 3.2,
        "enable_stamped_cmd_vel": True,
        "bond_heartbeat_period": 0.1,
    }


def _velocity_smoother() -> Params:
    return {
        "smoothing_frequency": 20.0,
        "scale_velocities": False,
        "feedback": "OPEN_LOOP",
        "max_velocity": [0.5, 0.0, 2.0],
        "min_velocity": [-0.5, 0.0, -2.0],
        "max_accel": [2.5, 0.0, 3.2],
        "max_decel": [-2.5, 0.0, -3.2],
        "odom_topic": "odom",
        "odom_duration": 0.1,
        "deadband_velocity": [0.0, 0.0, 0.0],
        "velocity_timeout": 1.0,
        "use_realtime_priority": False,
        "stamp_smoothed_velocity_with_smoothing_time": False,
        "enable_stamped_cmd_vel": True,
        "bond_heartbeat_period": 0.1,
    }


def _collision_monitor() -> Params:
    polygon = {
        "type": "polygon",
        "points": "[[0.3, 0.3], [0.3, -0.3], [0.0, -0.3], [0.0, 0.3]]",
        "action_type": "stop",
        "min_points": 4,
        "visualize": True,
        "polygon_pub_topic": "polygon_stop",
        "enabled": True,
    }
    return {
        "base_frame_id": "base_footprint",
        "odom_frame_id": "odom",
        "cmd_vel_in_topic": "cmd_vel_smoothed",
        "cmd_vel_out_topic": "cmd_vel",
        "state_topic": "collision_monitor_state",
        "transform_tolerance": 0.2,
        "source_timeout": 1.0,
        "base_shift_correction": True,
        "stop_pub_timeout": 2.0,
        "enable_stamped_cmd_vel": True,
        "use_realtime_priority": False,
        "polygons": ["FootprintApproach"],
        "FootprintApproach.type": "polygon",
        "FootprintApproach.action_type": "approach",
        "FootprintApproach.footprint_topic": "/local_costmap/published_footprint",
        "FootprintApproach.time_before_collision": 1.2,
        "FootprintApproach.simulation_time_step": 0.1,
        "FootprintApproach.min_points": 6,
        "FootprintApproach.visualize": False,
        "FootprintApproach.enabled": True,
        "FootprintApproach.holonomic": False,
        "FootprintApproach.max_points": 3,
        **_prefixed("PolygonStop", polygon),
        "observation_sources": ["scan"],
        "scan.type": "scan",
        "scan.topic": "scan",
        "scan.min_height": 0.15,
        "scan.max_height": 2.0,
        "scan.enabled": True,
        "bond_heartbeat_period": 0.1,
    }


def _docking_server() -> Params:
    return {
        "controller_frequency": 50.0,
        "initial_perception_timeout": 5.0,
        "wait_charge_timeout": 5.0,
        "dock_approach_timeout": 30.0,
        "undock_linear_tolerance": 0.05,
        "undock_angular_tolerance": 0.1,
        "max_retries": 3,
        "base_frame": "base_link",
        "fixed_frame": "odom",
        "dock_backwards": False,
        "dock_prestaging_tolerance": 0.5,
        "dock_plugins": ["simple_charging_dock"],
        "simple_charging_dock.plugin": "opennav_docking::SimpleChargingDock",
        "simple_charging_dock.docking_threshold": 0.05,
        "simple_charging_dock.staging_x_offset": -0.7,
        "simple_charging_dock.use_external_detection_pose": True,
        "simple_charging_dock.use_battery_status": False,
        "simple_charging_dock.use_stall_detection": False,
        "simple_charging_dock.external_detection_timeout": 1.0,
        "simple_charging_dock.external_detection_translation_x": -0.18,
        "simple_charging_dock.external_detection_translation_y": 0.0,
        "simple_charging_dock.external_detection_rotation_roll": -1.57,
        "simple_charging_dock.external_detection_rotation_pitch": -1.57,
        "simple_charging_dock.external_detection_rotation_yaw": 0.0,
        "simple_charging_dock.filter_coef": 0.1,
        "docks": ["home_dock"],
        "home_dock.type": "simple_charging_dock",
        "home_dock.frame": "map",
        "home_dock.pose": [0.0, 0.0, 0.0],
        "controller.k_phi": 3.0,
        "controller.k_delta": 2.0,
        "controller.v_linear_min": 0.15,
        "controller.v_linear_max": 0.15,
        "controller.use_collision_detection": True,
        "controller.costmap_topic": "local_costmap/costmap_raw",
        "controller.footprint_topic": "local_costmap/published_footprint",
        "controller.transform_tolerance": 0.1,
        "controller.projection_time": 5.0,
        "controller.simulation_step": 0.1,
        "controller.dock_collision_threshold": 0.3,
        "bond_heartbeat_period": 0.1,
    }


def _ekf() -> Params:
    params: Params = {
        **_tf_qos("tf"),
        "frequency": 30.0,
        "diagnostic_updater.period": 1.0,
        "sensor_timeout": 0.1,
        "two_d_mode": True,
        "transform_time_offset": 0.0,
        "transform_timeout": 0.0,
        "print_diagnostics": True,
        "debug": False,
        "publish_tf": True,
        "publish_acceleration": False,
        "permit_corrected_publication": False,
        "reset_on_time_jump": False,
        "smooth_lagged_data": False,
        "history_length": 0.0,
        "map_frame": "map",
        "odom_frame": "odom",
        "base_link_frame": "base_footprint",
        "world_frame": "odom",
        "use_control": False,
        "dynamic_process_noise_covariance": False,
        "process_noise_covariance": [0.05] * 15,
        "initial_estimate_covariance": [1e-9] * 15,
    }
    for source, topic, config in (
        ("odom0", "/diff_drive_controller/odom", [False, False, False, False, False, False, True, True]),
        ("imu0", "/imu/data", [False, False, False, False, False, True, False, False]),
    ):
        params.update(
            {
                source: topic,
                f"{source}_config": config + [False] * 7,
                f"{source}_queue_size": 10,
                f"{source}_differential": False,
                f"{source}_relative": False,
                f"{source}_nodelay": False,
                f"{source}_pose_rejection_threshold": 5.0,
                f"{source}_twist_rejection_threshold": 1.0,
                f"{source}_pose_use_child_frame": False,
            }
        )
    params["imu0_remove_gravitational_acceleration"] = True
    params["imu0_linear_acceleration_rejection_threshold"] = 0.8
    return params


def _realsense() -> Params:
    params: Params = {
        "camera_name": "camera",
        "camera_namespace": "camera",
        "serial_no": "''",
        "usb_port_id": "''",
        "device_type": "''",
        "json_file_path": "''",
        "initial_reset": False,
        "rosbag_filename": "''",
        "base_frame_id": "link",
        "tf_publish_rate": 0.0,
        "diagnostics_period": 0.0,
        "diagnostic_updater.period": 1.0,
        "publish_tf": True,
        "enable_sync": False,
        "align_depth.enable": False,
        "colorizer.enable": False,
        "pointcloud.enable": True,
        "pointcloud.stream_filter": 2,
        "pointcloud.stream_index_filter": 0,
        "pointcloud.ordered_pc": False,
        "pointcloud.allow_no_texture_points": False,
        "decimation_filter.enable": False,
        "spatial_filter.enable": False,
        "temporal_filter.enable": False,
        "hole_filling_filter.enable": False,
        "hdr_merge.enable": False,
        "clip_distance": -2.0,
        "angular_velocity_cov": 0.01,
        "linear_accel_cov": 0.01,
        "unite_imu_method": 0,
        "wait_for_device_timeout": -1.0,
        "reconnect_timeout": 6.0,
    }
    for stream in ("color", "depth", "infra1", "infra2"):
        params.update(
            {
                f"enable_{stream}": stream in ("color", "depth"),
                f"{stream}_qos": "SYSTEM_DEFAULT",
                f"{stream}_info_qos": "DEFAULT",
                f"rgb_camera.{stream}_profile" if stream == "color" else f"depth_module.{stream}_profile": (
                    "640x480x30"
                ),
                f"rgb_camera.{stream}_format" if stream == "color" else f"depth_module.{stream}_format": (
                    "RGB8" if stream == "color" else "Z16" if stream == "depth" else "Y8"
                ),
            }
        )
    for sensor in ("rgb_camera", "depth_module"):
        params.update(
            {
                f"{sensor}.enable_auto_exposure": True,
                f"{sensor}.exposure": 166 if sensor == "rgb_camera" else 8500,
                f"{sensor}.gain": 64 if sensor == "rgb_camera" else 16,
                f"{sensor}.global_time_enabled": True,
                f"{sensor}.frames_queue_size": 16,
                f"{sensor}.power_line_frequency": 3,
                f"{sensor}.auto_exposure_priority": False,
            }
        )
    params.update(
        {
            "rgb_camera.brightness": 0,
            "rgb_camera.contrast": 50,
            "rgb_camera.gamma": 300,
            "rgb_camera.hue": 0,
            "rgb_camera.saturation": 64,
            "rgb_camera.sharpness": 50,
            "rgb_camera.white_balance": 4600.0,
            "rgb_camera.enable_auto_white_balance": True,
            "depth_module.emitter_enabled": 1,
            "depth_module.emitter_on_off": False,
            "depth_module.laser_power": 150.0,
            "depth_module.visual_preset": 0,
            "depth_module.inter_cam_sync_mode": 0,
            "depth_module.hdr_enabled": False,
        }
    )
    return params


def _diff_drive_controller() -> Params:
    return {
        "type": "diff_drive_controller/DiffDriveController",
        "left_wheel_names": ["left_wheel_joint"],
        "right_wheel_names": ["right_wheel_joint"],
        "wheel_separation": 0.287,
        "wheels_per_side": 1,
        "wheel_radius": 0.033,
        "wheel_separation_multiplier": 1.0,
        "left_wheel_radius_multiplier": 1.0,
        "right_wheel_radius_multiplier": 1.0,
        "publish_rate": 50.0,
        "odom_frame_id": "odom",
        "base_frame_id": "base_footprint",
        "pose_covariance_diagonal": [0.001, 0.001, 1000000.0, 1000000.0, 1000000.0, 0.01],
        "twist_covariance_diagonal": [0.001, 0.001, 1000000.0, 1000000.0, 1000000.0, 0.01],
        "open_loop": False,
        "position_feedback": True,
        "enable_odom_tf": False,
        "cmd_vel_timeout": 0.5,
        "tf_frame_prefix_enable": True,
        "tf_frame_prefix": "",
        "preserve_turning_radius": True,
        "publish_limited_velocity": False,
        "velocity_rolling_window_size": 10,
        "linear.x.max_velocity": 0.5,
        "linear.x.min_velocity": -0.5,
        "linear.x.max_acceleration": 1.0,
        "angular.z.max_velocity": 2.0,
        "angular.z.min_velocity": -2.0,
        "angular.z.max_acceleration": 3.0,
        "update_rate": 50,
    }


NODE_PARAMETERS: dict[str, Params] = {
    "controller_server": _controller_server(),
    "planner_server": {
        "expected_planner_frequency": 20.0,
        "costmap_update_timeout": 1.0,
        "planner_plugins": ["GridBased"],
        "GridBased.plugin": "nav2_navfn_planner::NavfnPlanner",
        "GridBased.tolerance": 0.5,
        "GridBased.use_astar": False,
        "GridBased.allow_unknown": True,
        "GridBased.use_final_approach_orientation": False,
        "action_server_result_timeout": 10.0,
        "bond_heartbeat_period": 0.1,
    },
    "smoother_server": {
        "smoother_plugins": ["simple_smoother"],
        "simple_smoother.plugin": "nav2_smoother::SimpleSmoother",
        "simple_smoother.tolerance": 1e-10,
        "simple_smoother.max_its": 1000,
        "simple_smoother.do_refinement": True,
        "simple_smoother.refinement_num": 2,
        "simple_smoother.w_data": 0.2,
        "simple_smoother.w_smooth": 0.3,
        "simple_smoother.enforce_path_inversion": True,
        "robot_base_frame": "base_link",
        "transform_tolerance": 0.1,
        "costmap_topic": "global_costmap/costmap_raw",
        "footprint_topic": "global_costmap/published_footprint",
        "bond_heartbeat_period": 0.1,
    },
    "bt_navigator": _bt_navigator(),
    "behavior_server": _behavior_server(),
    "waypoint_follower": {
        "loop_rate": 20,
        "stop_on_failure": False,
        "action_server_result_timeout": 900.0,
        "global_frame_id": "map",
        "waypoint_task_executor_plugin": "wait_at_waypoint",
        "wait_at_waypoint.plugin": "nav2_waypoint_follower::WaitAtWaypoint",
        "wait_at_waypoint.enabled": True,
        "wait_at_waypoint.waypoint_pause_duration": 200,
        "bond_heartbeat_period": 0.1,
    },
    "velocity_smoother": _velocity_smoother(),
    "collision_monitor": _collision_monitor(),
    "docking_server": _docking_server(),
    "map_server": {
        "yaml_filename": "/opt/ros/jazzy/share/nav2_bringup/maps/warehouse.yaml",
        "topic_name": "map",
        "frame_id": "map",
        "service_introspection_mode": "disabled",
        "bond_heartbeat_period": 0.1,
    },
    "amcl": _amcl(),
    "global_costmap/global_costmap": _costmap(local=False),
    "local_costmap/local_costmap": _costmap(local=True),
    "lifecycle_manager_navigation": {
        "autostart": True,
        "node_names": [
            "controller_server",
            "smoother_server",
            "planner_server",
            "behavior_server",
            "velocity_smoother",
            "collision_monitor",
            "bt_navigator",
            "waypoint_follower",
            "docking_server",
        ],
        "bond_timeout": 4.0,
        "bond_respawn_max_duration": 10.0,
        "attempt_respawn_reconnection": True,
        "service_timeout": 5.0,
    },
    "lifecycle_manager_costmap_filters": {
        "autostart": True,
        "node_names": ["filter_mask_server", "costmap_filter_info_server"],
        "bond_timeout": 4.0,
        "bond_respawn_max_duration": 10.0,
        "attempt_respawn_reconnection": True,
        "service_timeout": 5.0,
    },
    "map_saver": {
        "save_map_timeout": 5.0,
        "free_thresh_default": 0.25,
        "occupied_thresh_default": 0.65,
        "map_subscribe_transient_local": True,
        "bond_heartbeat_period": 0.1,
    },
    "costmap_filter_info_server": {
        "type": 0,
        "filter_info_topic": "costmap_filter_info",
        "mask_topic": "keepout_filter_mask",
        "base": 0.0,
        "multiplier": 1.0,
        "bond_heartbeat_period": 0.1,
    },
    "filter_mask_server": {
        "yaml_filename": "/opt/ros/jazzy/share/nav2_bringup/maps/keepout_mask.yaml",
        "topic_name": "keepout_filter_mask",
        "frame_id": "map",
        "bond_heartbeat_period": 0.1,
    },
    "lifecycle_manager_localization": {
        "autostart": True,
        "node_names": ["map_server", "amcl", "map_saver"],
        "bond_timeout": 4.0,
        "bond_respawn_max_duration": 10.0,
        "attempt_respawn_reconnection": True,
        "service_timeout": 5.0,
    },
    "robot_state_publisher": {
        **_tf_qos("tf", "tf_static"),
        "publish_frequency": 20.0,
        "ignore_timestamp": False,
        "frame_prefix": "",
        "robot_description": "",
    },
    "controller_manager": {
        "update_rate": 100,
        "diagnostic_updater.period": 1.0,
        "thread_priority": 50,
        "cpu_affinity": [],
        "enforce_command_limits": True,
        "hardware_components_initial_state.unconfigured": [],
        "hardware_components_initial_state.inactive": [],
        "diff_drive_controller.type": "diff_drive_controller/DiffDriveController",
        "joint_state_broadcaster.type": "joint_state_broadcaster/JointStateBroadcaster",
        "imu_sensor_broadcaster.type": "imu_sensor_broadcaster/IMUSensorBroadcaster",
        "diagnostics.threshold.controller_manager.periodicity.mean_error.warn": 5.0,
        "diagnostics.threshold.controller_manager.periodicity.mean_error.error": 10.0,
    },
    "diff_drive_controller": _diff_drive_controller(),
    "joint_state_broadcaster": {
        "type": "joint_state_broadcaster/JointStateBroadcaster",
        "joints": [],
        "interfaces": [],
        "use_local_topics": False,
        "use_urdf_to_filter": True,
        "map_interface_to_joint_state.position": "position",
        "map_interface_to_joint_state.velocity": "velocity",
        "map_interface_to_joint_state.effort": "effort",
        "extra_joints": [],
        "update_rate": 50,
    },
    "imu_sensor_broadcaster": {
        "type": "imu_sensor_broadcaster/IMUSensorBroadcaster",
        "sensor_name": "imu_sensor",
        "frame_id": "imu_link",
        "static_covariance_orientation": [0.0] * 9,
        "static_covariance_angular_velocity": [0.0] * 9,
        "static_covariance_linear_acceleration": [0.0] * 9,
        "update_rate": 100,
    },
    "ekf_filter_node": _ekf(),
    "rplidar_node": {
        "channel_type": "serial",
        "serial_port": "/dev/ttyUSB0",
        "serial_baudrate": 115200,
        "frame_id": "laser",
        "inverted": False,
        "angle_compensate": True,
        "scan_mode": "Standard",
        "scan_frequency": 10.0,
        "topic_name": "scan",
        "auto_standby": False,
        "flip_x_axis": False,
        "max_distance": 12.0,
    },
    "camera/camera": _realsense(),
    "imu_driver": {
        "port": "/dev/i2c-1",
        "frame_id": "imu_link",
        "rate": 100.0,
        "gyro_range": 2000,
        "accel_range": 4,
        "publish_magnetometer": False,
        "orientation_covariance": [0.01, 0.0, 0.0, 0.0, 0.01, 0.0, 0.0, 0.0, 0.01],
    },
    "twist_mux": {
        "topics.navigation.topic": "cmd_vel",
        "topics.navigation.timeout": 0.5,
        "topics.navigation.priority": 10,
        "topics.joystick.topic": "cmd_vel_joy",
        "topics.joystick.timeout": 0.5,
        "topics.joystick.priority": 100,
        "locks.pause.topic": "pause_navigation",
        "locks.pause.timeout": 0.0,
        "locks.pause.priority": 100,
        "locks.e_stop.topic": "e_stop",
        "locks.e_stop.timeout": 0.0,
        "locks.e_stop.priority": 255,
        "use_stamped": True,
    },
    "joy_node": {
        "device_id": 0,
        "device_name": "",
        "deadzone": 0.5,
        "autorepeat_rate": 20.0,
        "sticky_buttons": False,
        "coalesce_interval_ms": 1,
    },
    "teleop_twist_joy_node": {
        "require_enable_button": True,
        "enable_button": 5,
        "enable_turbo_button": 4,
        "axis_linear.x": 1,
        "axis_linear.y": -1,
        "axis_linear.z": -1,
        "axis_angular.yaw": 0,
        "axis_angular.pitch": -1,
        "axis_angular.roll": -1,
        "scale_linear.x": 0.5,
        "scale_linear.y": 0.0,
        "scale_linear.z": 0.0,
        "scale_linear_turbo.x": 1.0,
        "scale_linear_turbo.y": 0.0,
        "scale_linear_turbo.z": 0.0,
        "scale_angular.yaw": 0.5,
        "scale_angular.pitch": 0.0,
        "scale_angular.roll": 0.0,
        "scale_angular_turbo.yaw": 1.0,
        "scale_angular_turbo.pitch": 0.0,
        "scale_angular_turbo.roll": 0.0,
        "inverted_reverse": False,
        "publish_stamped_twist": True,
        "frame": "teleop_twist_joy",
    },
}
