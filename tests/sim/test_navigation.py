"""The navigating robot's topics: the room's latched /map, /plan and /odom, and ray-casting against a grid."""

from __future__ import annotations

import math
from array import array

import pytest
from rawclient import RawClient

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.maps import FREE, OCCUPIED, UNKNOWN, GridMap
from rosbridge_mcp_server.sim.nodes.navigation import PLAN_GOAL
from rosbridge_mcp_server.sim.nodes.room import PILLAR, ray_distance, turtle_room_map
from rosbridge_mcp_server.sim.world import TURTLE_ARENA, TURTLE_HOME


async def test_map_is_latched_and_shows_the_room_walls_pillar_and_unknown_beyond(sim: SimulatedRobot) -> None:
    """A late subscriber gets /map (latched: it is published once): free inside, occupied walls and pillar,
    unknown outside."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/map", "id": "map"})
        # Not before a barrier's reply: a loaded machine delivered the latched message just after it.
        published = await client.next_publish("/map")
    msg = published["msg"]
    info = msg["info"]
    assert msg["header"]["frame_id"] == "map"
    assert (info["width"], info["height"]) == (242, 242)
    assert info["resolution"] == pytest.approx(0.05, abs=1e-3)
    grid = GridMap(
        info["width"],
        info["height"],
        info["resolution"],
        (info["origin"]["position"]["x"], info["origin"]["position"]["y"]),
        array("b", msg["data"]),
    )
    assert grid.value(TURTLE_HOME, TURTLE_HOME) == FREE
    assert grid.value(PILLAR[0], PILLAR[1]) == OCCUPIED
    assert grid.value(-0.07, 3.0) == OCCUPIED  # the wall just outside x = 0
    assert grid.value(TURTLE_ARENA + 0.4, 3.0) == UNKNOWN


def test_grid_ray_cast_agrees_with_the_exact_room_within_a_cell() -> None:
    """Rays against the rasterised room stop where the exact walls and pillar are, give or take a cell."""
    grid = turtle_room_map()
    for degrees in range(0, 360, 7):
        angle = math.radians(degrees)
        exact = ray_distance(3.0, 6.0, angle)
        assert grid.ray_distance(3.0, 6.0, angle, 20.0) == pytest.approx(exact, abs=2 * grid.resolution)


def test_grid_ray_cast_reports_inf_beyond_its_range() -> None:
    """A ray that meets nothing within max_range is inf."""
    assert grid_ray(max_range=1.0) == math.inf
    assert grid_ray(max_range=10.0) == pytest.approx(TURTLE_ARENA - 3.0, abs=0.1)


def grid_ray(max_range: float) -> float:
    return turtle_room_map().ray_distance(3.0, 6.0, 0.0, max_range)


def test_a_finer_room_map_is_the_same_room() -> None:
    """map_cells only changes the resolution: the room, its pillar and its walls stay where they are."""
    fine = turtle_room_map(2000)
    assert (fine.width, fine.height) == (2000, 2000)
    assert fine.value(PILLAR[0] + 0.45, PILLAR[1]) == OCCUPIED
    assert fine.value(PILLAR[0] + 0.55, PILLAR[1]) == FREE
    assert fine.value(TURTLE_ARENA + 0.05, 5.0) == OCCUPIED


async def test_plan_leads_from_the_turtle_to_the_goal_in_the_map_frame(sim: SimulatedRobot) -> None:
    """/plan is latched; its first pose is the turtle's position and its last the planner's goal."""
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/plan", "id": "plan"})
        plan = (await client.next_publish("/plan"))["msg"]
    assert plan["header"]["frame_id"] == "map"
    first, last = plan["poses"][0]["pose"]["position"], plan["poses"][-1]["pose"]["position"]
    assert (last["x"], last["y"]) == pytest.approx(PLAN_GOAL)
    assert (first["x"], first["y"]) == pytest.approx((TURTLE_HOME, TURTLE_HOME))
    steps = [
        math.dist(
            (a["pose"]["position"]["x"], a["pose"]["position"]["y"]),
            (b["pose"]["position"]["x"], b["pose"]["position"]["y"]),
        )
        for a, b in zip(plan["poses"], plan["poses"][1:], strict=False)
    ]
    assert max(steps) <= 0.1 + 1e-9


async def test_odom_is_the_turtle_pose_relative_to_its_start(sim: SimulatedRobot) -> None:
    """/odom: frame odom, child base_link, the pose of odom → base_link and the commanded speeds."""
    sim.world.turtle.x, sim.world.turtle.theta = TURTLE_HOME + 1.0, math.pi / 2
    async with await RawClient.open(sim.url) as client:
        await client.send({"op": "subscribe", "topic": "/odom", "id": "odom"})
        odom = (await client.next_publish("/odom"))["msg"]
    assert (odom["header"]["frame_id"], odom["child_frame_id"]) == ("odom", "base_link")
    assert odom["pose"]["pose"]["position"]["x"] == pytest.approx(1.0)
    assert odom["pose"]["pose"]["orientation"]["z"] == pytest.approx(math.sin(math.pi / 4))
