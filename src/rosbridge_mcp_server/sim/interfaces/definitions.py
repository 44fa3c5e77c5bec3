"""Interface definition texts of the simulated robot, in the ROS .msg/.srv/.action syntax.

Our own transcription of the standard interfaces (field types, names, array forms, constants, ROS 2
defaults); comments are left out. Keys are ``pkg/kind/Name``. ``COMMON`` is written in ROS 2 form and turned
into ROS 1 form by :func:`to_ros1_text` (``builtin_interfaces/Time`` -> ``time``, ``std_msgs/Header`` ->
``Header``, defaults dropped), so a type that reads the same in both dialects is written once.
"""

from __future__ import annotations

__all__ = ["COMMON", "ROS1_ONLY", "ROS2_ONLY", "ROSAPI_2_1", "to_ros1_text"]


_STD_SCALARS = {
    "Bool": "bool",
    "Byte": "byte",
    "Char": "char",
    "Int8": "int8",
    "Int16": "int16",
    "Int32": "int32",
    "Int64": "int64",
    "UInt8": "uint8",
    "UInt16": "uint16",
    "UInt32": "uint32",
    "UInt64": "uint64",
    "Float32": "float32",
    "Float64": "float64",
    "String": "string",
}

_STD_MULTI = {
    "ByteMultiArray": "byte",
    "Int8MultiArray": "int8",
    "Int16MultiArray": "int16",
    "Int32MultiArray": "int32",
    "Int64MultiArray": "int64",
    "UInt8MultiArray": "uint8",
    "UInt16MultiArray": "uint16",
    "UInt32MultiArray": "uint32",
    "UInt64MultiArray": "uint64",
    "Float32MultiArray": "float32",
    "Float64MultiArray": "float64",
}

_STAMPED_GEOMETRY = {
    "Vector3Stamped": "Vector3 vector",
    "PointStamped": "Point point",
    "QuaternionStamped": "Quaternion quaternion",
    "PoseStamped": "Pose pose",
    "PoseWithCovarianceStamped": "PoseWithCovariance pose",
    "TwistStamped": "Twist twist",
    "TwistWithCovarianceStamped": "TwistWithCovariance twist",
    "AccelStamped": "Accel accel",
    "AccelWithCovarianceStamped": "AccelWithCovariance accel",
    "WrenchStamped": "Wrench wrench",
    "PolygonStamped": "Polygon polygon",
    "InertiaStamped": "Inertia inertia",
}

