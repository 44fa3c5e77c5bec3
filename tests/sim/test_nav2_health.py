"""The Nav2 world's health as a real robot reports it (/diagnostics, /rosout, the drivers' topics), and the
faults that break it on purpose, seen on a raw rosbridge socket in both dialects."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from rawclient import RawClient

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.nodes.nav2.health import FAULTS, check_faults

WAIT = 30.0


async def messages(client: RawClient, topic: str, count: int, wait: float = WAIT) -> list[dict[str, Any]]:
    """*count* messages of *topic* (others are kept in the client's backlog)."""
    got = []
    for _ in range(count):
        frame = await client.recv_until(lambda f: f.get("op") == "publish" and f.get("topic") == topic, wait)
        got.append(frame["msg"])
    return got


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_a_healthy_robot_reports_every_driver_ok_and_its_drivers_publish(dialect: str) -> None:
    async with (
        SimulatedRobot(dialect=dialect, world="nav2") as robot,
        await RawClient.open(robot.url) as client,
    ):  # type: ignore[arg-type]
        for topic in (
            "/diagnostics",
            "/camera/camera/color/camera_info",
            "/diff_drive_controller/odom",
            "/imu_sensor_broadcaster/imu",
        ):
            await client.send({"op": "subscribe", "topic": topic})
        statuses = [s for msg in await messages(client, "/diagnostics", 4) for s in msg["status"]]
        assert {s["name"] for s in statuses} == {
            "rplidar_node: RPLidar A2M8",
            "camera/camera: RealSense D435",
            "controller_manager: Controllers Activity",
            "ekf_filter_node: odometry/filtered topic status",
        }
        assert {s["level"] for s in statuses} == {0}
        info = (await messages(client, "/camera/camera/color/camera_info", 1))[0]
        assert (info["width"], info["height"]) == (640, 480)
        await messages(client, "/diff_drive_controller/odom", 2)
        await messages(client, "/imu_sensor_broadcaster/imu", 2)
    assert "/rplidar_node" in robot.graph.publishers_of("/diagnostics")


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_log_errors_logs_on_rosout_as_each_dialect_does(dialect: str) -> None:
    async with (
        SimulatedRobot(dialect=dialect, world="nav2", faults=["log-errors"]) as robot,  # type: ignore[arg-type]
        await RawClient.open(robot.url) as client,
    ):
        topic = "/rosout" if dialect == "ros2" else "/rosout_agg"
        await client.send({"op": "subscribe", "topic": topic})
        lines = await messages(client, topic, 2, wait=WAIT)
    error = next(line for line in lines if "progress" in line["msg"])
    if dialect == "ros2":
        assert (error["level"], error["name"]) == (40, "controller_server")
        assert set(error["stamp"]) == {"sec", "nanosec"}
    else:
        assert (error["level"], error["name"]) == (8, "/controller_server")
        assert error["header"]["seq"] >= 1
        assert error["topics"] == []


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_scan_stopped_keeps_the_lidar_in_the_graph_and_sends_nothing(dialect: str) -> None:
    async with (
        SimulatedRobot(dialect=dialect, world="nav2", faults=["scan-stopped"]) as robot,  # type: ignore[arg-type]
        await RawClient.open(robot.url) as client,
    ):
        await client.send({"op": "subscribe", "topic": "/scan"})
        await client.send({"op": "subscribe", "topic": "/odom"})
        await messages(client, "/odom", 5)  # a second of the world running
        assert not any(f.get("topic") == "/scan" for f in client.backlog)
        assert robot.graph.publishers_of("/scan") == ["/rplidar_node"]


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_tf_stale_stops_odom_to_base_footprint_only(dialect: str) -> None:
    async with (
        SimulatedRobot(dialect=dialect, world="nav2", faults=["tf-stale"]) as robot,  # type: ignore[arg-type]
        await RawClient.open(robot.url) as client,
    ):
        await client.send({"op": "subscribe", "topic": "/tf"})
        frames = {
            (t["header"]["frame_id"], t["child_frame_id"])
            for msg in await messages(client, "/tf", 5)
            for t in msg["transforms"]
        }
    assert frames == {("map", "odom")}


async def test_driver_error_and_controller_inactive_on_ros2() -> None:
    async with (
        SimulatedRobot(world="nav2", faults=["driver-error", "controller-inactive"]) as robot,
        await RawClient.open(robot.url) as client,
    ):
        state = await client.call("/controller_server/get_state", {})
        planner = await client.call("/planner_server/get_state", {})
        await client.send({"op": "subscribe", "topic": "/diagnostics"})
        statuses = [s for msg in await messages(client, "/diagnostics", 4) for s in msg["status"]]
    assert state["values"]["current_state"] == {"id": 2, "label": "inactive"}
    assert planner["values"]["current_state"]["label"] == "active"
    lidar = next(s for s in statuses if s["name"].startswith("rplidar_node"))
    assert lidar["level"] == 2
    assert "Motor stalled" in lidar["message"]
    assert all(s["level"] == 0 for s in statuses if s is not lidar)


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_node_gone_takes_amcl_out_of_the_graph_a_moment_after_start(dialect: str) -> None:
    robot = SimulatedRobot(dialect=dialect, world="nav2", faults=["node-gone"])  # type: ignore[arg-type]
    robot.nav2.health.node_gone_after = 0.2
    async with robot:
        assert "/amcl" in robot.graph.node_names()
        await robot.wait_for(lambda _world: robot.nav2.health.gone, timeout=WAIT)
        assert "/amcl" not in robot.graph.node_names()
        assert "/amcl_pose" not in dict(robot.graph.topics())
        assert not [s for s in robot.graph.services if s.startswith("/amcl/")]
        async with await RawClient.open(robot.url) as client:
            await client.send({"op": "subscribe", "topic": "/tf", "type": "tf2_msgs/TFMessage"})
            frames = {
                (t["header"]["frame_id"], t["child_frame_id"])
                for msg in await messages(client, "/tf", 3)
                for t in msg["transforms"]
            }
    assert frames == {("odom", "base_footprint")}


def test_faults_are_checked_by_name_and_dialect() -> None:
    assert check_faults(["log-errors", " tf-stale", "log-errors", ""], ros2=True) == (
        "log-errors",
        "tf-stale",
    )
    with pytest.raises(ValueError, match="unknown fault wheels; the faults are " + ", ".join(FAULTS)):
        check_faults(["wheels"], ros2=True)
    with pytest.raises(ValueError, match="controller-inactive needs ROS 2"):
        check_faults(["controller-inactive"], ros2=False)
    with pytest.raises(ValueError, match="faults need world='nav2'"):
        SimulatedRobot(faults=["scan-stopped"])


async def test_the_fault_flag_breaks_the_commands_robot() -> None:
    """rosbridge-sim-robot --world nav2 --fault scan-stopped,driver-error serves a broken robot."""
    from test_command import _start

    process, url = await _start("--port", "0", "--world", "nav2", "--fault", "scan-stopped,driver-error")
    try:
        async with await RawClient.open(url) as client:
            await client.send({"op": "subscribe", "topic": "/diagnostics"})
            statuses = [s for msg in await messages(client, "/diagnostics", 4) for s in msg["status"]]
            assert any(s["level"] == 2 for s in statuses)
            assert not any(f.get("topic") == "/scan" for f in client.backlog)
    finally:
        process.terminate()
        await asyncio.wait_for(process.wait(), 20)
