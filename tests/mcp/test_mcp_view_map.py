"""view_map through an MCP session: the room's map with the robot, the plan and the scan where they are."""

from __future__ import annotations

import asyncio
import base64
import io
import json
import math
import time
from typing import Any

import pytest
import websockets
from mcp.types import CallToolResult, ImageContent
from mcp_harness import Session, open_session, text_of
from PIL import Image

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.pictures.drawing import OBSTACLE_COLOUR, PATH_COLOUR, ROBOT_COLOUR
from rosbridge_mcp_server.pictures.maps import MARGIN_BOTTOM, MARGIN_LEFT
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.nodes.navigation import PLAN_GOAL
from rosbridge_mcp_server.sim.world import TURTLE_ARENA, TURTLE_HOME


def picture_of(result: CallToolResult) -> Image.Image:
    images = [block for block in result.content if isinstance(block, ImageContent)]
    assert len(images) == 1
    assert images[0].mime_type == "image/png"
    return Image.open(io.BytesIO(base64.b64decode(images[0].data))).convert("RGB")


def pixel_of(data: dict[str, Any], image: Image.Image, x: float, y: float) -> tuple[int, int]:
    """Where map point (x, y) is on the picture, from the answer's window and scale."""
    x_min, y_min = data["window"][0], data["window"][1]
    ppm = data["pixels_per_metre"]
    return (
        round(MARGIN_LEFT + (x - x_min) * ppm),
        round(image.height - MARGIN_BOTTOM - (y - y_min) * ppm),
    )


def colour_near(
    image: Image.Image, at: tuple[int, int], colour: tuple[int, int, int], reach: int = 2
) -> bool:
    """Whether a pixel within ``reach`` of ``at`` has about this colour (the PNG is palette-quantised)."""
    return any(
        all(abs(a - b) <= 16 for a, b in zip(image.getpixel((x, y)), colour, strict=True))  # type: ignore[arg-type]
        for x in range(at[0] - reach, at[0] + reach + 1)
        for y in range(at[1] - reach, at[1] + reach + 1)
        if 0 <= x < image.width and 0 <= y < image.height
    )


async def test_the_robot_is_drawn_at_its_pose_from_tf(session: Session, sim: SimulatedRobot) -> None:
    """The turtle moved to (3, 7) facing 60°: the answer says so and the blue arrow is there."""
    sim.world.turtle.x, sim.world.turtle.y, sim.world.turtle.theta = 3.0, 7.0, math.radians(60)
    result = await session.ok("view_map", {})
    data = result.structured_content
    assert data is not None
    assert data["robot"] == pytest.approx([3.0, 7.0, 60.0], abs=0.01)
    assert (data["cells"], data["frame_id"]) == ([242, 242], "map")
    assert data["shares"]["known"] == pytest.approx(0.89, abs=0.01)
    image = picture_of(result)
    assert colour_near(image, pixel_of(data, image, 3.0, 7.0), ROBOT_COLOUR, reach=0)
    assert not colour_near(image, pixel_of(data, image, TURTLE_HOME, TURTLE_HOME), ROBOT_COLOUR, reach=3)
    assert "robot base_link at x=3 y=7 yaw=60°" in text_of(result)


async def test_the_scan_lands_on_the_walls_and_the_plan_reaches_its_goal(session: Session) -> None:
    """From the start the laser hits the wall straight ahead (x = arena edge); the plan ends at its goal."""
    result = await session.ok("view_map", {"path_topic": "/plan", "scan_topic": "/scan"})
    data = result.structured_content
    assert data is not None
    assert data["scan_hits"] > 300
    assert data["path_poses"] > 10
    image = picture_of(result)
    assert colour_near(image, pixel_of(data, image, TURTLE_ARENA, TURTLE_HOME), OBSTACLE_COLOUR)
    assert colour_near(image, pixel_of(data, image, *PLAN_GOAL), PATH_COLOUR)
    assert not colour_near(image, pixel_of(data, image, 3.0, 3.0), OBSTACLE_COLOUR, reach=3)


async def test_around_robot_shows_a_window_centred_on_the_robot(session: Session) -> None:
    """around_robot 2 shows about 4 m by 4 m around the turtle, as large as max_size allows."""
    result = await session.ok("view_map", {"around_robot": 2, "max_size": 300})
    data = result.structured_content
    assert data is not None
    x_min, y_min, x_max, y_max = data["window"]
    assert (x_min + x_max) / 2 == pytest.approx(TURTLE_HOME, abs=0.1)
    assert (y_min + y_max) / 2 == pytest.approx(TURTLE_HOME, abs=0.1)
    assert x_max - x_min == pytest.approx(4.0, abs=0.15)
    image = picture_of(result)
    assert max(image.size) == 300
    assert colour_near(image, pixel_of(data, image, TURTLE_HOME, TURTLE_HOME), ROBOT_COLOUR, reach=0)


