"""The Nav2 world: a mobile robot's graph as Nav2, ros2_control and its drivers make it (Jazzy names).

About 30 nodes (13 of them lifecycle nodes with their lifecycle services), ~70 topics, 350-400 services and
1,000+ declared parameters on ROS 2, and Nav2's action servers (``/navigate_to_pose``, ``/follow_path``,
``/spin``, ...) whose goals run a few steps and succeed; navigating moves the robot to the goal. With
``robots=N`` the same robot runs N times under ``/robot1``, ``/robot2``, ... (rosbridge, rosapi, ``/rosout``
and ``/parameter_events`` stay global).

What the robot sees comes from :class:`Surroundings`: the map on ``/map`` (latched) and the ranges on
``/scan``. The default, :class:`TurtleRoom`, is the turtle world's room (the square arena with its pillar)
as a grid and rays; a richer room plugs in by giving ``Nav2World(surroundings=...)`` (or setting
:attr:`Nav2World.surroundings` before the robot starts).

On ROS 1 the same nodes, topics and parameters are there in ROS 1 form (no lifecycle services, each node's
logger services, the actions as actionlib servers over their five topics).
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol

from rosbridge_mcp_server.sim.actions import ActionServer, GoalHandle
from rosbridge_mcp_server.sim.actions.ros2 import FeedbackFn
from rosbridge_mcp_server.sim.graph import ServiceEntry
from rosbridge_mcp_server.sim.nodes.kit import NodeKit, quaternion_from_yaw
from rosbridge_mcp_server.sim.nodes.nav2_actionlib import ActionlibServer
from rosbridge_mcp_server.sim.nodes.nav2_params import NODE_PARAMETERS, common_parameters
from rosbridge_mcp_server.sim.nodes.room import PILLAR, ray_distance
from rosbridge_mcp_server.sim.world import TURTLE_ARENA, TURTLE_HOME

__all__ = [
    "LIFECYCLE_NODES",
    "NAV2_ACTIONS",
    "NAV2_NODES",
    "Grid",
    "Nav2Robot",
    "Nav2World",
    "Surroundings",
    "TurtleRoom",
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

_MANAGERS = (
    "lifecycle_manager_navigation",
    "lifecycle_manager_localization",
    "lifecycle_manager_costmap_filters",
)
_LIFECYCLE_SERVICES = (
    ("change_state", "lifecycle_msgs/srv/ChangeState"),
    ("get_state", "lifecycle_msgs/srv/GetState"),
    ("get_available_states", "lifecycle_msgs/srv/GetAvailableStates"),
    ("get_available_transitions", "lifecycle_msgs/srv/GetAvailableTransitions"),
    ("get_transition_graph", "lifecycle_msgs/srv/GetAvailableTransitions"),
)
_STATE_LABELS = {1: "unconfigured", 2: "inactive", 3: "active", 4: "finalized"}
#: lifecycle transition id -> (from state, to state)
_TRANSITIONS = {1: (1, 2), 2: (2, 1), 3: (2, 3), 4: (3, 2), 5: (1, 4), 6: (2, 4), 7: (3, 4)}
_TRANSITION_LABELS = {
    1: "configure",
    2: "cleanup",
    3: "activate",
    4: "deactivate",
    5: "shutdown",
    6: "shutdown",
    7: "shutdown",
}
_CONTROLLERS = (
    ("diff_drive_controller", "diff_drive_controller/DiffDriveController"),
    ("joint_state_broadcaster", "joint_state_broadcaster/JointStateBroadcaster"),
    ("imu_sensor_broadcaster", "imu_sensor_broadcaster/IMUSensorBroadcaster"),
)

TF_PERIOD = 1.0 / 20
SCAN_PERIOD = 1.0 / 10
SCAN_POINTS = 360
RANGE_MIN = 0.15
RANGE_MAX = 12.0
#: Steps a goal of a Nav2 action runs before it succeeds (one feedback each).
GOAL_STEPS = 4
MAP_RESOLUTION = 0.1


# --- what the robot sees ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class Grid:
    """An occupancy grid: row-major cells (0 free, 100 occupied, -1 unknown) from the origin corner."""

    width: int
    height: int
    resolution: float
    origin_x: float
    origin_y: float
    data: list[int]


class Surroundings(Protocol):
    """What the Nav2 robot's map and laser see; the hook for a room model (poses in the map frame)."""

    def grid(self) -> Grid:
        """The map the map server publishes."""

    def ranges(
        self, x: float, y: float, yaw: float, angles: Sequence[float], range_max: float
    ) -> list[float]:
        """One laser sweep from (x, y, yaw): the distance along each angle (relative to yaw), ``inf`` beyond
        ``range_max``."""


