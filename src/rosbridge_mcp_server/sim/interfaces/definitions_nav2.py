"""Interface texts of the Nav2 world: nav2_msgs, lifecycle_msgs, ros2_control's and the drivers' types.

Our own transcription of the Jazzy interfaces (field types, names, constants), comments left out, in the
ROS 2 form of :data:`~.definitions.COMMON`; a ROS 1 robot gets them through ``to_ros1_text`` (a ROS 1 robot
has no lifecycle, but the world keeps one graph for both dialects).
"""

from __future__ import annotations

__all__ = ["KILTED", "NAV2"]

#: nav2_msgs' error codes every Nav2 result starts with (each action adds its own from 100 on).
_ERRORS = "uint16 NONE=0\nuint16 UNKNOWN=1\n"
_RESULT = "uint16 error_code\nstring error_msg\n"

NAV2: dict[str, str] = {
    # --- lifecycle_msgs ----------------------------------------------------------------------------------
    "lifecycle_msgs/msg/State": (
        "uint8 PRIMARY_STATE_UNKNOWN = 0\nuint8 PRIMARY_STATE_UNCONFIGURED = 1\n"
        "uint8 PRIMARY_STATE_INACTIVE = 2\n"
        "uint8 PRIMARY_STATE_ACTIVE = 3\nuint8 PRIMARY_STATE_FINALIZED = 4\n"
        "uint8 TRANSITION_STATE_CONFIGURING = 10\nuint8 TRANSITION_STATE_CLEANINGUP = 11\n"
        "uint8 TRANSITION_STATE_SHUTTINGDOWN = 12\nuint8 TRANSITION_STATE_ACTIVATING = 13\n"
        "uint8 TRANSITION_STATE_DEACTIVATING = 14\nuint8 TRANSITION_STATE_ERRORPROCESSING = 15\n"
        "uint8 id\nstring label\n"
    ),
    "lifecycle_msgs/msg/Transition": (
        "uint8 TRANSITION_CREATE = 0\nuint8 TRANSITION_CONFIGURE = 1\nuint8 TRANSITION_CLEANUP = 2\n"
        "uint8 TRANSITION_ACTIVATE = 3\nuint8 TRANSITION_DEACTIVATE = 4\n"
        "uint8 TRANSITION_UNCONFIGURED_SHUTDOWN = 5\nuint8 TRANSITION_INACTIVE_SHUTDOWN = 6\n"
        "uint8 TRANSITION_ACTIVE_SHUTDOWN = 7\nuint8 TRANSITION_DESTROY = 8\n"
        "uint8 id\nstring label\n"
    ),
    "lifecycle_msgs/msg/TransitionDescription": (
        "Transition transition\nState start_state\nState goal_state\n"
    ),
    "lifecycle_msgs/msg/TransitionEvent": (
        "uint64 timestamp\nTransition transition\nState start_state\nState goal_state\n"
    ),
    "lifecycle_msgs/srv/ChangeState": "Transition transition\n---\nbool success\n",
    "lifecycle_msgs/srv/GetState": "---\nState current_state\n",
    "lifecycle_msgs/srv/GetAvailableStates": "---\nState[] available_states\n",
    "lifecycle_msgs/srv/GetAvailableTransitions": "---\nTransitionDescription[] available_transitions\n",
    "bond/msg/Status": (
        "std_msgs/Header header\nstring id\nstring instance_id\nbool active\nfloat32 heartbeat_timeout\n"
        "float32 heartbeat_period\n"
    ),
    # --- nav2_msgs: messages -----------------------------------------------------------------------------
    "nav2_msgs/msg/CostmapMetaData": (
        "builtin_interfaces/Time map_load_time\nbuiltin_interfaces/Time update_time\nstring layer\n"
        "float32 resolution\nuint32 size_x\nuint32 size_y\ngeometry_msgs/Pose origin\n"
    ),
    "nav2_msgs/msg/Costmap": "std_msgs/Header header\nCostmapMetaData metadata\nuint8[] data\n",
    "nav2_msgs/msg/CostmapUpdate": (
        "std_msgs/Header header\nuint32 x\nuint32 y\nuint32 size_x\nuint32 size_y\nuint8[] data\n"
    ),
    "nav2_msgs/msg/CostmapFilterInfo": (
        "std_msgs/Header header\nuint8 type\nstring filter_mask_topic\nfloat32 base\nfloat32 multiplier\n"
    ),
    "nav2_msgs/msg/SpeedLimit": "std_msgs/Header header\nbool percentage\nfloat64 speed_limit\n",
    "nav2_msgs/msg/Particle": "geometry_msgs/Pose pose\nfloat64 weight\n",
    "nav2_msgs/msg/ParticleCloud": "std_msgs/Header header\nParticle[] particles\n",
    "nav2_msgs/msg/BehaviorTreeStatusChange": (
        "builtin_interfaces/Time timestamp\nuint16 node_uid\nstring node_name\nstring uid\n"
        "string previous_status\nstring current_status\n"
    ),
    "nav2_msgs/msg/BehaviorTreeLog": (
        "builtin_interfaces/Time timestamp\nBehaviorTreeStatusChange[] event_log\n"
    ),
    "nav2_msgs/msg/CollisionMonitorState": (
        "uint8 DO_NOTHING=0\nuint8 STOP=1\nuint8 SLOWDOWN=2\nuint8 APPROACH=3\nuint8 LIMIT=4\n"
        "uint8 action_type\nstring polygon_name\n"
    ),
    "nav2_msgs/msg/WaypointStatus": (
        "uint8 PENDING=0\nuint8 COMPLETED=1\nuint8 SKIPPED=2\nuint8 FAILED=3\n"
        "uint8 waypoint_status\nuint32 waypoint_index\ngeometry_msgs/PoseStamped waypoint_pose\n"
        "uint16 error_code\nstring error_msg\n"
    ),
    "nav2_msgs/msg/VoxelGrid": (
        "std_msgs/Header header\nuint32[] data\ngeometry_msgs/Point32 origin\n"
        "geometry_msgs/Vector3 resolutions\nuint32 size_x\nuint32 size_y\nuint32 size_z\n"
    ),
    # --- nav2_msgs: services -----------------------------------------------------------------------------
    "nav2_msgs/srv/ManageLifecycleNodes": (
        "uint8 STARTUP = 0\nuint8 PAUSE = 1\nuint8 RESUME = 2\nuint8 RESET = 3\nuint8 SHUTDOWN = 4\n"
        "uint8 CONFIGURE = 5\nuint8 CLEANUP = 6\nuint8 command\n---\nbool success\n"
    ),
    "nav2_msgs/srv/LoadMap": (
        "string map_url\n---\nuint8 RESULT_SUCCESS=0\nuint8 RESULT_MAP_DOES_NOT_EXIST=1\n"
        "uint8 RESULT_INVALID_MAP_DATA=2\nuint8 RESULT_INVALID_MAP_METADATA=3\n"
        "uint8 RESULT_UNDEFINED_FAILURE=255\n"
        "nav_msgs/OccupancyGrid map\nuint8 result\n"
    ),
    "nav2_msgs/srv/SaveMap": (
        "string map_topic\nstring map_url\nstring image_format\nstring map_mode\nfloat32 free_thresh\n"
        "float32 occupied_thresh\n---\nbool result\n"
    ),
    "nav2_msgs/srv/ClearEntireCostmap": "std_msgs/Empty request\n---\nstd_msgs/Empty response\n",
    "nav2_msgs/srv/ClearCostmapAroundRobot": "float32 reset_distance\n---\nstd_msgs/Empty response\n",
    "nav2_msgs/srv/ClearCostmapExceptRegion": "float32 reset_distance\n---\nstd_msgs/Empty response\n",
    "nav2_msgs/srv/GetCostmap": "CostmapMetaData specs\n---\nCostmap map\n",
    "nav2_msgs/srv/IsPathValid": (
        "nav_msgs/Path path\nfloat32 max_cost\nbool consider_unknown_as_obstacle\n---\nbool is_valid\n"
        "int32[] invalid_pose_indices\n"
    ),
    "nav2_msgs/srv/SetInitialPose": "geometry_msgs/PoseWithCovarianceStamped pose\n---\n",
    "nav2_msgs/srv/ReloadDockDatabase": "string filepath\n---\nbool success\n",
    # --- nav2_msgs: actions ------------------------------------------------------------------------------
    "nav2_msgs/action/NavigateToPose": (
        "geometry_msgs/PoseStamped pose\nstring behavior_tree\n---\n"
        f"{_ERRORS}uint16 FAILED_TO_LOAD_BEHAVIOR_TREE=901\nuint16 TF_ERROR=902\n{_RESULT}---\n"
        "geometry_msgs/PoseStamped current_pose\nbuiltin_interfaces/Duration navigation_time\n"
        "builtin_interfaces/Duration estimated_time_remaining\nint16 number_of_recoveries\n"
        "float32 distance_remaining\n"
    ),
    "nav2_msgs/action/NavigateThroughPoses": (
        "geometry_msgs/PoseStamped[] poses\nstring behavior_tree\n---\n"
        f"{_ERRORS}uint16 FAILED_TO_LOAD_BEHAVIOR_TREE=901\nuint16 TF_ERROR=902\n{_RESULT}---\n"
        "geometry_msgs/PoseStamped current_pose\nbuiltin_interfaces/Duration navigation_time\n"
        "builtin_interfaces/Duration estimated_time_remaining\nint16 number_of_recoveries\n"
        "float32 distance_remaining\nint16 number_of_poses_remaining\n"
    ),
    "nav2_msgs/action/FollowPath": (
        "nav_msgs/Path path\nstring controller_id\nstring goal_checker_id\nstring progress_checker_id\n---\n"
        f"{_ERRORS}uint16 INVALID_CONTROLLER=101\nuint16 TF_ERROR=102\nuint16 INVALID_PATH=103\n"
        "uint16 PATIENCE_EXCEEDED=104\nuint16 FAILED_TO_MAKE_PROGRESS=105\nuint16 NO_VALID_CONTROL=106\n"
        f"std_msgs/Empty result\n{_RESULT}---\nfloat32 distance_to_goal\nfloat32 speed\n"
    ),
    "nav2_msgs/action/ComputePathToPose": (
        "geometry_msgs/PoseStamped goal\ngeometry_msgs/PoseStamped start\nstring planner_id\nbool use_start\n"
        f"---\n{_ERRORS}uint16 INVALID_PLANNER=201\nuint16 TF_ERROR=202\nuint16 START_OUTSIDE_MAP=203\n"
        "uint16 GOAL_OUTSIDE_MAP=204\nuint16 START_OCCUPIED=205\nuint16 GOAL_OCCUPIED=206\n"
        "uint16 TIMEOUT=207\nuint16 NO_VALID_PATH=208\n"
        f"nav_msgs/Path path\nbuiltin_interfaces/Duration planning_time\n{_RESULT}---\n"
    ),
    "nav2_msgs/action/ComputePathThroughPoses": (
        "geometry_msgs/PoseStamped[] goals\ngeometry_msgs/PoseStamped start\nstring planner_id\n"
        f"bool use_start\n---\n{_ERRORS}uint16 INVALID_PLANNER=301\nuint16 TF_ERROR=302\n"
        "uint16 NO_VALID_PATH=308\nuint16 NO_VIAPOINTS_GIVEN=309\n"
        f"nav_msgs/Path path\nbuiltin_interfaces/Duration planning_time\n{_RESULT}---\n"
    ),
    "nav2_msgs/action/SmoothPath": (
        "nav_msgs/Path path\nstring smoother_id\nbuiltin_interfaces/Duration max_smoothing_duration\n"
        f"bool check_for_collisions\n---\n{_ERRORS}uint16 INVALID_SMOOTHER=501\nuint16 TIMEOUT=502\n"
        "uint16 SMOOTHED_PATH_IN_COLLISION=503\nuint16 FAILED_TO_SMOOTH_PATH=504\nuint16 INVALID_PATH=505\n"
        "nav_msgs/Path path\nbuiltin_interfaces/Duration smoothing_duration\nbool was_completed\n"
        f"{_RESULT}---\n"
    ),
    "nav2_msgs/action/Spin": (
        "float32 target_yaw\nbuiltin_interfaces/Duration time_allowance\nbool disable_collision_checks\n---\n"
        f"{_ERRORS}uint16 TIMEOUT=701\nuint16 TF_ERROR=702\nuint16 COLLISION_AHEAD=703\n"
        f"builtin_interfaces/Duration total_elapsed_time\n{_RESULT}---\nfloat32 angular_distance_traveled\n"
    ),
    "nav2_msgs/action/BackUp": (
        "geometry_msgs/Point target\nfloat32 speed\nbuiltin_interfaces/Duration time_allowance\n"
        f"bool disable_collision_checks\n---\n{_ERRORS}uint16 TIMEOUT=701\nuint16 TF_ERROR=702\n"
        "uint16 INVALID_INPUT=703\nuint16 COLLISION_AHEAD=704\n"
        f"builtin_interfaces/Duration total_elapsed_time\n{_RESULT}---\nfloat32 distance_traveled\n"
    ),
    "nav2_msgs/action/DriveOnHeading": (
        "geometry_msgs/Point target\nfloat32 speed\nbuiltin_interfaces/Duration time_allowance\n"
        f"bool disable_collision_checks\n---\n{_ERRORS}uint16 TIMEOUT=701\nuint16 TF_ERROR=702\n"
        "uint16 INVALID_INPUT=703\nuint16 COLLISION_AHEAD=704\n"
        f"builtin_interfaces/Duration total_elapsed_time\n{_RESULT}---\nfloat32 distance_traveled\n"
    ),
    "nav2_msgs/action/Wait": (
        "builtin_interfaces/Duration time\n---\n"
        f"{_ERRORS}builtin_interfaces/Duration total_elapsed_time\n{_RESULT}---\n"
        "builtin_interfaces/Duration time_left\n"
    ),
    "nav2_msgs/action/AssistedTeleop": (
        "builtin_interfaces/Duration time_allowance\n---\n"
        f"{_ERRORS}uint16 TIMEOUT=701\nbuiltin_interfaces/Duration total_elapsed_time\n{_RESULT}---\n"
        "builtin_interfaces/Duration current_teleop_duration\n"
    ),
    "nav2_msgs/action/FollowWaypoints": (
        "uint32 number_of_loops\nuint32 goal_index 0\ngeometry_msgs/PoseStamped[] poses\n---\n"
        f"{_ERRORS}uint16 TASK_EXECUTOR_FAILED=601\nuint16 NO_VALID_WAYPOINTS=602\n"
        f"WaypointStatus[] missed_waypoints\n{_RESULT}---\nuint32 current_waypoint\n"
    ),
    "nav2_msgs/action/DockRobot": (
        "bool use_dock_id true\nstring dock_id\ngeometry_msgs/PoseStamped dock_pose\nstring dock_type\n"
        "float32 max_staging_time 1000.0\nbool navigate_to_staging_pose true\n---\n"
        "uint16 NONE=0\nuint16 DOCK_NOT_IN_DB=901\nuint16 DOCK_NOT_VALID=902\nuint16 FAILED_TO_STAGE=903\n"
        "uint16 FAILED_TO_DETECT_DOCK=904\nuint16 FAILED_TO_CONTROL=905\nuint16 FAILED_TO_CHARGE=906\n"
        "uint16 UNKNOWN=999\nbool success true\nuint16 error_code\nuint16 num_retries\n---\n"
        "uint16 NONE=0\nuint16 NAV_TO_STAGING_POSE=1\nuint16 INITIAL_PERCEPTION=2\nuint16 CONTROLLING=3\n"
        "uint16 WAIT_FOR_CHARGE=4\nuint16 RETRY=5\nuint16 state\n"
        "builtin_interfaces/Duration docking_time\nuint16 num_retries\n"
    ),
    "nav2_msgs/action/UndockRobot": (
        "string dock_type\nfloat32 max_undocking_time 30.0\n---\n"
        "uint16 NONE=0\nuint16 DOCK_NOT_VALID=902\nuint16 FAILED_TO_CONTROL=905\nuint16 UNKNOWN=999\n"
        "bool success true\nuint16 error_code\n---\n"
    ),
    # --- ros2_control --------------------------------------------------------------------------------------
    "controller_manager_msgs/msg/ControllerState": (
        "string name\nstring state\nstring type\nbool is_async\nuint16 update_rate\nbool is_chainable\n"
        "bool is_chained\nstring[] claimed_interfaces\nstring[] required_command_interfaces\n"
        "string[] required_state_interfaces\n"
    ),
    "controller_manager_msgs/msg/HardwareInterface": "string name\nbool is_available\nbool is_claimed\n",
    "controller_manager_msgs/msg/HardwareComponentState": (
        "string name\nstring type\nstring plugin_name\nlifecycle_msgs/State state\n"
        "HardwareInterface[] command_interfaces\nHardwareInterface[] state_interfaces\n"
    ),
    "controller_manager_msgs/srv/ListControllers": "---\nControllerState[] controller\n",
    "controller_manager_msgs/srv/ListControllerTypes": "---\nstring[] types\nstring[] base_classes\n",
    "controller_manager_msgs/srv/ListHardwareComponents": "---\nHardwareComponentState[] component\n",
    "controller_manager_msgs/srv/ListHardwareInterfaces": (
        "---\nHardwareInterface[] command_interfaces\nHardwareInterface[] state_interfaces\n"
    ),
    "controller_manager_msgs/srv/LoadController": "string name\n---\nbool ok\n",
    "controller_manager_msgs/srv/ConfigureController": "string name\n---\nbool ok\n",
    "controller_manager_msgs/srv/UnloadController": "string name\n---\nbool ok\n",
    "controller_manager_msgs/srv/ReloadControllerLibraries": "bool force_kill\n---\nbool ok\n",
    "controller_manager_msgs/srv/SwitchController": (
        "string[] activate_controllers\nstring[] deactivate_controllers\nint32 BEST_EFFORT=1\n"
        "int32 STRICT=2\nint32 strictness 0\nbool activate_asap false\n"
        "builtin_interfaces/Duration timeout\n---\nbool ok\n"
    ),
    "controller_manager_msgs/srv/SetHardwareComponentState": (
        "string name\nlifecycle_msgs/State target_state\n---\nbool ok\nlifecycle_msgs/State state\n"
    ),
    "control_msgs/msg/InterfaceValue": "string[] interface_names\nfloat64[] values\n",
    "control_msgs/msg/DynamicJointState": (
        "std_msgs/Header header\nstring[] joint_names\nInterfaceValue[] interface_values\n"
    ),
    # --- drivers and friends -------------------------------------------------------------------------------
    "sensor_msgs/msg/Joy": "std_msgs/Header header\nfloat32[] axes\nint32[] buttons\n",
    "sensor_msgs/msg/JoyFeedback": (
        "uint8 TYPE_LED    = 0\nuint8 TYPE_RUMBLE = 1\nuint8 TYPE_BUZZER = 2\n"
        "uint8 type\nuint8 id\nfloat32 intensity\n"
    ),
    "diagnostic_msgs/msg/KeyValue": "string key\nstring value\n",
    "diagnostic_msgs/msg/DiagnosticStatus": (
        "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\n"
        "byte level\nstring name\nstring message\nstring hardware_id\nKeyValue[] values\n"
    ),
    "diagnostic_msgs/msg/DiagnosticArray": "std_msgs/Header header\nDiagnosticStatus[] status\n",
    "map_msgs/msg/OccupancyGridUpdate": (
        "std_msgs/Header header\nint32 x\nint32 y\nuint32 width\nuint32 height\nint8[] data\n"
    ),
    "robot_localization/srv/SetPose": "geometry_msgs/PoseWithCovarianceStamped pose\n---\n",
    "robot_localization/srv/ToggleFilterProcessing": "bool on\n---\nbool status\n",
}

#: What Kilted (and Rolling) changed: NavigateThroughPoses and ComputePathThroughPoses take their poses as one
#: ``nav_msgs/Goals`` (a header and the poses), not as a list of PoseStamped.
KILTED: dict[str, str] = {
    "nav_msgs/msg/Goals": "std_msgs/Header header\ngeometry_msgs/PoseStamped[] goals\n",
    "nav2_msgs/action/NavigateThroughPoses": NAV2["nav2_msgs/action/NavigateThroughPoses"].replace(
        "geometry_msgs/PoseStamped[] poses\n", "nav_msgs/Goals poses\n", 1
    ),
    "nav2_msgs/action/ComputePathThroughPoses": NAV2["nav2_msgs/action/ComputePathThroughPoses"].replace(
        "geometry_msgs/PoseStamped[] goals\n", "nav_msgs/Goals goals\n", 1
    ),
}
