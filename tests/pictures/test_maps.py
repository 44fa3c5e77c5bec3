"""Occupancy grids to pictures: decoding, shares, colours, the robot and overlays where their poses are."""

from __future__ import annotations

import dataclasses
import math
from array import array
from typing import Any

import pytest
from PIL import Image

from rosbridge_mcp_server.pictures.drawing import OBSTACLE_COLOUR, PATH_COLOUR, ROBOT_COLOUR
from rosbridge_mcp_server.pictures.maps import MARGIN_BOTTOM, MARGIN_LEFT, MapPicture, Overlay, draw_map
from rosbridge_mcp_server.robot.occupancy import MapError, Pose2D, decode_grid, decode_path


def grid_message(
    width: int, height: int, cells: list[int], *, resolution: float = 0.1, yaw: float = 0.0
) -> dict[str, Any]:
    return {
        "header": {"frame_id": "/map"},
        "info": {
            "resolution": resolution,
            "width": width,
            "height": height,
            "origin": {
                "position": {"x": -1.0, "y": -2.0, "z": 0.0},
                "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)},
            },
        },
        "data": cells,
    }


def room(width: int = 100, height: int = 60) -> list[int]:
    """Free inside a one-cell occupied border, the top ten rows unknown, a cost patch at columns 60-69."""
    cells = []
    for row in range(height):
        for col in range(width):
            if row >= height - 10:
                cells.append(-1)
            elif row in (0, height - 11) or col in (0, width - 1):
                cells.append(100)
            elif 60 <= col < 70 and 10 <= row < 20:
                cells.append(40)
            else:
                cells.append(0)
    return cells


def pixel_of(picture: MapPicture, x: float, y: float) -> tuple[int, int]:
    """Where map point (x, y) is drawn (unrotated grid)."""
    x_min, y_min = picture.window[0], picture.window[1]
    ppm = picture.pixels_per_metre
    map_height = picture.image.height - MARGIN_BOTTOM
    return (round(MARGIN_LEFT + (x - x_min) * ppm), round(map_height - (y - y_min) * ppm))


def colour_near(
    image: Image.Image, at: tuple[int, int], colour: tuple[int, int, int], reach: int = 2
) -> bool:
    x0, y0 = at
    rgb = image.convert("RGB")
    return any(
        all(abs(a - b) <= 12 for a, b in zip(rgb.getpixel((x, y)), colour, strict=True))  # type: ignore[arg-type]
        for x in range(x0 - reach, x0 + reach + 1)
        for y in range(y0 - reach, y0 + reach + 1)
        if 0 <= x < image.width and 0 <= y < image.height
    )


def test_a_grid_decodes_with_its_frame_origin_and_cells_as_bytes() -> None:
    """int8 -1 becomes byte 255; the frame loses its leading slash; the origin's yaw is read."""
    grid = decode_grid(grid_message(2, 2, [0, 100, -1, 50], yaw=math.pi / 2))
    assert grid.cells == bytes([0, 100, 255, 50])
    assert grid.frame_id == "map"
    assert (grid.origin.x, grid.origin.y) == (-1.0, -2.0)
    assert grid.origin.yaw == pytest.approx(math.pi / 2)


@pytest.mark.parametrize(
    ("message", "complaint"),
    [
        ({"data": []}, "no 'info'"),
        (grid_message(0, 2, []), "must be positive"),
        ({**grid_message(2, 2, [0] * 4), "info": {"width": 2, "height": 2, "resolution": 0}}, "resolution"),
        (grid_message(2, 2, [0, 0, 0]), "has 3 cells of data; 2 x 2 needs 4"),
        (grid_message(2, 2, [0, 0, 0, 300]), "not int8"),
    ],
)
def test_a_malformed_grid_is_refused_naming_the_field(message: dict[str, Any], complaint: str) -> None:
    """Each broken field gets a sentence saying what is wrong."""
    with pytest.raises(MapError, match=complaint):
        decode_grid(message)