COMMON: dict[str, str] = {
    **{f"std_msgs/msg/{name}": f"{prim} data\n" for name, prim in _STD_SCALARS.items()},
    **{
        f"std_msgs/msg/{name}": f"MultiArrayLayout layout\n{prim}[] data\n"
        for name, prim in _STD_MULTI.items()
    },
    "std_msgs/msg/Empty": "",
    "std_msgs/msg/ColorRGBA": "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n",
    "std_msgs/msg/MultiArrayDimension": "string label\nuint32 size\nuint32 stride\n",
    "std_msgs/msg/MultiArrayLayout": "MultiArrayDimension[] dim\nuint32 data_offset\n",
    # geometry_msgs
    "geometry_msgs/msg/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Point32": "float32 x\nfloat32 y\nfloat32 z\n",
    "geometry_msgs/msg/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/msg/Pose": "Point position\nQuaternion orientation\n",
    "geometry_msgs/msg/Pose2D": "float64 x\nfloat64 y\nfloat64 theta\n",
    "geometry_msgs/msg/PoseArray": "std_msgs/Header header\nPose[] poses\n",
    "geometry_msgs/msg/PoseWithCovariance": "Pose pose\nfloat64[36] covariance\n",
    "geometry_msgs/msg/Twist": "Vector3 linear\nVector3 angular\n",
    "geometry_msgs/msg/TwistWithCovariance": "Twist twist\nfloat64[36] covariance\n",
    "geometry_msgs/msg/Accel": "Vector3 linear\nVector3 angular\n",
    "geometry_msgs/msg/AccelWithCovariance": "Accel accel\nfloat64[36] covariance\n",
    "geometry_msgs/msg/Wrench": "Vector3 force\nVector3 torque\n",
    "geometry_msgs/msg/Transform": "Vector3 translation\nQuaternion rotation\n",
    "geometry_msgs/msg/TransformStamped": (
        "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"
    ),
    "geometry_msgs/msg/Polygon": "Point32[] points\n",
    "geometry_msgs/msg/Inertia": (
        "float64 m\nVector3 com\nfloat64 ixx\nfloat64 ixy\nfloat64 ixz\nfloat64 iyy\nfloat64 iyz\n"
        "float64 izz\n"
    ),
    **{
        f"geometry_msgs/msg/{name}": f"std_msgs/Header header\n{field}\n"
        for name, field in _STAMPED_GEOMETRY.items()
    },
    # sensor_msgs
    "sensor_msgs/msg/Image": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\n"
        "uint32 step\nuint8[] data\n"
    ),
    "sensor_msgs/msg/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data\n",
    "sensor_msgs/msg/RegionOfInterest": (
        "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n"
    ),
    "sensor_msgs/msg/LaserScan": (
        "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\n"
        "float32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\n"
        "float32[] ranges\nfloat32[] intensities\n"
    ),
    "sensor_msgs/msg/Imu": (
        "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
        "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
        "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n"
    ),
    "sensor_msgs/msg/JointState": (
        "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n"
    ),
    "sensor_msgs/msg/BatteryState": (
        "uint8 POWER_SUPPLY_STATUS_UNKNOWN = 0\nuint8 POWER_SUPPLY_STATUS_CHARGING = 1\n"
        "uint8 POWER_SUPPLY_STATUS_DISCHARGING = 2\nuint8 POWER_SUPPLY_STATUS_NOT_CHARGING = 3\n"
        "uint8 POWER_SUPPLY_STATUS_FULL = 4\n"
        "uint8 POWER_SUPPLY_HEALTH_UNKNOWN = 0\nuint8 POWER_SUPPLY_HEALTH_GOOD = 1\n"
        "uint8 POWER_SUPPLY_HEALTH_OVERHEAT = 2\nuint8 POWER_SUPPLY_HEALTH_DEAD = 3\n"
        "uint8 POWER_SUPPLY_HEALTH_OVERVOLTAGE = 4\nuint8 POWER_SUPPLY_HEALTH_UNSPEC_FAILURE = 5\n"
        "uint8 POWER_SUPPLY_HEALTH_COLD = 6\nuint8 POWER_SUPPLY_HEALTH_WATCHDOG_TIMER_EXPIRE = 7\n"
        "uint8 POWER_SUPPLY_HEALTH_SAFETY_TIMER_EXPIRE = 8\n"
        "uint8 POWER_SUPPLY_TECHNOLOGY_UNKNOWN = 0\nuint8 POWER_SUPPLY_TECHNOLOGY_NIMH = 1\n"
        "uint8 POWER_SUPPLY_TECHNOLOGY_LION = 2\nuint8 POWER_SUPPLY_TECHNOLOGY_LIPO = 3\n"
        "uint8 POWER_SUPPLY_TECHNOLOGY_LIFE = 4\nuint8 POWER_SUPPLY_TECHNOLOGY_NICD = 5\n"
        "uint8 POWER_SUPPLY_TECHNOLOGY_LIMN = 6\n"
        "std_msgs/Header header\nfloat32 voltage\nfloat32 temperature\nfloat32 current\nfloat32 charge\n"
        "float32 capacity\nfloat32 design_capacity\nfloat32 percentage\nuint8 power_supply_status\n"
        "uint8 power_supply_health\nuint8 power_supply_technology\nbool present\nfloat32[] cell_voltage\n"
        "float32[] cell_temperature\nstring location\nstring serial_number\n"
    ),
    "sensor_msgs/msg/NavSatStatus": (
        "int8 STATUS_NO_FIX = -1\nint8 STATUS_FIX = 0\nint8 STATUS_SBAS_FIX = 1\nint8 STATUS_GBAS_FIX = 2\n"
        "int8 status\n"
        "uint16 SERVICE_GPS = 1\nuint16 SERVICE_GLONASS = 2\nuint16 SERVICE_COMPASS = 4\n"
        "uint16 SERVICE_GALILEO = 8\nuint16 service\n"
    ),
    "sensor_msgs/msg/NavSatFix": (
        "std_msgs/Header header\nNavSatStatus status\nfloat64 latitude\nfloat64 longitude\nfloat64 altitude\n"
        "float64[9] position_covariance\n"
        "uint8 COVARIANCE_TYPE_UNKNOWN = 0\nuint8 COVARIANCE_TYPE_APPROXIMATED = 1\n"
        "uint8 COVARIANCE_TYPE_DIAGONAL_KNOWN = 2\nuint8 COVARIANCE_TYPE_KNOWN = 3\n"
        "uint8 position_covariance_type\n"
    ),
    "sensor_msgs/msg/Range": (
        "uint8 ULTRASOUND = 0\nuint8 INFRARED = 1\n"
        "std_msgs/Header header\nuint8 radiation_type\nfloat32 field_of_view\nfloat32 min_range\n"
        "float32 max_range\nfloat32 range\n"
    ),
    "sensor_msgs/msg/Temperature": "std_msgs/Header header\nfloat64 temperature\nfloat64 variance\n",
    "sensor_msgs/msg/PointField": (
        "uint8 INT8    = 1\nuint8 UINT8   = 2\nuint8 INT16   = 3\nuint8 UINT16  = 4\nuint8 INT32   = 5\n"
        "uint8 UINT32  = 6\nuint8 FLOAT32 = 7\nuint8 FLOAT64 = 8\n"
        "string name\nuint32 offset\nuint8 datatype\nuint32 count\n"
    ),
    "sensor_msgs/msg/PointCloud2": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\nbool is_bigendian\n"
        "uint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n"
    ),
    # nav_msgs
    "nav_msgs/msg/MapMetaData": (
        "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\nuint32 height\n"
        "geometry_msgs/Pose origin\n"
    ),
    "nav_msgs/msg/OccupancyGrid": "std_msgs/Header header\nMapMetaData info\nint8[] data\n",
    "nav_msgs/msg/Odometry": (
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n"
        "geometry_msgs/TwistWithCovariance twist\n"
    ),
    "nav_msgs/msg/Path": "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n",
    "nav_msgs/srv/GetMap": "---\nnav_msgs/OccupancyGrid map\n",
    "tf2_msgs/msg/TFMessage": "geometry_msgs/TransformStamped[] transforms\n",
    # std_srvs
    "std_srvs/srv/Empty": "---\n",
    "std_srvs/srv/Trigger": "---\nbool success\nstring message\n",
    "std_srvs/srv/SetBool": "bool data\n---\nbool success\nstring message\n",
    # turtlesim
    "turtlesim/msg/Pose": (
        "float32 x\nfloat32 y\nfloat32 theta\n\nfloat32 linear_velocity\nfloat32 angular_velocity\n"
    ),
    "turtlesim/msg/Color": "uint8 r\nuint8 g\nuint8 b\n",
    "turtlesim/srv/Spawn": "float32 x\nfloat32 y\nfloat32 theta\nstring name\n---\nstring name\n",
    "turtlesim/srv/Kill": "string name\n---\n",
    "turtlesim/srv/TeleportAbsolute": "float32 x\nfloat32 y\nfloat32 theta\n---\n",
    "turtlesim/srv/TeleportRelative": "float32 linear\nfloat32 angular\n---\n",
    "turtlesim/srv/SetPen": "uint8 r\nuint8 g\nuint8 b\nuint8 width\nuint8 off\n---\n",
    "rosgraph_msgs/msg/Clock": "builtin_interfaces/Time clock\n",
    # rosbridge's own topics (/client_count is std_msgs Int32)
    "rosbridge_msgs/msg/ConnectedClient": "string ip_address\nbuiltin_interfaces/Time connection_time\n",
    "rosbridge_msgs/msg/ConnectedClients": "ConnectedClient[] clients\n",
}