async def test_a_frame_tf_does_not_know_is_a_note_not_a_failure(session: Session) -> None:
    """A misspelt base frame: the map still comes, the robot is not drawn, the note says why."""
    result = await session.ok("view_map", {"base_frame": "base_lnk", "around_robot": 2, "timeout": 3})
    data = result.structured_content
    assert data is not None
    assert data["robot"] is None
    assert any("'base_lnk' has not been seen" in note for note in data["notes"])
    assert "around_robot needs the robot's pose" in text_of(result)


@pytest.mark.parametrize(
    ("arguments", "complaint"),
    [
        ({"topic": "/scan"}, "topic: /scan carries sensor_msgs"),
        ({"topic": "/mapp"}, "Topic /mapp is not in the ROS graph. Did you mean /map?"),
        ({"path_topic": "/odom"}, "path_topic: /odom carries nav_msgs"),
        ({"scan_topic": "/map"}, "scan_topic: /map carries nav_msgs"),
        ({"max_size": 10}, "max_size"),
    ],
)
async def test_bad_arguments_are_errors_naming_what_is_wrong(
    session: Session, arguments: dict[str, Any], complaint: str
) -> None:
    """Wrong types, unknown topics and out-of-range sizes are isError answers."""
    assert complaint in await session.error("view_map", arguments)


async def test_a_costmap_in_the_odom_frame_is_shaded_and_places_the_robot_through_tf(
    sim: SimulatedRobot,
) -> None:
    """A latched 20x20 costmap in odom: cost cells counted and coloured, the robot at odom's (0, 0)."""
    costmap_type = "nav_msgs/msg/OccupancyGrid" if sim.dialect == "ros2" else "nav_msgs/OccupancyGrid"
    cells = [0] * 400
    for index in range(200, 300):
        cells[index] = 50
    costmap = {
        "header": {"frame_id": "odom"},
        "info": {
            "resolution": 0.1,
            "width": 20,
            "height": 20,
            "origin": {"position": {"x": -1.0, "y": -1.0, "z": 0.0}, "orientation": {"w": 1.0}},
        },
        "data": cells,
    }
    async with RosbridgeClient(sim.url, connect_timeout=2.0, request_timeout=5.0) as publisher:
        await publisher.wait_connected(30.0)
        await publisher.publish("/test/costmap", costmap_type, costmap, latch=True)
        async with open_session(sim.url) as session:
            result = await session.ok("view_map", {"topic": "/test/costmap"})
    data = result.structured_content
    assert data is not None
    assert data["shares"]["cost"] == pytest.approx(0.25)
    assert data["robot"] == pytest.approx([0.0, 0.0, 0.0], abs=0.01)
    image = picture_of(result)
    red, green, blue = image.getpixel(pixel_of(data, image, 0.5, 0.5))  # type: ignore[misc]
    assert (red, green, blue) != (254, 254, 254)
    assert red > green
    assert "cost 25%" in text_of(result)


async def test_a_2000_cell_map_is_drawn_with_its_walls(make_sim: Any) -> None:
    """The room at 2000x2000 cells (4 M numbers of JSON) arrives and shrinks to 800 px, walls intact."""
    robot = await make_sim(map_cells=2000)
    async with open_session(robot.url) as session:
        result = await session.ok("view_map", {"timeout": 20})
    data = result.structured_content
    assert data is not None
    assert data["cells"] == [2000, 2000]
    image = picture_of(result)
    assert max(image.size) == 800
    assert colour_near(image, pixel_of(data, image, -0.05, 3.0), (0, 0, 0), reach=1)
    assert colour_near(image, pixel_of(data, image, TURTLE_HOME, TURTLE_HOME), ROBOT_COLOUR, reach=0)


async def test_a_large_map_through_cbor_draws_the_same_picture_as_through_json(make_sim: Any) -> None:
    """A 1000x1000 map: view_map on a bridge that answers CBOR and on one that ignores it, pixel for pixel."""
    answers = []
    for cbor in (True, False):
        robot = await make_sim(map_cells=1000, cbor=cbor)
        async with open_session(robot.url) as session:
            answers.append(await session.ok("view_map", {"timeout": 20}))
    through_cbor, through_json = answers
    assert through_cbor.structured_content == through_json.structured_content
    assert picture_of(through_cbor).tobytes() == picture_of(through_json).tobytes()


