"""What the fence reads of a motion goal (``robot/motion_goals.py``) and the footprint checks
(``robot/navigation.py``), pure: every type spelling and carrier, every goal shape, the disc and the swept
drive against the zones, a straight drive against the map. The MCP attacks are in
``tests/mcp/test_mcp_fence.py``."""

from __future__ import annotations

from typing import Any

import pytest

from rosbridge_mcp_server.robot.motion_goals import (
    GoalPose,
    Motion,
    carried_goal,
    motion_action,
    read_motion,
    with_speed,
)
from rosbridge_mcp_server.robot.navigation import path_map_problem, zone_problem
from rosbridge_mcp_server.robot.occupancy import Grid, Pose2D

BOX = {"box": ((2.0, 0.0), (3.0, 0.0), (3.0, 1.0), (2.0, 1.0))}


def stamped(x: float, y: float, frame: str = "map") -> dict[str, Any]:
    return {"header": {"frame_id": frame}, "pose": {"position": {"x": x, "y": y}, "orientation": {"w": 1.0}}}


@pytest.mark.parametrize(
    "spelling",
    [
        "nav2_msgs/action/NavigateToPose",
        "nav2_msgs/NavigateToPose",
        "nav2_msgs/NavigateToPoseAction",
        "nav2_msgs/NavigateToPoseActionGoal",
        "nav2_msgs/NavigateToPoseGoal",
        "nav2_msgs/action/NavigateToPose_Goal",
        "nav2_msgs/action/NavigateToPose_SendGoal",
        " /nav2_msgs/action/NavigateToPose ",
    ],
)
def test_every_spelling_of_an_action_type_names_the_action(spelling: str) -> None:
    assert motion_action(spelling) == "nav2_msgs/NavigateToPose"


@pytest.mark.parametrize(
    "spelling", ["nav2_msgs/action/ComputePathToPose", "nav_msgs/Goals", "action_tutorials/Fibonacci", ""]
)
def test_what_does_not_move_the_robot_is_no_motion_action(spelling: str) -> None:
    assert motion_action(spelling) is None


def test_ros1_move_base_in_every_spelling() -> None:
    for spelling in (
        "move_base_msgs/MoveBaseAction",
        "move_base_msgs/MoveBaseActionGoal",
        "move_base_msgs/MoveBase",
    ):
        assert motion_action(spelling) == "move_base_msgs/MoveBase"


def test_the_goal_is_found_in_every_carrier() -> None:
    goal = {"pose": stamped(1.0, 2.0)}
    by_action = carried_goal("action", "/navigate_to_pose", "nav2_msgs/action/NavigateToPose", goal)
    by_service = carried_goal(
        "service",
        "/robot1/navigate_to_pose/_action/send_goal",
        "nav2_msgs/action/NavigateToPose_SendGoal",
        {"goal_id": {"uuid": [0] * 16}, "goal": goal},
    )
    by_topic = carried_goal(
        "topic",
        "/move_base/goal",
        "move_base_msgs/MoveBaseActionGoal",
        {"goal": {"target_pose": stamped(1, 2)}},
    )
    pose_topic = carried_goal(
        "topic", "/robot1/goal_pose", "geometry_msgs/msg/PoseStamped", stamped(1.0, 2.0)
    )
    assert by_action is not None
    assert by_action.goal == goal
    assert by_action.namespace == ""
    assert by_service is not None
    assert by_service.goal == goal
    assert by_service.namespace == "/robot1"
    assert by_topic is not None
    assert by_topic.action == "move_base_msgs/MoveBase"
    assert pose_topic is not None
    assert pose_topic.action == ""
    assert pose_topic.namespace == "/robot1"
    assert carried_goal("topic", "/chatter", "std_msgs/msg/String", {"data": "x"}) is None
    assert carried_goal("service", "/fibonacci/_action/send_goal", "x/action/Fibonacci_SendGoal", {}) is None


def test_a_goal_of_an_unknown_type_to_a_motion_action_name_cannot_be_placed() -> None:
    carried = carried_goal("action", "/drive_on_heading", "my_msgs/action/Drive", {"distance": 3})
    assert carried is not None
    motion = read_motion(carried)
    assert isinstance(motion, Motion)
    assert motion.unplaceable is not None
    assert "/drive_on_heading" in motion.unplaceable


def _read(action: str, goal: Any) -> Motion | str:
    carried = carried_goal("action", "/x", action, goal)
    assert carried is not None
    return read_motion(carried)


def test_kilted_and_jazzy_through_poses_read_every_pose() -> None:
    jazzy = _read("nav2_msgs/action/NavigateThroughPoses", {"poses": [stamped(1, 1), stamped(9, 2)]})
    kilted = _read(
        "nav2_msgs/action/NavigateThroughPoses",
        {"poses": {"header": {"frame_id": "odom"}, "goals": [stamped(1, 1, ""), stamped(9, 2)]}},
    )
    assert isinstance(jazzy, Motion)
    assert isinstance(kilted, Motion)
    assert [(p.x, p.y) for p in jazzy.poses] == [(1, 1), (9, 2)]
    # A pose with no frame of its own is in the Goals' header frame.
    assert kilted.poses == (GoalPose("odom", 1.0, 1.0, 0.0), GoalPose("map", 9.0, 2.0, 0.0))


