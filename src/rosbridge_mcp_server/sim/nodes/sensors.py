"""The robot's state and range sensors: ``/tf``, ``/tf_static``, ``/robot_description`` and ``/scan``.

The frame tree is ``map → world → odom → base_link → {base_scan, camera}``: ``map`` (the frame of ``/map``)
coincides with turtlesim's ``world``; ``odom`` sits where the turtle starts, so ``world → base_link`` is the
turtle's pose in turtlesim's coordinates and ``odom → base_link`` its pose relative to the start (also on
``/odom``). Frame ids carry no leading slash (tf2).
"""

from __future__ import annotations

import asyncio
import math
from typing import Any

from rosbridge_mcp_server.sim.nodes.kit import NodeKit, quaternion_from_yaw
from rosbridge_mcp_server.sim.nodes.navigation import odometry
from rosbridge_mcp_server.sim.nodes.room import ray_distance
from rosbridge_mcp_server.sim.world import TURTLE_HOME

__all__ = [
    "LIDAR",
    "ODOMETRY",
    "ROBOT_STATE_PUBLISHER",
    "SCAN_POINTS",
    "STATIC_TRANSFORMS",
    "TF_PERIOD",
    "Lidar",
    "RobotState",
    "robot_description",
]

ROBOT_STATE_PUBLISHER = "/robot_state_publisher"
ODOMETRY = "/odometry"
LIDAR = "/lidar"

TF_PERIOD = 1.0 / 20  # odom -> base_link at 20 Hz
SCAN_PERIOD = 1.0 / 5  # a 5 Hz spinning laser
SCAN_POINTS = 360
RANGE_MIN = 0.12
RANGE_MAX = 7.0
#: Readings straight back hit the scanner's own mast: NaN, as REP 117 reports erroneous readings.
MAST_HALF_WIDTH = 2

#: (parent, child, x, y, z, yaw) of every fixed transform, as robot_state_publisher and a world->odom
#: static broadcaster publish them on /tf_static.
STATIC_TRANSFORMS: tuple[tuple[str, str, float, float, float, float], ...] = (
    ("map", "world", 0.0, 0.0, 0.0, 0.0),
    ("world", "odom", TURTLE_HOME, TURTLE_HOME, 0.0, 0.0),
    ("base_link", "base_scan", 0.0, 0.0, 0.1, 0.0),
    ("base_link", "camera", 0.1, 0.0, 0.2, 0.0),
)


def robot_description(extra: str = "") -> str:
    """A small URDF of the robot whose fixed joints match :data:`STATIC_TRANSFORMS` (*extra*: more links and
    joints, e.g. the arm's)."""
    joints = "".join(
        f'  <joint name="{child}_joint" type="fixed">\n'
        f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
        f'    <origin xyz="{x:g} {y:g} {z:g}" rpy="0 0 {yaw:g}"/>\n  </joint>\n'
        for parent, child, x, y, z, yaw in STATIC_TRANSFORMS
        if parent == "base_link"
    )
    return (
        '<?xml version="1.0"?>\n<robot name="sim_turtle">\n'
        '  <link name="base_link">\n    <visual>\n      <geometry><cylinder radius="0.15" length="0.1"/>'
        "</geometry>\n    </visual>\n  </link>\n"
        '  <link name="base_scan"/>\n  <link name="camera"/>\n' + joints + extra + "</robot>\n"
    )


