"""Interface texts of the arm world: ROS 2 Jazzy (:data:`ARM`: control_msgs 5.x, trajectory_msgs;
ros2_control's controller_manager_msgs are in :mod:`.definitions_nav2`) and ROS 1 Noetic (:data:`ARM_ROS1`,
written in ROS 2 form and rewritten by ``to_ros1_text``: control_msgs 1.5 has no multi-DOF trajectory or
component tolerances; ros_control's controller_manager_msgs list ``claimed_resources`` and switch with
``start_controllers`` / ``stop_controllers``)."""

from __future__ import annotations

__all__ = ["ARM", "ARM_ROS1"]

_TOLERANCES = (
    "control_msgs/JointTolerance[] path_tolerance\n"
    "control_msgs/JointComponentTolerance[] component_path_tolerance\n"
    "control_msgs/JointTolerance[] goal_tolerance\n"
    "control_msgs/JointComponentTolerance[] component_goal_tolerance\n"
    "builtin_interfaces/Duration goal_time_tolerance\n"
)

ARM: dict[str, str] = {
    "trajectory_msgs/msg/JointTrajectoryPoint": (
        "float64[] positions\nfloat64[] velocities\nfloat64[] accelerations\nfloat64[] effort\n"
        "builtin_interfaces/Duration time_from_start\n"
    ),
    "trajectory_msgs/msg/JointTrajectory": (
        "std_msgs/Header header\nstring[] joint_names\nJointTrajectoryPoint[] points\n"
    ),
    "trajectory_msgs/msg/MultiDOFJointTrajectoryPoint": (
        "geometry_msgs/Transform[] transforms\ngeometry_msgs/Twist[] velocities\n"
        "geometry_msgs/Twist[] accelerations\nbuiltin_interfaces/Duration time_from_start\n"
    ),
    "trajectory_msgs/msg/MultiDOFJointTrajectory": (
        "std_msgs/Header header\nstring[] joint_names\nMultiDOFJointTrajectoryPoint[] points\n"
    ),
    "control_msgs/msg/JointTolerance": (
        "string name\nfloat64 position\nfloat64 velocity\nfloat64 acceleration\n"
    ),
    "control_msgs/msg/JointComponentTolerance": (
        "uint16 X_AXIS=1\nuint16 Y_AXIS=2\nuint16 Z_AXIS=3\nuint16 TRANSLATION=4\nuint16 ROTATION=5\n"
        "string joint_name\nuint16 component\nfloat64 position\nfloat64 velocity\nfloat64 acceleration\n"
    ),
    "control_msgs/msg/GripperCommand": "float64 position\nfloat64 max_effort\n",
    "control_msgs/action/FollowJointTrajectory": (
        "trajectory_msgs/JointTrajectory trajectory\n"
        "trajectory_msgs/MultiDOFJointTrajectory multi_dof_trajectory\n"
        + _TOLERANCES
        + "---\nint32 error_code\nint32 SUCCESSFUL = 0\nint32 INVALID_GOAL = -1\nint32 INVALID_JOINTS = -2\n"
        "int32 OLD_HEADER_TIMESTAMP = -3\nint32 PATH_TOLERANCE_VIOLATED = -4\n"
        "int32 GOAL_TOLERANCE_VIOLATED = -5\n"
        "string error_string\n---\nstd_msgs/Header header\nstring[] joint_names\n"
        "trajectory_msgs/JointTrajectoryPoint desired\ntrajectory_msgs/JointTrajectoryPoint actual\n"
        "trajectory_msgs/JointTrajectoryPoint error\nstring[] multi_dof_joint_names\n"
        "trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_desired\n"
        "trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_actual\n"
        "trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_error\n"
    ),
    "control_msgs/action/GripperCommand": (
        "control_msgs/GripperCommand command\n---\nfloat64 position\nfloat64 effort\nbool stalled\n"
        "bool reached_goal\n---\nfloat64 position\nfloat64 effort\nbool stalled\nbool reached_goal\n"
    ),
}

#: ROS 1 Noetic's forms, where they differ from ROS 2's (these replace the ROS 2 texts in the ROS 1 table).
ARM_ROS1: dict[str, str] = {
    **{
        key: ARM[key]
        for key in ("trajectory_msgs/msg/JointTrajectoryPoint", "trajectory_msgs/msg/JointTrajectory")
    },
    "control_msgs/msg/JointTolerance": ARM["control_msgs/msg/JointTolerance"],
    "control_msgs/msg/GripperCommand": ARM["control_msgs/msg/GripperCommand"],
    "control_msgs/action/FollowJointTrajectory": (
        "trajectory_msgs/JointTrajectory trajectory\ncontrol_msgs/JointTolerance[] path_tolerance\n"
        "control_msgs/JointTolerance[] goal_tolerance\nbuiltin_interfaces/Duration goal_time_tolerance\n"
        "---\nint32 error_code\nint32 SUCCESSFUL = 0\nint32 INVALID_GOAL = -1\nint32 INVALID_JOINTS = -2\n"
        "int32 OLD_HEADER_TIMESTAMP = -3\nint32 PATH_TOLERANCE_VIOLATED = -4\n"
        "int32 GOAL_TOLERANCE_VIOLATED = -5\n"
        "string error_string\n---\nstd_msgs/Header header\nstring[] joint_names\n"
        "trajectory_msgs/JointTrajectoryPoint desired\ntrajectory_msgs/JointTrajectoryPoint actual\n"
        "trajectory_msgs/JointTrajectoryPoint error\n"
    ),
    "control_msgs/action/GripperCommand": ARM["control_msgs/action/GripperCommand"],
    "controller_manager_msgs/msg/HardwareInterfaceResources": (
        "string hardware_interface\nstring[] resources\n"
    ),
    "controller_manager_msgs/msg/ControllerState": (
        "string name\nstring state\nstring type\n"
        "controller_manager_msgs/HardwareInterfaceResources[] claimed_resources\n"
    ),
    "controller_manager_msgs/srv/ListControllers": (
        "---\ncontroller_manager_msgs/ControllerState[] controller\n"
    ),
    "controller_manager_msgs/srv/SwitchController": (
        "string[] start_controllers\nstring[] stop_controllers\nint32 strictness\nint32 BEST_EFFORT=1\n"
        "int32 STRICT=2\nbool start_asap\nfloat64 timeout\n---\nbool ok\n"
    ),
}