class TurtleRoom:
    """The turtle world's room (a square arena with a round pillar), as a grid and as the laser sees it."""

    def grid(self) -> Grid:
        cells = math.ceil(TURTLE_ARENA / MAP_RESOLUTION) + 1
        cx, cy, radius = PILLAR
        data: list[int] = []
        for row in range(cells):
            for col in range(cells):
                x, y = (col + 0.5) * MAP_RESOLUTION, (row + 0.5) * MAP_RESOLUTION
                edge = row in (0, cells - 1) or col in (0, cells - 1)
                data.append(100 if edge or math.hypot(x - cx, y - cy) <= radius else 0)
        return Grid(cells, cells, MAP_RESOLUTION, -MAP_RESOLUTION / 2, -MAP_RESOLUTION / 2, data)

    def ranges(
        self, x: float, y: float, yaw: float, angles: Sequence[float], range_max: float
    ) -> list[float]:
        out: list[float] = []
        for angle in angles:
            distance = ray_distance(x, y, yaw + angle)
            out.append(math.inf if distance > range_max else max(distance, RANGE_MIN))
        return out


# --- one robot -------------------------------------------------------------------------------------------


@dataclass
class Nav2Robot:
    """One robot's state in the map frame: pose (m, rad), the command it follows (m/s, rad/s)."""

    namespace: str
    x: float = TURTLE_HOME
    y: float = TURTLE_HOME
    yaw: float = 0.0
    linear: float = 0.0
    angular: float = 0.0
    command_time: float = 0.0
    commands: int = 0
    #: Lifecycle state id of each lifecycle node (by name relative to the namespace).
    states: dict[str, int] = field(default_factory=dict)

    def step(self, dt: float) -> None:
        if time.monotonic() - self.command_time > 0.5:
            self.linear = self.angular = 0.0
        self.yaw = math.atan2(math.sin(self.yaw + self.angular * dt), math.cos(self.yaw + self.angular * dt))
        self.x = min(max(self.x + math.cos(self.yaw) * self.linear * dt, 0.2), TURTLE_ARENA - 0.2)
        self.y = min(max(self.y + math.sin(self.yaw) * self.linear * dt, 0.2), TURTLE_ARENA - 0.2)


def _pose(x: float, y: float, yaw: float) -> dict[str, Any]:
    return {"position": {"x": x, "y": y, "z": 0.0}, "orientation": quaternion_from_yaw(yaw)}


def _yaw_of(orientation: Any) -> float:
    if not isinstance(orientation, dict):
        return 0.0
    z, w = float(orientation.get("z", 0.0)), float(orientation.get("w", 1.0))
    return 2 * math.atan2(z, w)