ROS2_ONLY: dict[str, str] = {
    "std_msgs/msg/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "builtin_interfaces/msg/Time": "int32 sec\nuint32 nanosec\n",
    "builtin_interfaces/msg/Duration": "int32 sec\nuint32 nanosec\n",
    "unique_identifier_msgs/msg/UUID": "uint8[16] uuid\n",
    "sensor_msgs/msg/CameraInfo": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\n"
        "float64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\n"
        "RegionOfInterest roi\n"
    ),
    # action_msgs
    "action_msgs/msg/GoalInfo": "unique_identifier_msgs/UUID goal_id\nbuiltin_interfaces/Time stamp\n",
    "action_msgs/msg/GoalStatus": (
        "int8 STATUS_UNKNOWN   = 0\nint8 STATUS_ACCEPTED  = 1\nint8 STATUS_EXECUTING = 2\n"
        "int8 STATUS_CANCELING = 3\nint8 STATUS_SUCCEEDED = 4\nint8 STATUS_CANCELED  = 5\n"
        "int8 STATUS_ABORTED   = 6\n\nGoalInfo goal_info\nint8 status\n"
    ),
    "action_msgs/msg/GoalStatusArray": "GoalStatus[] status_list\n",
    "action_msgs/srv/CancelGoal": (
        "GoalInfo goal_info\n---\n"
        "int8 ERROR_NONE = 0\nint8 ERROR_REJECTED = 1\nint8 ERROR_UNKNOWN_GOAL_ID = 2\n"
        "int8 ERROR_GOAL_TERMINATED = 3\nint8 return_code\nGoalInfo[] goals_canceling\n"
    ),
    # rcl_interfaces
    "rcl_interfaces/msg/ParameterType": (
        "uint8 PARAMETER_NOT_SET=0\nuint8 PARAMETER_BOOL=1\nuint8 PARAMETER_INTEGER=2\n"
        "uint8 PARAMETER_DOUBLE=3\nuint8 PARAMETER_STRING=4\nuint8 PARAMETER_BYTE_ARRAY=5\n"
        "uint8 PARAMETER_BOOL_ARRAY=6\nuint8 PARAMETER_INTEGER_ARRAY=7\nuint8 PARAMETER_DOUBLE_ARRAY=8\n"
        "uint8 PARAMETER_STRING_ARRAY=9\n"
    ),
    "rcl_interfaces/msg/ParameterValue": (
        "uint8 type\nbool bool_value\nint64 integer_value\nfloat64 double_value\nstring string_value\n"
        "byte[] byte_array_value\nbool[] bool_array_value\nint64[] integer_array_value\n"
        "float64[] double_array_value\nstring[] string_array_value\n"
    ),
    "rcl_interfaces/msg/Parameter": "string name\nParameterValue value\n",
    "rcl_interfaces/msg/SetParametersResult": "bool successful\nstring reason\n",
    "rcl_interfaces/msg/FloatingPointRange": "float64 from_value\nfloat64 to_value\nfloat64 step\n",
    "rcl_interfaces/msg/IntegerRange": "int64 from_value\nint64 to_value\nuint64 step\n",
    "rcl_interfaces/msg/ParameterDescriptor": (
        "string name\nuint8 type\nstring description\nstring additional_constraints\n"
        "bool read_only false\nbool dynamic_typing false\n"
        "FloatingPointRange[<=1] floating_point_range\nIntegerRange[<=1] integer_range\n"
    ),
    "rcl_interfaces/msg/ParameterEvent": (
        "builtin_interfaces/Time stamp\nstring node\nParameter[] new_parameters\n"
        "Parameter[] changed_parameters\nParameter[] deleted_parameters\n"
    ),
    "rcl_interfaces/msg/ListParametersResult": "string[] names\nstring[] prefixes\n",
    "rcl_interfaces/srv/DescribeParameters": "string[] names\n---\nParameterDescriptor[] descriptors\n",
    "rcl_interfaces/srv/GetParameterTypes": "string[] names\n---\nuint8[] types\n",
    "rcl_interfaces/srv/GetParameters": "string[] names\n---\nParameterValue[] values\n",
    "rcl_interfaces/srv/ListParameters": (
        "uint64 DEPTH_RECURSIVE=0\nstring[] prefixes\nuint64 depth\n---\nListParametersResult result\n"
    ),
    "rcl_interfaces/srv/SetParameters": "Parameter[] parameters\n---\nSetParametersResult[] results\n",
    "rcl_interfaces/srv/SetParametersAtomically": (
        "Parameter[] parameters\n---\nSetParametersResult result\n"
    ),
    "rcl_interfaces/msg/Log": (
        "byte DEBUG=10\nbyte INFO=20\nbyte WARN=30\nbyte ERROR=40\nbyte FATAL=50\n"
        "builtin_interfaces/Time stamp\nuint8 level\nstring name\nstring msg\nstring file\n"
        "string function\nuint32 line\n"
    ),
    # example_interfaces
    "example_interfaces/msg/Bool": "bool data\n",
    "example_interfaces/msg/Empty": "",
    "example_interfaces/msg/Float64": "float64 data\n",
    "example_interfaces/msg/Int32": "int32 data\n",
    "example_interfaces/msg/Int64": "int64 data\n",
    "example_interfaces/msg/String": "string data\n",
    "example_interfaces/srv/AddTwoInts": "int64 a\nint64 b\n---\nint64 sum\n",
    "example_interfaces/srv/SetBool": "bool data\n---\nbool success\nstring message\n",
    "example_interfaces/srv/Trigger": "---\nbool success\nstring message\n",
    "example_interfaces/action/Fibonacci": "int32 order\n---\nint32[] sequence\n---\nint32[] sequence\n",
    "turtlesim/action/RotateAbsolute": "float32 theta\n---\nfloat32 delta\n---\nfloat32 remaining\n",
    # rosapi_msgs (rosbridge_suite 2.x-4.x)
    "rosapi_msgs/msg/TypeDef": (
        "string type\nstring[] fieldnames\nstring[] fieldtypes\nint32[] fieldarraylen\nstring[] examples\n"
        "string[] constnames\nstring[] constvalues\n"
    ),
    "rosapi_msgs/srv/Topics": "\n---\nstring[] topics\nstring[] types\n",
    "rosapi_msgs/srv/TopicsForType": "string type\n---\nstring[] topics\n",
    "rosapi_msgs/srv/TopicsAndRawTypes": (
        "\n---\nstring[] topics\nstring[] types\nstring[] typedefs_full_text\n"
    ),
    "rosapi_msgs/srv/TopicType": "string topic\n---\nstring type\n",
    "rosapi_msgs/srv/Publishers": "string topic\n---\nstring[] publishers\n",
    "rosapi_msgs/srv/Subscribers": "string topic\n---\nstring[] subscribers\n",
    "rosapi_msgs/srv/Services": "\n---\nstring[] services\n",
    "rosapi_msgs/srv/ServicesForType": "string type\n---\nstring[] services\n",
    "rosapi_msgs/srv/ServiceType": "string service\n---\nstring type\n",
    "rosapi_msgs/srv/ServiceProviders": "string service\n---\nstring[] providers\n",
    "rosapi_msgs/srv/ServiceNode": "string service\n---\nstring node\n",
    "rosapi_msgs/srv/Nodes": "\n---\nstring[] nodes\n",
    "rosapi_msgs/srv/NodeDetails": (
        "string node\n---\nstring[] subscribing\nstring[] publishing\nstring[] services\n"
    ),
    "rosapi_msgs/srv/GetActionServers": "\n---\nstring[] action_servers\n",
    "rosapi_msgs/srv/MessageDetails": "string type\n---\nTypeDef[] typedefs\n",
    "rosapi_msgs/srv/ServiceRequestDetails": "string type\n---\nTypeDef[] typedefs\n",
    "rosapi_msgs/srv/ServiceResponseDetails": "string type\n---\nTypeDef[] typedefs\n",
    "rosapi_msgs/srv/ActionGoalDetails": "string type\n---\nTypeDef[] typedefs\n",
    "rosapi_msgs/srv/ActionResultDetails": "string type\n---\nTypeDef[] typedefs\n",
    "rosapi_msgs/srv/ActionFeedbackDetails": "string type\n---\nTypeDef[] typedefs\n",
    "rosapi_msgs/srv/ActionType": "string action\n---\nstring type\n",
    "rosapi_msgs/srv/GetParam": (
        "string name\nstring default_value\n---\nstring value\nbool successful\nstring reason\n"
    ),
    "rosapi_msgs/srv/SetParam": "string name\nstring value\n---\nbool successful\nstring reason\n",
    "rosapi_msgs/srv/HasParam": "string name\n---\nbool exists\n",
    "rosapi_msgs/srv/DeleteParam": "string name\n---\nbool successful\nstring reason\n",
    "rosapi_msgs/srv/GetParamNames": "---\nstring[] names\n",
    "rosapi_msgs/srv/GetTime": "---\nbuiltin_interfaces/Time time\n",
    "rosapi_msgs/srv/GetROSVersion": "---\nuint8 version\nstring distro\n",
    "rosapi_msgs/srv/Interfaces": "---\nstring[] interfaces\n",
}

