"""The picture tools with several robots behind one server: each picture is of the robot the call names."""

from __future__ import annotations

from mcp_harness import text_of
from test_mcp_fleet import fleet_session

from rosbridge_mcp_server.sim import SimulatedRobot


async def test_view_map_draws_the_robot_the_call_names(
    sim_ros2: SimulatedRobot, sim_ros1: SimulatedRobot
) -> None:
    """Two turtles at different places: each robot's view_map puts its own turtle on its own map."""
    sim_ros2.world.turtle.x, sim_ros2.world.turtle.y = 2.0, 3.0
    sim_ros1.world.turtle.x, sim_ros1.world.turtle.y = 8.0, 9.0
    async with fleet_session({"jazzy": sim_ros2, "noetic": sim_ros1}) as client:
        jazzy = await client.call_tool("view_map", {"robot": "jazzy"})
        noetic = await client.call_tool("view_map", {"robot": "noetic"})
    assert not jazzy.is_error, text_of(jazzy)
    assert not noetic.is_error, text_of(noetic)
    assert jazzy.structured_content is not None
    assert noetic.structured_content is not None
    assert jazzy.structured_content["robot"][:2] == [2.0, 3.0]
    assert noetic.structured_content["robot"][:2] == [8.0, 9.0]
