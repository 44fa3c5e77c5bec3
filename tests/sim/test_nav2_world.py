"""The Nav2 world (``world="nav2"``): a Nav2-scale graph in both dialects, its latched map, its frames, its
lifecycle and action servers, and a fleet under ``/robotN``; all seen through rosapi and the bridge's ops."""

from __future__ import annotations

import math
from collections.abc import Awaitable, Callable
from typing import Any

import pytest
from rawclient import RawClient

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.nodes.nav2 import LIFECYCLE_NODES, NAV2_ACTIONS, Grid

MakeSim = Callable[..., Awaitable[SimulatedRobot]]


@pytest.fixture(params=["ros2", "ros1"])
async def nav2(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    """A started Nav2 robot of each dialect."""
    return await make_sim(dialect=request.param, world="nav2")


async def test_ros2_nav2_graph_has_the_size_of_a_real_nav2_robot(make_sim: MakeSim) -> None:
    """~36 nodes (half lifecycle), ~70-80 topics, 350-400 services, 1,000+ parameters, Nav2's actions."""
    robot = await make_sim(dialect="ros2", world="nav2")
    async with await RawClient.open(robot.url) as client:
        nodes = (await client.values("/rosapi/nodes"))["nodes"]
        topics = (await client.values("/rosapi/topics"))["topics"]
        services = (await client.values("/rosapi/services"))["services"]
        params = (await client.values("/rosapi/get_param_names"))["names"]
        actions = (await client.values("/rosapi/action_servers"))["action_servers"]
    assert 30 <= len(nodes) <= 40
    lifecycle = [n for n in nodes if f"{n}/change_state" in services]
    assert len(lifecycle) == len(LIFECYCLE_NODES) >= len(nodes) // 3
    assert "/global_costmap/global_costmap" in lifecycle
    assert 70 <= len(topics) <= 90
    assert 350 <= len(services) <= 400
    assert len(params) >= 1000
    assert "/controller_server:FollowPath.vx_max" in params
    assert sorted(actions) == sorted(f"/{name}" for name, _, _ in NAV2_ACTIONS)


async def test_ros1_actionlib_goal_of_a_nav2_action_is_served(make_sim: MakeSim) -> None:
    """ROS 1: a goal published on /spin/goal gets feedback, then a SUCCEEDED result on /spin/result."""
    robot = await make_sim(dialect="ros1", world="nav2")
    async with await RawClient.open(robot.url) as client:
        await client.send({"op": "subscribe", "topic": "/spin/feedback", "id": "f"})
        await client.send({"op": "subscribe", "topic": "/spin/result", "id": "r"})
        await client.send(
            {"op": "advertise", "topic": "/spin/goal", "type": "nav2_msgs/SpinActionGoal", "id": "a"}
        )
        await client.send(
            {
                "op": "publish",
                "topic": "/spin/goal",
                "msg": {"goal_id": {"id": "spin-1"}, "goal": {"target_yaw": 1.0}},
            }
        )
        feedback = (await client.next_publish("/spin/feedback"))["msg"]
        result = (await client.next_publish("/spin/result"))["msg"]
    assert feedback["status"]["goal_id"]["id"] == "spin-1"
    assert result["status"]["status"] == 3  # SUCCEEDED
    assert robot.nav2.robots[0].yaw == pytest.approx(1.0)


async def test_ros1_nav2_graph_lists_the_same_nodes_and_the_actions_as_actionlib_topics(
    make_sim: MakeSim,
) -> None:
    """On ROS 1 the nodes and parameters are there in ROS 1 form; each action is its five topics."""
    robot = await make_sim(dialect="ros1", world="nav2")
    async with await RawClient.open(robot.url) as client:
        nodes = (await client.values("/rosapi/nodes"))["nodes"]
        actions = (await client.values("/rosapi/action_servers"))["action_servers"]
        goal_type = (await client.values("/rosapi/topic_type", {"topic": "/navigate_to_pose/goal"}))["type"]
        value = await client.values("/rosapi/get_param", {"name": "/controller_server/FollowPath/vx_max"})
    assert "/controller_server" in nodes
    assert "/local_costmap/local_costmap" in nodes
    # 0.11.17 repeats a namespace for later topics (its quirk), so compare the set.
    assert set(actions) == {f"/{name}" for name, _, _ in NAV2_ACTIONS} | {"/move_base"}
    assert goal_type == "nav2_msgs/NavigateToPoseActionGoal"
    assert value["value"] == "0.5"


async def test_map_is_latched_and_consistent_with_its_size(nav2: SimulatedRobot) -> None:
    """A late subscriber to /map gets the map at once; width x height cells, 0.1 m each, walls occupied."""
    async with await RawClient.open(nav2.url) as client:
        await client.send({"op": "subscribe", "topic": "/map", "id": "map"})
        grid = (await client.next_publish("/map"))["msg"]
    info = grid["info"]
    assert info["width"] * info["height"] == len(grid["data"])
    assert info["resolution"] == pytest.approx(0.1)
    assert grid["header"]["frame_id"] == "map"
    assert grid["data"][0] == 100
    assert 0 in grid["data"]


async def test_tf_chains_map_to_odom_to_the_robot(nav2: SimulatedRobot) -> None:
    """/tf carries map→odom and odom→base_footprint; latched /tf_static carries base_footprint→base_link."""
    async with await RawClient.open(nav2.url) as client:
        await client.send({"op": "subscribe", "topic": "/tf", "id": "tf"})
        await client.send({"op": "subscribe", "topic": "/tf_static", "id": "tf_static"})
        moving = (await client.next_publish("/tf"))["msg"]["transforms"]
        static = (await client.next_publish("/tf_static"))["msg"]["transforms"]
    pairs = {(t["header"]["frame_id"], t["child_frame_id"]) for t in moving}
    assert pairs == {("map", "odom"), ("odom", "base_footprint")}
    assert ("base_footprint", "base_link") in {(t["header"]["frame_id"], t["child_frame_id"]) for t in static}


async def test_scan_comes_from_the_surroundings_hook(nav2: SimulatedRobot) -> None:
    """/scan's 360 ranges are what the surroundings give for the robot's pose (the room's far wall ahead)."""
    seen: list[tuple[float, float, float]] = []
    room = nav2.nav2.surroundings

    class Recording:
        def grid(self) -> Grid:
            return room.grid()

        def ranges(self, x: float, y: float, yaw: float, angles: Any, range_max: float) -> list[float]:
            seen.append((x, y, yaw))
            return room.ranges(x, y, yaw, angles, range_max)

    nav2.nav2.surroundings = Recording()
    async with await RawClient.open(nav2.url) as client:
        await client.send({"op": "subscribe", "topic": "/scan", "id": "scan"})
        scan = (await client.next_publish("/scan"))["msg"]
    assert len(scan["ranges"]) == 360
    assert seen
    assert seen[0][:2] == (nav2.nav2.robots[0].x, nav2.nav2.robots[0].y)
    assert all(r is None or scan["range_min"] <= r <= scan["range_max"] for r in scan["ranges"])


async def test_cmd_vel_drives_the_robot(nav2: SimulatedRobot) -> None:
    """A velocity command on /cmd_vel (TwistStamped on ROS 2, Twist on ROS 1) moves the robot forward."""
    robot = nav2.nav2.robots[0]
    start = robot.x
    twist = {"linear": {"x": 0.5}, "angular": {"z": 0.0}}
    msg = {"twist": twist} if nav2.dialect == "ros2" else twist
    async with await RawClient.open(nav2.url) as client:
        await client.send({"op": "publish", "topic": "/cmd_vel", "msg": msg})
        await nav2.wait_for(lambda _: robot.x > start + 0.01)
    assert robot.commands == 1


async def test_ros2_navigate_to_pose_sends_feedback_succeeds_and_moves_the_robot(make_sim: MakeSim) -> None:
    """A NavigateToPose goal: feedback with distance_remaining, status 4, the robot driven to the goal."""
    robot = await make_sim(dialect="ros2", world="nav2")
    robot.nav2.navigator.speed = 5.0  # a test drive of a second or two
    goal = {"pose": {"header": {"frame_id": "map"}, "pose": {"position": {"x": 2.0, "y": 3.0}}}}
    async with await RawClient.open(robot.url) as client:
        await client.send(
            {
                "op": "send_action_goal",
                "id": "nav",
                "action": "/navigate_to_pose",
                "action_type": "nav2_msgs/action/NavigateToPose",
                "args": goal,
                "feedback": True,
            }
        )
        feedback = await client.reply("nav", op="action_feedback")
        result = await client.reply("nav", op="action_result", wait=30.0)
    assert feedback["values"]["distance_remaining"] > 0
    assert result["status"] == 4
    assert result["result"] is True
    assert result["values"]["error_code"] == 0
    state = robot.nav2.robots[0]
    assert state.x == pytest.approx(2.0, abs=0.05)
    assert state.y == pytest.approx(3.0, abs=0.05)
    assert (state.linear, state.angular) == (0.0, 0.0)


async def test_ros2_action_types_are_described_by_rosapi(make_sim: MakeSim) -> None:
    """rosapi names each action's nav2_msgs type and gives its goal's TypeDefs."""
    robot = await make_sim(dialect="ros2", world="nav2")
    async with await RawClient.open(robot.url) as client:
        kind = (await client.values("/rosapi/action_type", {"action": "/follow_path"}))["type"]
        goal = await client.values("/rosapi/action_goal_details", {"type": "nav2_msgs/action/Spin"})
    assert kind == "nav2_msgs/action/FollowPath"
    assert goal["typedefs"][0]["fieldnames"] == ["target_yaw", "time_allowance", "disable_collision_checks"]


async def test_ros2_lifecycle_services_report_and_change_the_state(make_sim: MakeSim) -> None:
    """get_state says active; deactivate moves it to inactive; is_active of its manager then says no."""
    robot = await make_sim(dialect="ros2", world="nav2")
    async with await RawClient.open(robot.url) as client:
        before = await client.values("/controller_server/get_state")
        changed = await client.values("/controller_server/change_state", {"transition": {"id": 4}})
        after = await client.values("/controller_server/get_state")
        active = await client.values("/lifecycle_manager_navigation/is_active")
    assert before["current_state"] == {"id": 3, "label": "active"}
    assert changed == {"success": True}
    assert after["current_state"]["label"] == "inactive"
    assert active["success"] is False


async def test_ros2_node_parameters_answer_through_the_node_services(make_sim: MakeSim) -> None:
    """A Nav2 node's own get_parameters answers its declared values."""
    robot = await make_sim(dialect="ros2", world="nav2")
    async with await RawClient.open(robot.url) as client:
        values = await client.values("/amcl/get_parameters", {"names": ["max_particles", "laser_model_type"]})
    assert [v.get("integer_value") or v.get("string_value") for v in values["values"]] == [
        2000,
        "likelihood_field",
    ]


async def test_a_fleet_runs_the_same_robot_under_each_namespace(make_sim: MakeSim) -> None:
    """robots=3: every node, topic and action three times under /robot1..3; rosbridge and rosapi once."""
    robot = await make_sim(dialect="ros2", world="nav2", robots=3)
    async with await RawClient.open(robot.url) as client:
        nodes = (await client.values("/rosapi/nodes"))["nodes"]
        actions = (await client.values("/rosapi/action_servers"))["action_servers"]
        await client.send({"op": "subscribe", "topic": "/robot2/map", "id": "m"})
        grid = (await client.next_publish("/robot2/map"))["msg"]
    for i in (1, 2, 3):
        assert f"/robot{i}/controller_server" in nodes
        assert f"/robot{i}/navigate_to_pose" in actions
    assert "/controller_server" not in nodes
    assert nodes.count("/rosapi") == 1
    assert len(actions) == 3 * len(NAV2_ACTIONS)
    assert grid["info"]["width"] > 0
    assert len(robot.nav2.robots) == 3


def test_a_fleet_needs_the_nav2_world() -> None:
    """robots > 1 on the turtle world, or robots < 1, is refused naming the rule."""
    with pytest.raises(ValueError, match="nav2"):
        SimulatedRobot(robots=2)
    with pytest.raises(ValueError, match="world"):
        SimulatedRobot(world="mars")  # type: ignore[arg-type]


def test_default_surroundings_map_has_the_room_walls_all_round() -> None:
    """The turtle room as a grid: every border cell occupied, the middle free."""
    grid = SimulatedRobot(world="nav2").nav2.surroundings.grid()
    rows = [grid.data[r * grid.width : (r + 1) * grid.width] for r in range(grid.height)]
    assert all(cell == 100 for cell in rows[0])
    assert all(row[0] == 100 for row in rows)
    assert rows[grid.height // 2][grid.width // 2] == 0
    assert math.isclose(grid.resolution, 0.1)
