"""The Nav2 robots moving, and what they publish: ``/tf`` and ``/odom`` at 20 Hz, ``/scan``, ``/imu/data``
and ``/joint_states`` at 10 Hz while someone listens, and once at the start the map, the costmaps,
``/tf_static``, ``/robot_description`` and ``/amcl_pose``. What the laser and the map see comes from the
:class:`Surroundings`."""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Sequence
from typing import Any

from rosbridge_mcp_server.sim.nodes.kit import NodeKit, quaternion_from_yaw
from rosbridge_mcp_server.sim.nodes.nav2.robot import Nav2Robot, pose
from rosbridge_mcp_server.sim.nodes.nav2.surroundings import RANGE_MIN, Surroundings
from rosbridge_mcp_server.sim.world import TURTLE_HOME

__all__ = ["RANGE_MAX", "SCAN_PERIOD", "SCAN_POINTS", "TF_PERIOD", "Motion"]

TF_PERIOD = 1.0 / 20
SCAN_PERIOD = 1.0 / 10
SCAN_POINTS = 360
RANGE_MAX = 12.0


class Motion:
    """Moves every robot of one world by its command and publishes what its sensors and drivers would."""

    def __init__(self, kit: NodeKit, robots: Sequence[Nav2Robot], surroundings: Surroundings) -> None:
        self.kit = kit
        self.robots = robots
        self.surroundings = surroundings

    def map_message(self) -> dict[str, Any]:
        grid = self.surroundings.grid()
        return {
            "header": self.kit.header("map"),
            "info": {
                "map_load_time": self.kit.stamp(),
                "resolution": grid.resolution,
                "width": grid.width,
                "height": grid.height,
                "origin": pose(grid.origin_x, grid.origin_y, 0.0),
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
                "origin": pose(-1.5, -1.5, 0.0),
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
            {"header": kit.header("map"), "pose": {"pose": pose(robot.x, robot.y, robot.yaw)}},
        )

    async def motion_loop(self) -> None:
        for robot in self.robots:
            self._publish_once(robot)
        kit = self.kit
        last = time.monotonic()
        while True:
            await asyncio.sleep(TF_PERIOD)
            # The time that really passed (a busy machine sleeps longer), so speeds hold in wall-clock time.
            now = time.monotonic()
            dt, last = min(now - last, 4 * TF_PERIOD), now
            for robot in self.robots:
                moving = robot.linear or robot.angular
                robot.step(dt)
                if moving:
                    kit.world.notify()
                ns = robot.namespace
                ox, oy = robot.x - TURTLE_HOME, robot.y - TURTLE_HOME
                if kit.wants(f"{ns}/tf"):
                    transforms = [
                        self._transform(("map", "odom"), (TURTLE_HOME, TURTLE_HOME, 0.0), 0.0),
                        self._transform(("odom", "base_footprint"), (ox, oy, 0.0), robot.yaw),
                    ]
                    # A fault (health.py) may silence one of them.
                    transforms = [
                        t
                        for t in transforms
                        if f"{t['header']['frame_id']}->{t['child_frame_id']}" not in robot.quiet
                    ]
                    if transforms:
                        kit.publish(f"{ns}/tf", {"transforms": transforms})
                if kit.wants(f"{ns}/odom"):
                    kit.publish(
                        f"{ns}/odom",
                        {
                            "header": kit.header("odom"),
                            "child_frame_id": "base_footprint",
                            "pose": {"pose": pose(ox, oy, robot.yaw)},
                            "twist": {
                                "twist": {"linear": {"x": robot.linear}, "angular": {"z": robot.angular}}
                            },
                        },
                    )

    async def sensor_loop(self) -> None:
        kit = self.kit
        while True:
            await asyncio.sleep(SCAN_PERIOD)
            for robot in self.robots:
                ns = robot.namespace
                if kit.wants(f"{ns}/scan") and "scan" not in robot.quiet:
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