class Nav2ActionServer(ActionServer):
    """A Nav2 action server: a goal runs :data:`GOAL_STEPS` steps (one feedback each) and succeeds."""

    def __init__(
        self,
        world: Nav2World,
        robot: Nav2Robot,
        *,
        name: str,
        action_type: str,
        node: str,
        on_success: Callable[[Nav2Robot, dict[str, Any]], dict[str, Any]] | None,
    ) -> None:
        super().__init__(world.kit.bridge, name, action_type, node)
        self.nav2 = world
        self.robot = robot
        self.on_success = on_success

    async def run_goal(self, handle: GoalHandle, feedback: FeedbackFn) -> tuple[str, dict[str, Any]]:
        step = self.nav2.action_step
        for index in range(GOAL_STEPS):
            if handle.cancel.is_set():
                return "canceled", {}
            feedback(self._feedback(handle.goal, index))
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(handle.cancel.wait(), step)
        if handle.cancel.is_set():
            return "canceled", {}
        result = self.on_success(self.robot, handle.goal) if self.on_success is not None else {}
        self.nav2.kit.world.notify()
        return "succeeded", result

    def _feedback(self, goal: dict[str, Any], index: int) -> dict[str, Any]:
        left = GOAL_STEPS - index
        leaf = self.type.rsplit("/", 1)[-1]
        if leaf.startswith("Navigate"):
            return {
                "current_pose": {
                    "header": {"frame_id": "map"},
                    "pose": _pose(self.robot.x, self.robot.y, 0.0),
                },
                "distance_remaining": float(left),
                "number_of_recoveries": 0,
            }
        if leaf == "FollowPath":
            return {"distance_to_goal": float(left), "speed": 0.3}
        if leaf == "Spin":
            return {"angular_distance_traveled": abs(float(goal.get("target_yaw", 0.0))) * index / GOAL_STEPS}
        if leaf in ("BackUp", "DriveOnHeading"):
            return {"distance_traveled": 0.1 * index}
        if leaf == "FollowWaypoints":
            return {"current_waypoint": index}
        return {}


# --- the world -------------------------------------------------------------------------------------------