ROS1_ONLY: dict[str, str] = {
    "std_msgs/msg/Header": "uint32 seq\ntime stamp\nstring frame_id\n",
    "std_msgs/msg/Time": "time data\n",
    "std_msgs/msg/Duration": "duration data\n",
    "sensor_msgs/msg/CameraInfo": (
        "Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] D\nfloat64[9] K\n"
        "float64[9] R\nfloat64[12] P\nuint32 binning_x\nuint32 binning_y\nRegionOfInterest roi\n"
    ),
    # actionlib_msgs
    "actionlib_msgs/msg/GoalID": "time stamp\nstring id\n",
    "actionlib_msgs/msg/GoalStatus": (
        "GoalID goal_id\nuint8 status\nuint8 PENDING         = 0\nuint8 ACTIVE          = 1\n"
        "uint8 PREEMPTED       = 2\nuint8 SUCCEEDED       = 3\nuint8 ABORTED         = 4\n"
        "uint8 REJECTED        = 5\nuint8 PREEMPTING      = 6\nuint8 RECALLING       = 7\n"
        "uint8 RECALLED        = 8\nuint8 LOST            = 9\n\nstring text\n"
    ),
    "actionlib_msgs/msg/GoalStatusArray": "Header header\nGoalStatus[] status_list\n",
    # move_base_msgs (ROS 1's navigation stack; the Nav2 world's move_base)
    "move_base_msgs/action/MoveBase": (
        "geometry_msgs/PoseStamped target_pose\n---\n---\ngeometry_msgs/PoseStamped base_position\n"
    ),
    # rosgraph_msgs
    "rosgraph_msgs/msg/Log": (
        "byte DEBUG=1\nbyte INFO=2\nbyte WARN=4\nbyte ERROR=8\nbyte FATAL=16\n"
        "Header header\nbyte level\nstring name\nstring msg\nstring file\nstring function\nuint32 line\n"
        "string[] topics\n"
    ),
    "roscpp/msg/Logger": "string name\nstring level\n",
    "roscpp/srv/GetLoggers": "---\nLogger[] loggers\n",
    "roscpp/srv/SetLoggerLevel": "string logger\nstring level\n---\n",
    # rospy_tutorials / actionlib_tutorials
    "rospy_tutorials/msg/Floats": "float32[] data\n",
    "rospy_tutorials/msg/HeaderString": "Header header\nstring data\n",
    "rospy_tutorials/srv/AddTwoInts": "int64 a\nint64 b\n---\nint64 sum\n",
    "rospy_tutorials/srv/BadTwoInts": "int64 a\nint32 b\n---\nint32 sum\n",
    "actionlib_tutorials/action/Fibonacci": "int32 order\n---\nint32[] sequence\n---\nint32[] sequence\n",
    "actionlib_tutorials/action/Averaging": (
        "int32 samples\n---\nfloat32 mean\nfloat32 std_dev\n---\nint32 sample\nfloat32 data\nfloat32 mean\n"
        "float32 std_dev\n"
    ),
    # rosapi (rosbridge_suite 0.11.x)
    "rosapi/msg/TypeDef": (
        "string type\nstring[] fieldnames\nstring[] fieldtypes\nint32[] fieldarraylen\nstring[] examples\n"
        "string[] constnames\nstring[] constvalues\n"
    ),
    "rosapi/srv/Topics": "\n---\nstring[] topics\nstring[] types\n",
    "rosapi/srv/TopicsForType": "string type\n---\nstring[] topics\n",
    "rosapi/srv/TopicsAndRawTypes": "\n---\nstring[] topics\nstring[] types\nstring[] typedefs_full_text\n",
    "rosapi/srv/TopicType": "string topic\n---\nstring type\n",
    "rosapi/srv/Publishers": "string topic\n---\nstring[] publishers\n",
    "rosapi/srv/Subscribers": "string topic\n---\nstring[] subscribers\n",
    "rosapi/srv/Services": "\n---\nstring[] services\n",
    "rosapi/srv/ServicesForType": "string type\n---\nstring[] services\n",
    "rosapi/srv/ServiceType": "string service\n---\nstring type\n",
    "rosapi/srv/ServiceProviders": "string service\n---\nstring[] providers\n",
    "rosapi/srv/ServiceNode": "string service\n---\nstring node\n",
    "rosapi/srv/ServiceHost": "string service\n---\nstring host\n",
    "rosapi/srv/Nodes": "\n---\nstring[] nodes\n",
    "rosapi/srv/NodeDetails": (
        "string node\n---\nstring[] subscribing\nstring[] publishing\nstring[] services\n"
    ),
    "rosapi/srv/GetActionServers": "\n---\nstring[] action_servers\n",
    "rosapi/srv/MessageDetails": "string type\n---\nTypeDef[] typedefs\n",
    "rosapi/srv/ServiceRequestDetails": "string type\n---\nTypeDef[] typedefs\n",
    "rosapi/srv/ServiceResponseDetails": "string type\n---\nTypeDef[] typedefs\n",
    "rosapi/srv/GetParam": "string name\nstring default\n---\nstring value\n",
    "rosapi/srv/SetParam": "string name\nstring value\n---\n",
    "rosapi/srv/HasParam": "string name\n---\nbool exists\n",
    "rosapi/srv/DeleteParam": "string name\n---\n",
    "rosapi/srv/GetParamNames": "---\nstring[] names\n",
    "rosapi/srv/SearchParam": "string name\n---\nstring global_name\n",
    "rosapi/srv/GetTime": "---\ntime time\n",
}