def test_shares_count_known_free_occupied_and_cost_cells() -> None:
    """Unknown, free, occupied and cost cells are counted apart."""
    picture = draw_map(decode_grid(grid_message(100, 60, room())), max_size=400, overlay=Overlay())
    shares = picture.shares
    assert shares.known == pytest.approx(50 / 60)
    assert shares.cost == pytest.approx(100 / 6000)
    assert shares.occupied == pytest.approx((2 * 100 + 2 * 48) / 6000)
    assert shares.free == pytest.approx(shares.known - shares.cost - shares.occupied)


def test_free_occupied_unknown_and_cost_cells_have_their_colours() -> None:
    """Free is white, a wall black, unknown grey, a cost a shade of yellow to purple."""
    picture = draw_map(decode_grid(grid_message(100, 60, room())), max_size=1000, overlay=Overlay())
    image = picture.image
    assert image.getpixel(pixel_of(picture, 2.0, 0.0)) == (254, 254, 254)
    assert image.getpixel(pixel_of(picture, -0.95, 0.0)) == (0, 0, 0)  # the left wall
    assert image.getpixel(pixel_of(picture, 2.0, 3.5)) == (205, 205, 205)  # the unknown rows
    assert image.getpixel(pixel_of(picture, 5.5, -0.5)) == (218, 112, 157)  # cost 40: yellow to purple


def test_the_robot_path_and_hits_are_drawn_where_their_coordinates_are() -> None:
    """A blue arrow at the robot's pose, the path's end green, a hit red."""
    overlay = Overlay(robot=Pose2D(3.0, 0.0, 0.3), path=[(1.0, -1.0), (6.0, -1.0)], hits=[(7.0, 1.0)])
    picture = draw_map(decode_grid(grid_message(100, 60, room())), max_size=800, overlay=overlay)
    assert colour_near(picture.image, pixel_of(picture, 3.0, 0.0), ROBOT_COLOUR, reach=0)
    assert colour_near(picture.image, pixel_of(picture, 6.0, -1.0), PATH_COLOUR)
    assert colour_near(picture.image, pixel_of(picture, 7.0, 1.0), OBSTACLE_COLOUR, reach=1)
    assert not colour_near(picture.image, pixel_of(picture, 5.0, 1.0), ROBOT_COLOUR, reach=3)


def test_one_cell_walls_survive_shrinking_a_large_map() -> None:
    """A 2000-cell-wide map shown 400 pixels wide still has its one-cell wall (every column of it black)."""
    width, height = 2000, 50
    cells = array("b", [0]) * (width * height)
    for col in range(width):
        cells[25 * width + col] = 100
    picture = draw_map(
        decode_grid(grid_message(width, height, cells.tolist())), max_size=400, overlay=Overlay()
    )
    row = round(picture.image.height - MARGIN_BOTTOM - 25.5 * 0.1 * picture.pixels_per_metre)
    band = [
        min(picture.image.getpixel((x, y))[0] for y in range(row - 1, row + 2))  # type: ignore[index]
        for x in range(MARGIN_LEFT + 1, picture.image.width - 1)
    ]
    assert max(band) == 0


def test_a_window_shows_only_the_metres_asked_for() -> None:
    """The window is cut to whole cells around the asked square, and drawn as large as max_size allows."""
    picture = draw_map(
        decode_grid(grid_message(100, 60, room())),
        max_size=300,
        overlay=Overlay(),
        window=(2.0, -1.0, 4.0, 1.0),
    )
    assert picture.window == pytest.approx((2.0, -1.0, 4.0, 1.0), abs=0.1)
    assert max(picture.image.size) == 300


def test_a_path_decodes_to_its_frame_and_points_skipping_malformed_poses() -> None:
    """Poses without a numeric position are left out."""
    message = {
        "header": {"frame_id": "odom"},
        "poses": [
            {"pose": {"position": {"x": 1, "y": 2}}},
            {"pose": {"position": {"x": None, "y": 2}}},
            {"nothing": 1},
            {"pose": {"position": {"x": 3.5, "y": -1.0}}},
        ],
    }
    assert decode_path(message) == ("odom", [(1.0, 2.0), (3.5, -1.0)])