class RobotState:
    """``/tf`` and ``/odom`` (odom → base_link from the turtle's pose), latched ``/tf_static``,
    ``/robot_description``."""

    def __init__(self, kit: NodeKit) -> None:
        self.kit = kit
        #: More of the robot (the arm world's): URDF text inside ``<robot>``, and fixed transforms.
        self.extra_description = ""
        self.extra_static: list[tuple[str, str, float, float, float, float]] = []

    def build(self) -> None:
        kit = self.kit
        tf_type = kit.msg_type("tf2_msgs", "TFMessage")
        kit.publisher(ODOMETRY, "/tf", tf_type)
        kit.publisher(ODOMETRY, "/odom", kit.msg_type("nav_msgs", "Odometry"))
        kit.publisher(ROBOT_STATE_PUBLISHER, "/tf_static", tf_type, latched=True)
        kit.publisher(
            ROBOT_STATE_PUBLISHER, "/robot_description", kit.msg_type("std_msgs", "String"), latched=True
        )
        kit.loops.append(self._loop)

    def _transform(self, frames: tuple[str, str], x: float, y: float, z: float, yaw: float) -> dict[str, Any]:
        parent, child = frames
        return {
            "header": self.kit.header(parent),
            "child_frame_id": child,
            "transform": {"translation": {"x": x, "y": y, "z": z}, "rotation": quaternion_from_yaw(yaw)},
        }

    def publish_static(self) -> None:
        """Once at start: a latched topic hands it to every later subscriber."""
        transforms = [
            self._transform((parent, child), x, y, z, yaw)
            for parent, child, x, y, z, yaw in (*STATIC_TRANSFORMS, *self.extra_static)
        ]
        self.kit.publish("/tf_static", {"transforms": transforms})
        self.kit.publish("/robot_description", {"data": robot_description(self.extra_description)})

    async def _loop(self) -> None:
        self.publish_static()
        turtle = self.kit.world.turtle
        while True:
            if self.kit.wants("/tf"):
                moved = self._transform(
                    ("odom", "base_link"), turtle.x - TURTLE_HOME, turtle.y - TURTLE_HOME, 0.0, turtle.theta
                )
                self.kit.publish("/tf", {"transforms": [moved]})
            if self.kit.wants("/odom"):
                self.kit.publish("/odom", odometry(self.kit))
            await asyncio.sleep(TF_PERIOD)


class Lidar:
    """``/scan``: a 360-point planar laser on the turtle, seeing the room's walls and pillar."""

    def __init__(self, kit: NodeKit) -> None:
        self.kit = kit

    def build(self) -> None:
        if self.kit.publisher(LIDAR, "/scan", self.kit.msg_type("sensor_msgs", "LaserScan")):
            self.kit.loops.append(self._loop)

    def _param(self, name: str, default: float) -> float:
        sep = ":" if self.kit.ros2 else "/"
        value = self.kit.world.params.get(f"{LIDAR}{sep}{name}", default)
        return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else default

    def scan(self) -> dict[str, Any]:
        """One sweep from the turtle's pose: index 180 looks straight ahead, angles counter-clockwise."""
        turtle = self.kit.world.turtle
        range_max = self._param("range_max", RANGE_MAX)
        increment = 2 * math.pi / SCAN_POINTS
        ranges: list[float] = []
        intensities: list[float] = []
        for i in range(SCAN_POINTS):
            if min(i, SCAN_POINTS - i) <= MAST_HALF_WIDTH:
                ranges.append(math.nan)
                intensities.append(0.0)
                continue
            distance = ray_distance(turtle.x, turtle.y, turtle.theta - math.pi + i * increment)
            if distance > range_max:
                ranges.append(math.inf)
                intensities.append(0.0)
            else:
                ranges.append(max(distance, RANGE_MIN))
                intensities.append(100.0)
        return {
            "header": self.kit.header(self._frame()),
            "angle_min": -math.pi,
            "angle_max": math.pi - increment,
            "angle_increment": increment,
            "time_increment": SCAN_PERIOD / SCAN_POINTS,
            "scan_time": SCAN_PERIOD,
            "range_min": RANGE_MIN,
            "range_max": range_max,
            "ranges": ranges,
            "intensities": intensities,
        }

    def _frame(self) -> str:
        sep = ":" if self.kit.ros2 else "/"
        frame = self.kit.world.params.get(f"{LIDAR}{sep}frame_id", "base_scan")
        return frame if isinstance(frame, str) else "base_scan"

    async def _loop(self) -> None:
        while True:
            await asyncio.sleep(SCAN_PERIOD)
            if self.kit.wants("/scan"):
                self.kit.publish("/scan", self.scan())
                self.kit.world.scans += 1
                self.kit.world.notify()