async def test_a_path_without_a_frame_is_drawn_in_the_maps(sim: SimulatedRobot) -> None:
    """A nav_msgs/Path whose header names no frame is taken to be in the map's frame."""
    path_type = "nav_msgs/msg/Path" if sim.dialect == "ros2" else "nav_msgs/Path"
    poses = [{"pose": {"position": {"x": x, "y": 2.0}, "orientation": {"w": 1.0}}} for x in (2.0, 4.0, 6.0)]
    async with RosbridgeClient(sim.url, connect_timeout=2.0, request_timeout=5.0) as publisher:
        await publisher.wait_connected(30.0)
        await publisher.publish("/test/path", path_type, {"poses": poses}, latch=True)
        async with open_session(sim.url) as session:
            result = await session.ok("view_map", {"path_topic": "/test/path"})
    data = result.structured_content
    assert data is not None
    assert data["path_poses"] == 3
    assert data["notes"] == []
    image = picture_of(result)
    assert colour_near(image, pixel_of(data, image, 6.0, 2.0), PATH_COLOUR)


async def test_a_silent_path_topic_is_a_note_and_the_map_still_comes(sim: SimulatedRobot) -> None:
    """A Path topic that is advertised but never published: the map is drawn, the note names the topic."""
    path_type = "nav_msgs/msg/Path" if sim.dialect == "ros2" else "nav_msgs/Path"
    async with RosbridgeClient(sim.url, connect_timeout=2.0, request_timeout=5.0) as publisher:
        await publisher.wait_connected(30.0)
        await publisher.advertise("/test/silent_plan", path_type)
        async with open_session(sim.url) as session:
            result = await session.ok("view_map", {"path_topic": "/test/silent_plan", "timeout": 3.0})
    data = result.structured_content
    assert data is not None
    assert data["path_poses"] is None
    assert data["notes"] == ["path not drawn: nothing arrived on /test/silent_plan within 3 s."]


async def test_a_map_too_large_for_one_cbor_frame_is_read_as_json_with_a_note(make_sim: Any) -> None:
    """A bridge fragmenting above 100 kB drops the 250 kB CBOR frame: view_map waits once more, for JSON."""
    robot = await make_sim(dialect="ros2", map_cells=500, max_message_size=100_000)
    async with open_session(robot.url) as session:
        result = await session.ok("view_map", {"timeout": 3})
    data = result.structured_content
    assert data is not None
    assert data["cells"] == [500, 500]
    assert any("did not arrive as CBOR within 3 s" in note for note in data["notes"])


def robot_pixels(image: Image.Image) -> int:
    """How many pixels of the picture have about the robot's colour."""
    return sum(
        count
        for count, colour in image.getcolors(image.width * image.height) or []
        if all(abs(a - b) <= 16 for a, b in zip(colour, ROBOT_COLOUR, strict=True))  # type: ignore[arg-type]
    )


def grid_message(origin: tuple[float, float], yaw: float = 0.0) -> dict[str, Any]:
    """A free 1 m x 1 m grid (10 x 10 cells of 0.1 m) in the map frame, its origin at ``origin``, turned by
    ``yaw`` radians."""
    return {
        "header": {"frame_id": "map"},
        "info": {
            "resolution": 0.1,
            "width": 10,
            "height": 10,
            "origin": {
                "position": {"x": origin[0], "y": origin[1], "z": 0.0},
                "orientation": {"z": math.sin(yaw / 2), "w": math.cos(yaw / 2)},
            },
        },
        "data": [0] * 100,
    }


async def view_grid(sim: SimulatedRobot, grid: dict[str, Any], calls: list[dict[str, Any]]) -> list[Any]:
    """view_map of *grid* (latched on /test/small_map) once per argument set in *calls*."""
    grid_type = "nav_msgs/msg/OccupancyGrid" if sim.dialect == "ros2" else "nav_msgs/OccupancyGrid"
    async with RosbridgeClient(sim.url, connect_timeout=2.0, request_timeout=5.0) as publisher:
        await publisher.wait_connected(30.0)
        await publisher.publish("/test/small_map", grid_type, grid, latch=True)
        async with open_session(sim.url) as session:
            return [await session.ok("view_map", {"topic": "/test/small_map", **call}) for call in calls]


async def test_a_robot_off_the_map_is_said_to_be_off_it_with_where_and_how_far(sim: SimulatedRobot) -> None:
    """A 1 m map at (0, 0)..(1, 1), the turtle at (4, 5): not drawn, and the text says it is off the map,
    where, and how far (5 m from the map's corner)."""
    sim.world.turtle.x, sim.world.turtle.y = 4.0, 5.0
    results = await view_grid(sim, grid_message((0.0, 0.0)), [{}, {"around_robot": 2}])
    for result in results:
        data = result.structured_content
        assert data is not None
        assert data["robot"] == pytest.approx([4.0, 5.0, 0.0], abs=0.01)
        said = (
            "The robot (base_link at x=4 y=5 in map) is off the map, 5 m outside its extent (x 0..1, "
            "y 0..1 m), so the picture cannot show it."
        )
        assert data["notes"][0] == said
        text = text_of(result)
        assert "robot base_link at x=4 y=5 yaw=0° (off the map: not drawn)" in text
        assert said in text
        assert "blue arrow" not in text
        assert robot_pixels(picture_of(result)) == 0