#: rosapi_msgs of rosbridge_suite 2.1.0 where they differ from the newest: ``None`` = not there yet.
ROSAPI_2_1: dict[str, str | None] = {
    "rosapi_msgs/srv/GetParam": "string name\nstring default_value\n---\nstring value\n",
    "rosapi_msgs/srv/SetParam": "string name\nstring value\n---\n",
    "rosapi_msgs/srv/DeleteParam": "string name\n---\n",
    "rosapi_msgs/srv/ActionType": None,
    "rosapi_msgs/srv/Interfaces": None,
    "rosapi_msgs/srv/ActionGoalDetails": None,
    "rosapi_msgs/srv/ActionResultDetails": None,
    "rosapi_msgs/srv/ActionFeedbackDetails": None,
}

_ROS1_TOKENS = {
    "builtin_interfaces/Time": "time",
    "builtin_interfaces/Duration": "duration",
    "std_msgs/Header": "Header",
}


def to_ros1_text(text: str) -> str:
    """Rewrite a ROS 2 form definition in ROS 1 form (time primitives, ``Header``, no default values)."""
    out: list[str] = []
    for line in text.split("\n"):
        body = line.split("#", 1)[0].strip()
        if not body or body == "---" or "=" in body:
            out.append(line)
            continue
        parts = body.split()
        type_name = _ROS1_TOKENS.get(parts[0], parts[0])
        out.append(f"{type_name} {parts[1]}" if len(parts) >= 2 else line)
    return "\n".join(out)