def test_a_rotated_grid_places_points_in_its_own_axes() -> None:
    """A grid turned 90° in its frame: map point (-2.5, 3.5) is cell (3.5, 2.5), and back."""
    unturned = decode_grid(grid_message(10, 10, [0] * 100, resolution=1.0))
    grid = dataclasses.replace(unturned, origin=Pose2D(0.0, 0.0, math.pi / 2))
    assert grid.to_cell(-2.5, 3.5) == pytest.approx((3.5, 2.5))
    assert grid.to_map(3.5, 2.5) == pytest.approx((-2.5, 3.5))
    picture = draw_map(grid, max_size=400, overlay=Overlay(robot=Pose2D(-2.5, 3.5, math.pi / 2)))
    scale = picture.pixels_per_metre
    at = (round(MARGIN_LEFT + 3.5 * scale), round(picture.image.height - MARGIN_BOTTOM - 2.5 * scale))
    assert colour_near(picture.image, at, ROBOT_COLOUR, reach=0)


def test_overlays_outside_a_window_are_cut_at_the_plots_edge() -> None:
    """Scan hits and a path beyond the window (around_robot) draw nothing over the axes and their labels."""
    far = [(x * 0.1, y * 0.1) for x in range(-10, 90) for y in (-19, 35)]  # beyond the window on both sides
    overlay = Overlay(robot=Pose2D(3.0, 0.0, 0.0), path=[(-1.0, -2.0), (9.0, 4.0)], hits=far)
    picture = draw_map(
        decode_grid(grid_message(100, 60, room())),
        max_size=300,
        overlay=overlay,
        window=(2.0, -1.0, 4.0, 1.0),
    )
    image = picture.image
    plot_bottom = image.height - MARGIN_BOTTOM
    margins = [
        (x, y) for x in range(image.width) for y in range(image.height) if x < MARGIN_LEFT or y >= plot_bottom
    ]
    drawn = {image.getpixel(xy) for xy in margins}
    assert OBSTACLE_COLOUR not in drawn
    assert PATH_COLOUR not in drawn
    assert ROBOT_COLOUR not in drawn
    # Inside the plot they are still drawn.
    assert colour_near(image, pixel_of(picture, 3.0, 0.0), ROBOT_COLOUR, reach=0)


def test_the_scale_bar_sits_below_the_map_and_hides_no_corner_of_it() -> None:
    """The map's lower-left corner keeps its cells' colours; the bar is drawn in the bottom margin."""
    picture = draw_map(decode_grid(grid_message(100, 60, room())), max_size=400, overlay=Overlay())
    image = picture.image
    plot_bottom = image.height - MARGIN_BOTTOM
    # Just inside the one-cell wall, the free cells of the corner are white (no box, no bar).
    corner = [
        image.getpixel((x, y))
        for x in range(MARGIN_LEFT + 6, MARGIN_LEFT + 60)
        for y in range(plot_bottom - 40, plot_bottom - 6)
    ]
    assert set(corner) == {(254, 254, 254)}
    bar_rows = [
        y for y in range(plot_bottom, image.height) if image.getpixel((MARGIN_LEFT + 20, y)) == (20, 20, 20)
    ]
    assert bar_rows, "the scale bar is not in the bottom margin"


def test_the_robot_arrow_is_large_enough_to_see() -> None:
    """On a 420-pixel map of a small room, the arrow spans at least a twentieth of the picture."""
    picture = draw_map(
        decode_grid(grid_message(100, 60, room())), max_size=420, overlay=Overlay(robot=Pose2D(3.0, 0.0, 0.0))
    )
    image = picture.image
    blue = [
        x for x in range(image.width) for y in range(image.height) if image.getpixel((x, y)) == ROBOT_COLOUR
    ]
    assert max(blue) - min(blue) >= max(image.size) / 20