async def test_a_robot_on_the_map_is_drawn_and_not_said_to_be_off_it(sim: SimulatedRobot) -> None:
    """The same 1 m map with the turtle at (0.5, 0.5) on it: drawn, no word of being off the map."""
    sim.world.turtle.x, sim.world.turtle.y = 0.5, 0.5
    [result] = await view_grid(sim, grid_message((0.0, 0.0)), [{}])
    data = result.structured_content
    assert data is not None
    assert data["robot"] == pytest.approx([0.5, 0.5, 0.0], abs=0.01)
    assert data["notes"] == []
    assert "robot base_link at x=0.5 y=0.5 yaw=0° (blue arrow)" in text_of(result)
    assert "off the map" not in text_of(result)
    assert robot_pixels(picture_of(result)) > 0


async def test_off_a_rotated_map_the_distance_is_to_its_nearest_edge(sim: SimulatedRobot) -> None:
    """The 1 m map at (5, 0) turned 90° covers x 4..5, y 0..1: the turtle at (2, 0.5) is 2 m off it."""
    sim.world.turtle.x, sim.world.turtle.y = 2.0, 0.5
    [result] = await view_grid(sim, grid_message((5.0, 0.0), math.pi / 2), [{}])
    data = result.structured_content
    assert data is not None
    assert data["robot"] == pytest.approx([2.0, 0.5, 0.0], abs=0.01)
    assert (
        "(base_link at x=2 y=0.5 in map) is off the map, 2 m outside its extent (x 4..5, y 0..1 m)"
        in (data["notes"][0])
    )


def _extreme(resolution: float, origin: float) -> dict[str, Any]:
    grid = grid_message((origin, -origin))
    grid["info"]["resolution"] = resolution
    return grid


@pytest.mark.parametrize(
    ("grid", "words"),
    [
        # 10 cells of 1e308 m: the extent is infinite (its axis ticks never ended: a thread spun, memory grew)
        (_extreme(1e308, 0.0), "The map's resolution is 1e+308 m per cell"),
        (_extreme(1e-300, 0.0), "The map's resolution is 1e-300 m per cell"),
        (_extreme(0.1, 1e308), "The map's origin (1e+308, -1e+308) lies"),  # was an OverflowError
    ],
)
async def test_a_map_of_absurd_size_or_place_is_refused_in_our_words(
    sim_ros2: SimulatedRobot, grid: dict[str, Any], words: str
) -> None:
    async with RosbridgeClient(sim_ros2.url, connect_timeout=2.0, request_timeout=5.0) as publisher:
        await publisher.wait_connected(30.0)
        await publisher.publish("/test/small_map", "nav_msgs/msg/OccupancyGrid", grid, latch=True)
        async with open_session(sim_ros2.url) as session:
            text = await asyncio.wait_for(session.error("view_map", {"topic": "/test/small_map"}), 20)
    assert words in text, text
    assert "unexpected error" not in text


async def test_a_robot_placed_absurdly_far_by_tf_is_said_to_be_off_the_map(sim_ros2: SimulatedRobot) -> None:
    """/tf puts the base 1.7e308 m away: the answer says the robot is off the map (how far overflowed: an
    "unexpected error")."""
    now = int(time.time())
    far = {
        "header": {"stamp": {"sec": now, "nanosec": 0}, "frame_id": "map"},
        "child_frame_id": "far_base",
        "transform": {"translation": {"x": 1.7e308, "y": -1.7e308}, "rotation": {"w": 1.0}},
    }
    async with open_session(sim_ros2.url) as session, websockets.connect(sim_ros2.url) as raw:
        await raw.send(json.dumps({"op": "advertise", "topic": "/tf", "type": "tf2_msgs/msg/TFMessage"}))

        async def publish() -> None:
            while True:
                await raw.send(json.dumps({"op": "publish", "topic": "/tf", "msg": {"transforms": [far]}}))
                await asyncio.sleep(0.05)

        publishing = asyncio.create_task(publish())
        try:
            result = await session.ok("view_map", {"base_frame": "far_base"})
        finally:
            publishing.cancel()
    assert "is off the map, over 1e+12 m outside its extent" in text_of(result), text_of(result)