class Nav2World:
    """Builds the Nav2 graph (one robot, or a fleet under ``/robotN``) on the kit's bridge."""

    def __init__(
        self,
        kit: NodeKit,
        *,
        robots: int = 1,
        action_step: float = 0.2,
        type_descriptions: bool = True,
        surroundings: Surroundings | None = None,
    ) -> None:
        if robots < 1:
            raise ValueError("robots must be >= 1")
        self.kit = kit
        self.ros2 = kit.ros2
        self.action_step = action_step
        self.type_descriptions = type_descriptions
        self.surroundings: Surroundings = surroundings or TurtleRoom()
        namespaces = [""] if robots == 1 else [f"/robot{i}" for i in range(1, robots + 1)]
        self.robots = [Nav2Robot(ns) for ns in namespaces]
        self.actions: list[Nav2ActionServer] = []
        #: Every node of the world (absolute names), for the plumbing every node gets.
        self.node_names: list[str] = []

    # --- names and types -----------------------------------------------------------------------------

    def _type(self, ros2_name: str, kind: Literal["msg", "srv", "action"] = "msg") -> str | None:
        pkg, _, leaf = ros2_name.split("/")
        return self.kit.type(ros2_name, f"{pkg}/{leaf}", kind)

    @property
    def _sep(self) -> str:
        return ":" if self.ros2 else "/"

    # --- building ------------------------------------------------------------------------------------

    def build(self) -> None:
        """Register every robot's nodes, topics, services, actions and parameters."""
        for robot in self.robots:
            self._build_robot(robot)
        self.kit.loops.append(self._motion_loop)
        self.kit.loops.append(self._sensor_loop)

    def _build_robot(self, robot: Nav2Robot) -> None:
        ns = robot.namespace
        nodes = [f"{ns}/{node}" for node in NAV2_NODES]
        self.node_names.extend(nodes)
        for node in nodes:
            self.kit.graph.node(node)
        self._topics(robot)
        self._services(robot)
        if self.ros2:
            for node in LIFECYCLE_NODES:
                robot.states[node] = 3
                self._lifecycle(robot, node)
            self._actions(robot)
        else:
            self._actionlib_topics(robot)
        self._parameters(robot)

    def _topics(self, robot: Nav2Robot) -> None:
        ns = robot.namespace
        kit = self.kit
        twist = "geometry_msgs/msg/TwistStamped" if self.ros2 else "geometry_msgs/msg/Twist"
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
        for node, topic, ros2_type, latched in pubs:
            kit.publisher(f"{ns}/{node}", f"{ns}/{topic}", self._type(ros2_type), latched=latched)
        for node, topic, ros2_type in subs:
            msg_type = self._type(ros2_type)
            if msg_type is None:
                continue
            kit.graph.add_subscriber(f"{ns}/{node}", f"{ns}/{topic}", msg_type)
        # The robot follows what reaches twist_mux on cmd_vel (velocity_smoother and collision_monitor
        # pass a command through unchanged here).
        twist_type = self._type(twist)
        if twist_type is not None:
            kit.graph.add_subscriber(f"{ns}/twist_mux", f"{ns}/cmd_vel", twist_type, self._on_cmd_vel(robot))
        bond = self._type("bond/msg/Status")
        if bond is not None:
            for node in (*LIFECYCLE_NODES, *_MANAGERS):
                kit.graph.add_publisher(f"{ns}/{node}", f"{ns}/bond", bond)
                kit.graph.add_subscriber(f"{ns}/{node}", f"{ns}/bond", bond)

    def _on_cmd_vel(self, robot: Nav2Robot) -> Callable[[dict[str, Any], int], None]:
        def follow(msg: dict[str, Any], _source: int) -> None:
            twist = msg.get("twist", msg)
            robot.linear = float(twist.get("linear", {}).get("x", 0.0))
            robot.angular = float(twist.get("angular", {}).get("z", 0.0))
            robot.command_time = time.monotonic()
            robot.commands += 1
            self.kit.world.notify()

        return follow

    def _service(self, node: str, name: str, ros2_type: str, handler: Any = None) -> None:
        service_type = self._type(ros2_type, "srv")
        if service_type is not None:
            self.kit.graph.add_service(ServiceEntry(name, service_type, node, handler or self._empty))

    @staticmethod
    async def _empty(request: dict[str, Any]) -> dict[str, Any]:
        return {}

    def _services(self, robot: Nav2Robot) -> None:
        ns = robot.namespace
        for manager in _MANAGERS:
            managed = NODE_PARAMETERS[manager]["node_names"]
            node = f"{ns}/{manager}"
            self._service(
                node,
                f"{node}/manage_nodes",
                "nav2_msgs/srv/ManageLifecycleNodes",
                self._manage(robot, managed),
            )
            self._service(node, f"{node}/is_active", "std_srvs/srv/Trigger", self._is_active(robot, managed))
        for server in ("map_server", "filter_mask_server"):
            self._service(
                f"{ns}/{server}", f"{ns}/{server}/load_map", "nav2_msgs/srv/LoadMap", self._load_map
            )
            self._service(f"{ns}/{server}", f"{ns}/{server}/map", "nav_msgs/srv/GetMap", self._get_map)
        self._service(f"{ns}/map_saver", f"{ns}/map_saver/save_map", "nav2_msgs/srv/SaveMap", self._saved)
        for leaf, srv in (
            ("reinitialize_global_localization", "std_srvs/srv/Empty"),
            ("request_nomotion_update", "std_srvs/srv/Empty"),
            ("set_initial_pose", "nav2_msgs/srv/SetInitialPose"),
        ):
            self._service(f"{ns}/amcl", f"{ns}/{leaf}", srv)
        for costmap in ("global_costmap", "local_costmap"):
            node = f"{ns}/{costmap}/{costmap}"
            for kind, srv in (
                ("clear_entirely", "nav2_msgs/srv/ClearEntireCostmap"),
                ("clear_around", "nav2_msgs/srv/ClearCostmapAroundRobot"),
                ("clear_except", "nav2_msgs/srv/ClearCostmapExceptRegion"),
            ):
                self._service(node, f"{ns}/{costmap}/{kind}_{costmap}", srv)
            self._service(node, f"{ns}/{costmap}/get_costmap", "nav2_msgs/srv/GetCostmap")
        self._service(
            f"{ns}/planner_server",
            f"{ns}/planner_server/is_path_valid",
            "nav2_msgs/srv/IsPathValid",
            self._path_valid,
        )
        self._service(
            f"{ns}/docking_server", f"{ns}/docking_server/reload_database", "nav2_msgs/srv/ReloadDockDatabase"
        )
        manager = f"{ns}/controller_manager"
        for leaf, srv in (
            ("configure_controller", "ConfigureController"),
            ("list_controller_types", "ListControllerTypes"),
            ("list_controllers", "ListControllers"),
            ("list_hardware_components", "ListHardwareComponents"),
            ("list_hardware_interfaces", "ListHardwareInterfaces"),
            ("load_controller", "LoadController"),
            ("reload_controller_libraries", "ReloadControllerLibraries"),
            ("set_hardware_component_state", "SetHardwareComponentState"),
            ("switch_controller", "SwitchController"),
            ("unload_controller", "UnloadController"),
        ):
            handler = self._list_controllers if leaf == "list_controllers" else self._ok
            self._service(manager, f"{manager}/{leaf}", f"controller_manager_msgs/srv/{srv}", handler)
        for leaf, srv in (
            ("set_pose", "robot_localization/srv/SetPose"),
            ("toggle", "robot_localization/srv/ToggleFilterProcessing"),
            ("enable", "std_srvs/srv/Empty"),
        ):
            self._service(f"{ns}/ekf_filter_node", f"{ns}/{leaf}", srv)

    @staticmethod
    async def _saved(request: dict[str, Any]) -> dict[str, Any]:
        return {"result": True}

    @staticmethod
    async def _ok(request: dict[str, Any]) -> dict[str, Any]:
        return {"ok": True}

    async def _list_controllers(self, request: dict[str, Any]) -> dict[str, Any]:
        return {
            "controller": [
                {"name": name, "state": "active", "type": kind, "update_rate": 50}
                for name, kind in _CONTROLLERS
            ]
        }

    async def _path_valid(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"is_valid": True, "invalid_pose_indices": []}

    async def _get_map(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"map": self.map_message()}

    async def _load_map(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"map": self.map_message(), "result": 0}

    def _manage(self, robot: Nav2Robot, managed: list[str]) -> Any:
        async def manage(request: dict[str, Any]) -> dict[str, Any]:
            command = int(request.get("command", 0))
            target = {0: 3, 1: 2, 2: 3, 3: 1, 4: 4, 5: 2, 6: 1}.get(command, 3)
            for node in managed:
                self._set_state(robot, node, target)
            return {"success": True}

        return manage

    def _is_active(self, robot: Nav2Robot, managed: list[str]) -> Any:
        async def is_active(request: dict[str, Any]) -> dict[str, Any]:
            active = all(robot.states.get(node) == 3 for node in managed)
            return {"success": active, "message": ""}

        return is_active

    def _set_state(self, robot: Nav2Robot, node: str, state: int) -> None:
        before = robot.states.get(node, 1)
        robot.states[node] = state
        topic = f"{robot.namespace}/{node}/transition_event"
        if before != state:
            self.kit.publish(
                topic,
                {
                    "timestamp": time.time_ns(),
                    "start_state": {"id": before, "label": _STATE_LABELS.get(before, "")},
                    "goal_state": {"id": state, "label": _STATE_LABELS.get(state, "")},
                },
            )
        self.kit.world.notify()

    def _lifecycle(self, robot: Nav2Robot, name: str) -> None:
        node = f"{robot.namespace}/{name}"
        self.kit.publisher(node, f"{node}/transition_event", self._type("lifecycle_msgs/msg/TransitionEvent"))

        async def change_state(request: dict[str, Any]) -> dict[str, Any]:
            transition = int(request.get("transition", {}).get("id", 0))
            move = _TRANSITIONS.get(transition)
            if move is None or robot.states.get(name) != move[0]:
                return {"success": False}
            self._set_state(robot, name, move[1])
            return {"success": True}

        async def get_state(request: dict[str, Any]) -> dict[str, Any]:
            state = robot.states.get(name, 1)
            return {"current_state": {"id": state, "label": _STATE_LABELS.get(state, "unknown")}}

        async def available_states(request: dict[str, Any]) -> dict[str, Any]:
            return {"available_states": [{"id": i, "label": label} for i, label in _STATE_LABELS.items()]}

        async def available_transitions(request: dict[str, Any]) -> dict[str, Any]:
            state = robot.states.get(name, 1)
            return {
                "available_transitions": [
                    {
                        "transition": {"id": tid, "label": _TRANSITION_LABELS[tid]},
                        "start_state": {"id": start, "label": _STATE_LABELS[start]},
                        "goal_state": {"id": goal, "label": _STATE_LABELS[goal]},
                    }
                    for tid, (start, goal) in _TRANSITIONS.items()
                    if start == state
                ]
            }

        handlers = {
            "change_state": change_state,
            "get_state": get_state,
            "get_available_states": available_states,
            "get_available_transitions": available_transitions,
            "get_transition_graph": available_transitions,
        }
        for leaf, srv in _LIFECYCLE_SERVICES:
            self._service(node, f"{node}/{leaf}", srv, handlers[leaf])

    @staticmethod
    def _succeed(
        behaviour: Callable[[Nav2Robot, dict[str, Any]], dict[str, Any]],
        robot: Nav2Robot,
        goal: dict[str, Any],
    ) -> None:
        behaviour(robot, goal)

    def _behaviours(self) -> dict[str, Callable[[Nav2Robot, dict[str, Any]], dict[str, Any]]]:
        """What a succeeding goal of each action does to the robot (and answers)."""
        return {
            "navigate_to_pose": self._arrive,
            "navigate_through_poses": self._arrive,
            "follow_waypoints": self._arrive,
            "compute_path_to_pose": self._plan,
            "compute_path_through_poses": self._plan,
            "spin": self._spin,
        }

    def _actions(self, robot: Nav2Robot) -> None:
        ns = robot.namespace
        behaviours = self._behaviours()
        for name, leaf, node in NAV2_ACTIONS:
            action_type = self._type(f"nav2_msgs/action/{leaf}", "action")
            if action_type is None:
                continue
            self.actions.append(
                Nav2ActionServer(
                    self,
                    robot,
                    name=f"{ns}/{name}",
                    action_type=action_type,
                    node=f"{ns}/{node}",
                    on_success=behaviours.get(name),
                )
            )

    def _actionlib_topics(self, robot: Nav2Robot) -> None:
        """ROS 1: each action as an actionlib server over its five topics."""
        ns = robot.namespace
        for name, leaf, node in NAV2_ACTIONS:
            if self._type(f"nav2_msgs/msg/{leaf}ActionGoal") is None:
                continue
            behaviour = self._behaviours().get(name)
            on_success: Callable[[dict[str, Any]], None] | None = None
            if behaviour is not None:
                on_success = functools.partial(self._succeed, behaviour, robot)
            ActionlibServer(
                self.kit,
                name=f"{ns}/{name}",
                node=f"{ns}/{node}",
                package="nav2_msgs",
                action=leaf,
                steps=GOAL_STEPS,
                step=self.action_step,
                on_success=on_success,
            )

    def _parameters(self, robot: Nav2Robot) -> None:
        params = self.kit.world.params
        sep = self._sep
        common = common_parameters(type_descriptions=self.type_descriptions) if self.ros2 else {}
        for name in NAV2_NODES:
            node = f"{robot.namespace}/{name}"
            for key, value in {**common, **NODE_PARAMETERS.get(name, {})}.items():
                params[f"{node}{sep}{key if self.ros2 else key.replace('.', '/')}"] = value

    # --- what the goals do ---------------------------------------------------------------------------

    def _goal_pose(self, goal: dict[str, Any]) -> tuple[float, float, float] | None:
        pose_msg = goal.get("pose") or goal.get("goal")
        if pose_msg is None:
            poses = goal.get("poses") or goal.get("goals") or []
            pose_msg = poses[-1] if poses else None
        if not isinstance(pose_msg, dict):
            return None
        pose = pose_msg.get("pose", {})
        position = pose.get("position", {})
        return float(position.get("x", 0.0)), float(position.get("y", 0.0)), _yaw_of(pose.get("orientation"))

    def _path(self, robot: Nav2Robot, goal: dict[str, Any]) -> dict[str, Any]:
        target = self._goal_pose(goal) or (robot.x, robot.y, robot.yaw)
        count = 20
        poses = [
            {
                "header": self.kit.header("map"),
                "pose": _pose(
                    robot.x + (target[0] - robot.x) * i / count,
                    robot.y + (target[1] - robot.y) * i / count,
                    target[2],
                ),
            }
            for i in range(count + 1)
        ]
        return {"header": self.kit.header("map"), "poses": poses}

    def _plan(self, robot: Nav2Robot, goal: dict[str, Any]) -> dict[str, Any]:
        path = self._path(robot, goal)
        self.kit.publish(f"{robot.namespace}/plan", path)
        return {"path": path, "planning_time": {"sec": 0, "nanosec": 20_000_000}}

    def _arrive(self, robot: Nav2Robot, goal: dict[str, Any]) -> dict[str, Any]:
        self.kit.publish(f"{robot.namespace}/plan", self._path(robot, goal))
        target = self._goal_pose(goal)
        if target is not None:
            robot.x = min(max(target[0], 0.2), TURTLE_ARENA - 0.2)
            robot.y = min(max(target[1], 0.2), TURTLE_ARENA - 0.2)
            robot.yaw = target[2]
        return {}

    def _spin(self, robot: Nav2Robot, goal: dict[str, Any]) -> dict[str, Any]:
        turn = float(goal.get("target_yaw", 0.0))
        robot.yaw = math.atan2(math.sin(robot.yaw + turn), math.cos(robot.yaw + turn))
        return {}

    # --- messages --------------------------------------------------------------------------------------

    def map_message(self) -> dict[str, Any]:
        grid = self.surroundings.grid()
        return {
            "header": self.kit.header("map"),
            "info": {
                "map_load_time": self.kit.stamp(),
                "resolution": grid.resolution,
                "width": grid.width,
                "height": grid.height,
                "origin": _pose(grid.origin_x, grid.origin_y, 0.0),
            },
            "data": grid.data,
        }

    def scan_message(self, robot: Nav2Robot) -> dict[str, Any]:
        increment = 2 * math.pi / SCAN_POINTS
        angles = [-math.pi + i * increment for i in range(SCAN_POINTS)]
        ranges = self.surroundings.ranges(robot.x, robot.y, robot.yaw, angles, RANGE_MAX)
        return {
            "header": self.kit.header("laser"),
            "angle_min": -math.pi,
            "angle_max": math.pi - increment,
            "angle_increment": increment,
            "time_increment": SCAN_PERIOD / SCAN_POINTS,
            "scan_time": SCAN_PERIOD,
            "range_min": RANGE_MIN,
            "range_max": RANGE_MAX,
            "ranges": ranges,
            "intensities": [47.0 if math.isfinite(r) else 0.0 for r in ranges],
        }

    def _transform(
        self, frames: tuple[str, str], xyz: tuple[float, float, float], yaw: float
    ) -> dict[str, Any]:
        x, y, z = xyz
        return {
            "header": self.kit.header(frames[0]),
            "child_frame_id": frames[1],
            "transform": {"translation": {"x": x, "y": y, "z": z}, "rotation": quaternion_from_yaw(yaw)},
        }

    def _publish_once(self, robot: Nav2Robot) -> None:
        ns = robot.namespace
        kit = self.kit
        kit.publish(f"{ns}/map", self.map_message())
        grid = self.map_message()
        kit.publish(f"{ns}/global_costmap/costmap", grid)
        local = {
            "header": kit.header("odom"),
            "info": {
                "resolution": 0.05,
                "width": 60,
                "height": 60,
                "origin": _pose(-1.5, -1.5, 0.0),
            },
            "data": [0] * 3600,
        }
        kit.publish(f"{ns}/local_costmap/costmap", local)
        kit.publish(
            f"{ns}/tf_static",
            {
                "transforms": [
                    self._transform(("base_footprint", "base_link"), (0.0, 0.0, 0.01), 0.0),
                    self._transform(("base_link", "laser"), (0.0, 0.0, 0.18), 0.0),
                    self._transform(("base_link", "imu_link"), (0.0, 0.0, 0.07), 0.0),
                    self._transform(("base_link", "camera_link"), (0.1, 0.0, 0.2), 0.0),
                ]
            },
        )
        kit.publish(f"{ns}/robot_description", {"data": _URDF})
        kit.publish(
            f"{ns}/amcl_pose",
            {"header": kit.header("map"), "pose": {"pose": _pose(robot.x, robot.y, robot.yaw)}},
        )

    # --- running ---------------------------------------------------------------------------------------

    async def _motion_loop(self) -> None:
        for robot in self.robots:
            self._publish_once(robot)
        kit = self.kit
        while True:
            await asyncio.sleep(TF_PERIOD)
            for robot in self.robots:
                moving = robot.linear or robot.angular
                robot.step(TF_PERIOD)
                if moving:
                    kit.world.notify()
                ns = robot.namespace
                ox, oy = robot.x - TURTLE_HOME, robot.y - TURTLE_HOME
                if kit.wants(f"{ns}/tf"):
                    kit.publish(
                        f"{ns}/tf",
                        {
                            "transforms": [
                                self._transform(("map", "odom"), (TURTLE_HOME, TURTLE_HOME, 0.0), 0.0),
                                self._transform(("odom", "base_footprint"), (ox, oy, 0.0), robot.yaw),
                            ]
                        },
                    )
                if kit.wants(f"{ns}/odom"):
                    kit.publish(
                        f"{ns}/odom",
                        {
                            "header": kit.header("odom"),
                            "child_frame_id": "base_footprint",
                            "pose": {"pose": _pose(ox, oy, robot.yaw)},
                            "twist": {
                                "twist": {"linear": {"x": robot.linear}, "angular": {"z": robot.angular}}
                            },
                        },
                    )

    async def _sensor_loop(self) -> None:
        kit = self.kit
        while True:
            await asyncio.sleep(SCAN_PERIOD)
            for robot in self.robots:
                ns = robot.namespace
                if kit.wants(f"{ns}/scan"):
                    kit.publish(f"{ns}/scan", self.scan_message(robot))
                    kit.world.scans += 1
                    kit.world.notify()
                if kit.wants(f"{ns}/imu/data"):
                    kit.publish(
                        f"{ns}/imu/data",
                        {
                            "header": kit.header("imu_link"),
                            "orientation": quaternion_from_yaw(robot.yaw),
                            "angular_velocity": {"z": robot.angular},
                            "linear_acceleration": {"z": 9.81},
                        },
                    )
                if kit.wants(f"{ns}/joint_states"):
                    kit.publish(
                        f"{ns}/joint_states",
                        {
                            "header": kit.header(""),
                            "name": ["left_wheel_joint", "right_wheel_joint"],
                            "position": [0.0, 0.0],
                            "velocity": [robot.linear / 0.033, robot.linear / 0.033],
                            "effort": [],
                        },
                    )

    async def close(self) -> None:
        """Stop every goal (the robot is shutting down)."""
        for server in self.actions:
            await server.close()


