"""The fence's judgement (``safety/navigation.py``) on acts built as the acting layer builds them, with a
scene given: what it needs placed, what it refuses while zones are set (fail closed), and what it lets through
without a policy. The attacks through an MCP session are in ``tests/mcp/test_mcp_fence.py``."""

from __future__ import annotations

from typing import Any

from rosbridge_mcp_server.robot.approval import Act
from rosbridge_mcp_server.robot.navigation import Scene
from rosbridge_mcp_server.robot.occupancy import Grid, Pose2D
from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.safety.navigation import goal_text, navigation_refusal

ZONES = parse_policy(
    {"navigation": {"keep_out": {"box": [[2.0, 0.0], [3.0, 0.0], [3.0, 1.0], [2.0, 1.0]]}}}, where="t.toml"
).navigation
NONE = parse_policy({}, where="t.toml").navigation
#: 60 x 60 free cells of 0.1 m from (0, 0).
GRID = Grid(60, 60, 0.1, Pose2D(0.0, 0.0, 0.0), "map", bytes(3600))


def stamped(x: float, y: float) -> dict[str, Any]:
    return {"header": {"frame_id": "map"}, "pose": {"position": {"x": x, "y": y}, "orientation": {"w": 1.0}}}


def path_act(scene: Scene | None) -> Act:
    goal = {"path": {"header": {"frame_id": "map"}, "poses": [stamped(1.0, 2.0), stamped(4.0, 2.0)]}}
    return Act("publish_action", "action", "/follow_path", "nav2_msgs/action/FollowPath", goal, scene=scene)


def test_a_path_needs_the_robot_placed_while_zones_are_set() -> None:
    goals = (Pose2D(1.0, 2.0, 0.0), Pose2D(4.0, 2.0, 0.0))
    unknown = Scene("/map", "base_link", grid=GRID, robot=None, goals=goals, problems=("no transform",))
    refusal = navigation_refusal(path_act(unknown), ZONES)
    assert refusal is not None
    assert "no transform" in refusal.text
    assert "nothing was sent" in refusal.text
    # Without a policy the poses still meet the map, and these are free.
    assert navigation_refusal(path_act(unknown), NONE) is None
    # From the robot at (1, 0.5) to the first pose is clear, and so is the rest: allowed under the zones.
    known = Scene("/map", "base_link", grid=GRID, robot=Pose2D(1.0, 0.5, 0.0), goals=goals)
    assert navigation_refusal(path_act(known), ZONES) is None
    # A path whose one pose is clear of the box, which the robot west of the box drives straight through.
    crossing = Scene(
        "/map", "base_link", grid=GRID, robot=Pose2D(1.0, 0.5, 0.0), goals=(Pose2D(4.0, 0.5, 0.0),)
    )
    goal = {"path": {"header": {"frame_id": "map"}, "poses": [stamped(4.0, 0.5)]}}
    act = Act("publish_action", "action", "/follow_path", "nav2_msgs/FollowPathAction", goal, scene=crossing)
    refusal = navigation_refusal(act, ZONES)
    assert refusal is not None
    assert "passes through the keep-out zone 'box'" in refusal.text


def test_a_send_goal_call_spelt_without_send_goal_in_its_type_is_still_judged() -> None:
    scene = Scene("/map", "base_link", grid=GRID, robot=Pose2D(1.0, 3.0, 0.0), goals=(Pose2D(2.5, 0.5, 0.0),))
    act = Act(
        "publish_service",
        "service",
        "/navigate_to_pose/_action/send_goal",
        "nav2_msgs/NavigateToPose",
        {"goal": {"pose": stamped(2.5, 0.5)}},
        scene=scene,
    )
    refusal = navigation_refusal(act, ZONES)
    assert refusal is not None
    assert "inside the keep-out zone 'box'" in refusal.text


def test_a_drive_is_asked_about_by_its_distance_not_by_where_the_robot_stands() -> None:
    """The question must read the same in a second round, when the robot's pose has jittered."""
    goal = {"target": {"x": -0.5}, "speed": 0.1}
    act = Act("publish_action", "action", "/backup", "nav2_msgs/action/BackUp", goal)
    assert goal_text(act) == "Drives the robot 0.50 m backward along its heading."
    spin = Act("publish_action", "action", "/spin", "nav2_msgs/action/Spin", {"target_yaw": 1.0})
    assert goal_text(spin) == "Turns the robot in place."


def test_a_path_too_long_to_check_is_refused_not_sampled() -> None:
    """2,000 pieces of 7 m across a 6 m map would be 280,000 samples: refused at once, naming the length."""
    corners = [Pose2D(0.5, 0.5, 0.0), Pose2D(5.5, 5.5, 0.0)]
    goals = tuple(corners[i % 2] for i in range(2000))
    scene = Scene("/map", "base_link", grid=GRID, robot=Pose2D(0.5, 0.5, 0.0), goals=goals)
    poses = [stamped(goal.x, goal.y) for goal in goals]
    goal = {"path": {"header": {"frame_id": "map"}, "poses": poses}}
    act = Act("publish_action", "action", "/follow_path", "nav2_msgs/action/FollowPath", goal, scene=scene)
    refusal = navigation_refusal(act, NONE)
    assert refusal is not None
    assert "14135 m in all, too long to check on the map" in refusal.text
