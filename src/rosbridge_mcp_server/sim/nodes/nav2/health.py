"""How the Nav2 robot reports its health, as a real one does, and the faults that break it on purpose.

A healthy robot publishes ``/diagnostics`` (each driver its own ``DiagnosticArray`` once a second, every
status OK), logs a few INFO lines on ``/rosout`` at start-up (ROS 1: the ``/rosout`` node passes each line on
``/rosout_agg``), and its drivers publish what a real robot's do beside the world's sensors: the camera's
``camera_info`` (15 Hz), ``diff_drive_controller/odom`` (20 Hz) and ``imu_sensor_broadcaster/imu`` (10 Hz).

:data:`FAULTS` break it (``SimulatedRobot(world="nav2", faults=[...])``, ``--fault NAME[,NAME...]``):

* ``scan-stopped``: the lidar stays in the graph and publishes nothing on ``scan``;
* ``tf-stale``: ``odom → base_footprint`` stops (``map → odom`` goes on);
* ``driver-error``: the lidar driver's ``/diagnostics`` status is ERROR with a message;
* ``controller-inactive``: ``/controller_server`` is inactive (ROS 2: lifecycle; ROS 1 has none, so the
  fault is refused there);
* ``log-errors``: ``/controller_server`` logs an ERROR line (and an INFO line) every second, and
  ``/bt_navigator`` a WARN line every two seconds;
* ``node-gone``: ``/amcl`` leaves the graph :attr:`Health.node_gone_after` seconds after start (its
  publishers, subscribers, services and its ``map → odom`` transform go with it).
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterable, Sequence
from typing import Any

from rosbridge_mcp_server.sim.nodes.kit import NodeKit, quaternion_from_yaw
from rosbridge_mcp_server.sim.nodes.nav2.robot import Nav2Robot, pose

__all__ = ["FAULTS", "ROS2_ONLY_FAULTS", "Health", "check_faults"]

FAULTS = ("scan-stopped", "tf-stale", "driver-error", "controller-inactive", "log-errors", "node-gone")
#: Faults of a concept ROS 1 does not have (lifecycle).
ROS2_ONLY_FAULTS = ("controller-inactive",)

DIAGNOSTICS_PERIOD = 1.0
CAMERA_PERIOD = 1.0 / 15
DRIVER_PERIOD = 1.0 / 20
#: The node that leaves the graph with ``node-gone``.
GONE_NODE = "amcl"

#: (node, status name, hardware id, key values) of each driver's OK status.
_STATUSES: tuple[tuple[str, str, str, tuple[tuple[str, str], ...]], ...] = (
    ("rplidar_node", "rplidar_node: RPLidar A2M8", "rplidar_a2m8", (("Scan rate", "10.0 Hz"),)),
    ("camera/camera", "camera/camera: RealSense D435", "realsense_d435_0412", (("Frame rate", "15"),)),
    (
        "controller_manager",
        "controller_manager: Controllers Activity",
        "diffbot",
        (("diff_drive_controller", "active"), ("joint_state_broadcaster", "active")),
    ),
    (
        "ekf_filter_node",
        "ekf_filter_node: odometry/filtered topic status",
        "none",
        (("Actual frequency (Hz)", "20"),),
    ),
)
_DRIVER_ERROR = "Motor stalled: no scan data from the device for 5 s (check the lidar's USB cable and power)"

#: (node, line) logged at INFO when the robot starts.
_STARTUP = (
    ("lifecycle_manager_localization", "Managed nodes are active"),
    ("lifecycle_manager_navigation", "Managed nodes are active"),
    ("controller_server", "Controller frequency set to 20.0000Hz"),
    ("amcl", "Setting pose (0.000000): 5.544 5.544 0.000"),
    ("rplidar_node", "RPLIDAR S/N: 3A1FE0F3C5E09ED2A0EA98F37B5C4D65, health status: OK"),
)

#: ROS 2 ``rcl_interfaces/msg/Log`` levels, and ROS 1 ``rosgraph_msgs/Log`` ones.
_LEVELS = {"info": (20, 2), "warn": (30, 4), "error": (40, 8)}


def check_faults(faults: Iterable[str], *, ros2: bool) -> tuple[str, ...]:
    """The faults as given, checked: :class:`ValueError` names an unknown one (and the choices) or a ROS 2
    only fault on ROS 1."""
    chosen = tuple(dict.fromkeys(f.strip() for f in faults if f.strip()))
    unknown = [f for f in chosen if f not in FAULTS]
    if unknown:
        raise ValueError(f"unknown fault {', '.join(unknown)}; the faults are {', '.join(FAULTS)}")
    if not ros2:
        lifecycle = [f for f in chosen if f in ROS2_ONLY_FAULTS]
        if lifecycle:
            raise ValueError(f"{', '.join(lifecycle)} needs ROS 2 (ROS 1 has no lifecycle nodes)")
    return chosen


class Health:
    """The robots' diagnostics, log lines and driver topics, and the faults set on them."""

    def __init__(self, kit: NodeKit, robots: Sequence[Nav2Robot], faults: Sequence[str]) -> None:
        self.kit = kit
        self.robots = robots
        self.faults = check_faults(faults, ros2=kit.ros2)
        #: Seconds after start before ``node-gone`` takes /amcl out of the graph.
        self.node_gone_after = 3.0
        #: Whether the node of ``node-gone`` has left.
        self.gone = False
        self._log_type: str | None = None
        self._diagnostics_type: str | None = None

    # --- building -----------------------------------------------------------------------------------------

    def build(self) -> None:
        """Register the /rosout and /diagnostics publishers and the loops; set the faults that are states."""
        kit = self.kit
        self._log_type = kit.type("rcl_interfaces/msg/Log", "rosgraph_msgs/Log", "msg")
        if self._log_type is not None:
            kit.types["/rosout"] = self._log_type
            if not kit.ros2:
                kit.types["/rosout_agg"] = self._log_type
        self._diagnostics_type = kit.msg_type("diagnostic_msgs", "DiagnosticArray")
        for robot in self.robots:
            if self._diagnostics_type is not None:
                # The lidar driver reports on /diagnostics too (layout.py lists the others).
                kit.publisher(
                    f"{robot.namespace}/rplidar_node",
                    f"{robot.namespace}/diagnostics",
                    self._diagnostics_type,
                )
            if "scan-stopped" in self.faults:
                robot.quiet.add("scan")
            if "tf-stale" in self.faults:
                robot.quiet.add("odom->base_footprint")
            if "controller-inactive" in self.faults:
                robot.states["controller_server"] = 2
        kit.loops += [self.diagnostics_loop, self.log_loop, self.driver_loop, self.camera_loop]

    # --- /rosout --------------------------------------------------------------------------------------------

    def log(self, robot: Nav2Robot, node: str, level: str, text: str) -> None:
        """One line on /rosout from *node* of *robot* (ROS 1: also on /rosout_agg, as rosout does)."""
        kit = self.kit
        if self._log_type is None:
            return
        ros2_level, ros1_level = _LEVELS[level]
        if kit.ros2:
            # rcl names a logger after the node, namespace dots and all, without the leading slash.
            logger = f"{robot.namespace}/{node}".strip("/").replace("/", ".")
            kit.publish(
                "/rosout",
                {
                    "stamp": kit.stamp(),
                    "level": ros2_level,
                    "name": logger,
                    "msg": text,
                    "file": f"./src/{node.rsplit('/', 1)[-1]}.cpp",
                    "function": "on_update",
                    "line": 120,
                },
            )
            return
        line = {
            "header": kit.header(""),
            "level": ros1_level,
            "name": f"{robot.namespace}/{node}",
            "msg": text,
            "file": f"{node.rsplit('/', 1)[-1]}.cpp",
            "function": "update",
            "line": 120,
            "topics": [],
        }
        kit.publish("/rosout", line)
        kit.publish("/rosout_agg", line)

    async def log_loop(self) -> None:
        for robot in self.robots:
            for node, text in _STARTUP:
                self.log(robot, node, "info", text)
        started = time.monotonic()
        tick = 0
        while True:
            await asyncio.sleep(1.0)
            tick += 1
            if "node-gone" in self.faults and time.monotonic() - started >= self.node_gone_after:
                self.take_out()
            if "log-errors" in self.faults:
                for robot in self.robots:
                    self.log(
                        robot, "controller_server", "info", "Received a goal, begin computing control effort."
                    )
                    self.log(robot, "controller_server", "error", "Failed to make progress")
                    if tick % 2 == 0:
                        self.log(
                            robot, "bt_navigator", "warn", "Goal failed: FollowPath aborted (error code 105)"
                        )

    def take_out(self) -> None:
        """``node-gone`` now: /amcl of every robot leaves the graph (once)."""
        if self.gone:
            return
        for robot in self.robots:
            self._leave(robot, GONE_NODE)
        self.gone = True
        self.kit.world.notify()

    def _leave(self, robot: Nav2Robot, name: str) -> None:
        """*name* of *robot* leaves the graph: its publishers, subscribers, services and parameters go."""
        graph = self.kit.graph
        node = f"{robot.namespace}/{name}"
        info = graph.nodes.get(node)
        if info is None:
            return
        for topic, count in list(info.publishes.items()):
            for _ in range(count):
                graph.remove_publisher(node, topic)
        for topic, count in list(info.subscribes.items()):
            for _ in range(count):
                graph.remove_subscriber(node, topic)
        for service in list(info.services):
            graph.remove_service(service)
        del graph.nodes[node]
        params = self.kit.world.params
        for key in [k for k in params if k.startswith((f"{node}:", f"{node}/"))]:
            del params[key]
        robot.quiet.add("map->odom")

    # --- /diagnostics ---------------------------------------------------------------------------------------

    async def diagnostics_loop(self) -> None:
        while True:
            for robot in self.robots:
                topic = f"{robot.namespace}/diagnostics"
                if not self.kit.wants(topic):
                    continue
                for node, name, hardware, values in _STATUSES:
                    level, message = 0, "OK"
                    if node == "rplidar_node" and "driver-error" in self.faults:
                        level, message = 2, _DRIVER_ERROR
                    status = {
                        "level": level,
                        "name": name if not robot.namespace else f"{robot.namespace.strip('/')}/{name}",
                        "message": message,
                        "hardware_id": hardware,
                        "values": [{"key": k, "value": v} for k, v in values],
                    }
                    self.kit.publish(topic, {"header": self.kit.header(""), "status": [status]})
            await asyncio.sleep(DIAGNOSTICS_PERIOD)

    # --- what the drivers publish beside the world's sensors ----------------------------------------------

    async def driver_loop(self) -> None:
        kit = self.kit
        tick = 0
        while True:
            await asyncio.sleep(DRIVER_PERIOD)
            tick += 1
            for robot in self.robots:
                ns = robot.namespace
                if kit.wants(f"{ns}/diff_drive_controller/odom"):
                    kit.publish(
                        f"{ns}/diff_drive_controller/odom",
                        {
                            "header": kit.header("odom"),
                            "child_frame_id": "base_footprint",
                            "pose": {"pose": pose(robot.x, robot.y, robot.yaw)},
                            "twist": {
                                "twist": {"linear": {"x": robot.linear}, "angular": {"z": robot.angular}}
                            },
                        },
                    )
                if tick % 2 == 0 and kit.wants(f"{ns}/imu_sensor_broadcaster/imu"):
                    kit.publish(
                        f"{ns}/imu_sensor_broadcaster/imu",
                        {
                            "header": kit.header("imu_link"),
                            "orientation": quaternion_from_yaw(robot.yaw),
                            "angular_velocity": {"z": robot.angular},
                            "linear_acceleration": {"z": 9.81},
                        },
                    )

    async def camera_loop(self) -> None:
        kit = self.kit
        while True:
            await asyncio.sleep(CAMERA_PERIOD)
            for robot in self.robots:
                for stream, frame, (width, height) in (
                    ("color", "camera_color_optical_frame", (640, 480)),
                    ("depth", "camera_depth_optical_frame", (848, 480)),
                ):
                    topic = f"{robot.namespace}/camera/camera/{stream}/camera_info"
                    if kit.wants(topic):
                        kit.publish(topic, _camera_info(kit, frame, width, height))


def _camera_info(kit: NodeKit, frame: str, width: int, height: int) -> dict[str, Any]:
    fx = fy = 0.8 * width
    cx, cy = width / 2, height / 2
    k = [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0]
    return {
        "header": kit.header(frame),
        "height": height,
        "width": width,
        "distortion_model": "plumb_bob",
        ("d" if kit.ros2 else "D"): [0.0] * 5,
        ("k" if kit.ros2 else "K"): k,
        ("r" if kit.ros2 else "R"): [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        ("p" if kit.ros2 else "P"): [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
    }