_URDF = (
    '<?xml version="1.0"?>\n<robot name="nav2_bot">\n'
    '  <link name="base_footprint"/>\n  <link name="base_link"/>\n  <link name="laser"/>\n'
    '  <link name="imu_link"/>\n  <link name="camera_link"/>\n'
    '  <link name="left_wheel"/>\n  <link name="right_wheel"/>\n'
    '  <joint name="base_joint" type="fixed"><parent link="base_footprint"/><child link="base_link"/>'
    '<origin xyz="0 0 0.01"/></joint>\n'
    '  <joint name="laser_joint" type="fixed"><parent link="base_link"/><child link="laser"/>'
    '<origin xyz="0 0 0.18"/></joint>\n'
    '  <joint name="imu_joint" type="fixed"><parent link="base_link"/><child link="imu_link"/>'
    '<origin xyz="0 0 0.07"/></joint>\n'
    '  <joint name="camera_joint" type="fixed"><parent link="base_link"/><child link="camera_link"/>'
    '<origin xyz="0.1 0 0.2"/></joint>\n'
    '  <joint name="left_wheel_joint" type="continuous"><parent link="base_link"/>'
    '<child link="left_wheel"/><origin xyz="0 0.144 0.023"/><axis xyz="0 1 0"/></joint>\n'
    '  <joint name="right_wheel_joint" type="continuous"><parent link="base_link"/>'
    '<child link="right_wheel"/><origin xyz="0 -0.144 0.023"/><axis xyz="0 1 0"/></joint>\n'
    "</robot>\n"
)