def test_the_other_shapes() -> None:
    path = _read(
        "nav2_msgs/action/FollowPath", {"path": {"header": {"frame_id": "map"}, "poses": [stamped(1, 0)]}}
    )
    back = _read("nav2_msgs/action/BackUp", {"target": {"x": 0.5}, "speed": 0.1})
    ahead = _read("nav2_msgs/action/DriveOnHeading", {"target": {"x": 2.0}, "speed": -0.3})
    spin = _read("nav2_msgs/action/Spin", {"target_yaw": 1.0})
    dock = _read("nav2_msgs/action/DockRobot", {"use_dock_id": False, "dock_pose": stamped(4, 4)})
    route = _read("nav2_msgs/action/ComputeAndTrackRoute", {"use_poses": True, "goal": stamped(3, 3)})
    assert isinstance(path, Motion)
    assert path.path
    assert len(path.poses) == 1
    assert isinstance(back, Motion)
    assert back.along == -0.5
    assert back.speed == 0.1
    assert isinstance(ahead, Motion)
    assert ahead.along == 2.0
    assert ahead.speed == 0.3
    assert isinstance(spin, Motion)
    assert spin.along == 0.0
    assert spin.placed_count == 1
    assert isinstance(dock, Motion)
    assert dock.poses == (GoalPose("map", 4.0, 4.0, 0.0),)
    assert isinstance(route, Motion)
    assert len(route.poses) == 1
    for action, goal in (
        ("nav2_msgs/action/AssistedTeleop", {}),
        ("nav2_msgs/action/DockRobot", {"dock_id": "home"}),
        ("nav2_msgs/action/UndockRobot", {}),
        ("nav2_msgs/action/ComputeAndTrackRoute", {"start_id": 1, "goal_id": 2}),
        ("nav2_msgs/action/FollowGPSWaypoints", {"gps_poses": []}),
    ):
        motion = _read(action, goal)
        assert isinstance(motion, Motion), action
        assert motion.unplaceable, action


def test_an_unreadable_goal_says_why() -> None:
    assert "finite" in str(_read("nav2_msgs/action/NavigateToPose", {"pose": stamped(float("nan"), 0)}))
    assert "no poses" in str(_read("nav2_msgs/action/FollowWaypoints", {"poses": []}))
    assert "no poses" in str(_read("nav2_msgs/action/NavigateThroughPoses", {"poses": {"goals": []}}))


def test_the_speed_is_set_in_its_carrier_with_its_sign() -> None:
    assert with_speed("action", {"speed": -5.0, "target": {"x": -1}}, 0.5) == {
        "speed": -0.5,
        "target": {"x": -1},
    }
    assert with_speed("topic", {"goal": {"speed": 5.0}}, 0.5) == {"goal": {"speed": 0.5}}


def test_the_footprint_not_the_point_meets_a_keep_out_zone() -> None:
    just_outside = Pose2D(1.99, 0.5, 0.0)
    assert zone_problem(just_outside, {}, BOX) is None  # the point alone
    problem = zone_problem(just_outside, {}, BOX, radius=0.2)
    assert problem is not None
    assert "reaches 0.19 m into the keep-out zone 'box'" in problem
    assert zone_problem(Pose2D(1.7, 0.5, 0.0), {}, BOX, radius=0.2) is None


def test_a_straight_drive_through_a_zone_is_refused_though_both_ends_are_clear() -> None:
    problem = zone_problem(Pose2D(4.0, 0.5, 0.0), {}, BOX, radius=0.2, start=Pose2D(1.0, 0.5, 0.0))
    assert problem is not None
    assert "passes through the keep-out zone 'box'" in problem
    beside = zone_problem(Pose2D(4.0, 1.1, 0.0), {}, BOX, radius=0.2, start=Pose2D(1.0, 1.1, 0.0))
    assert beside is not None
    assert "reaches 0.10 m into" in beside
    assert zone_problem(Pose2D(4.0, 1.5, 0.0), {}, BOX, radius=0.2, start=Pose2D(1.0, 1.5, 0.0)) is None


def test_the_whole_footprint_must_be_inside_one_allowed_zone() -> None:
    lab = {"lab": ((0.0, 0.0), (5.0, 0.0), (5.0, 5.0), (0.0, 5.0))}
    assert zone_problem(Pose2D(2.5, 2.5, 0.0), lab, {}, radius=0.2) is None
    near_edge = zone_problem(Pose2D(4.9, 2.5, 0.0), lab, {}, radius=0.2)
    assert near_edge is not None
    assert "not inside one allowed zone ('lab')" in near_edge
    outside = zone_problem(Pose2D(6.0, 2.5, 0.0), lab, {}, radius=0.2)
    assert outside is not None
    assert "outside every allowed zone" in outside


def test_a_straight_drive_meets_the_map() -> None:
    # 10 x 10 cells of 0.1 m, free but for an obstacle cell at column 5, row 2 and unknown at column 2, row 7.
    cells = bytearray(100)
    cells[2 * 10 + 5] = 100
    cells[7 * 10 + 2] = 255
    grid = Grid(10, 10, 0.1, Pose2D(0.0, 0.0, 0.0), "map", bytes(cells))
    start = Pose2D(0.15, 0.25, 0.0)
    blocked = path_map_problem(grid, start, Pose2D(0.95, 0.25, 0.0))
    assert blocked is not None
    assert "runs into an obstacle" in blocked
    assert path_map_problem(grid, Pose2D(0.15, 0.15, 0.0), Pose2D(0.95, 0.35, 0.0)) is not None
    assert path_map_problem(grid, start, Pose2D(0.15, 0.55, 0.0)) is None
    unknown = path_map_problem(grid, Pose2D(0.25, 0.15, 0.0), Pose2D(0.25, 0.95, 0.0))
    assert unknown is not None
    assert "unknown space" in unknown
    off = path_map_problem(grid, start, Pose2D(-3.0, 0.25, 0.0))
    assert off is not None
    assert "leaves the map" in off
