"""Topic fields over time: dotted paths to numbers, units, figures, and the chart's lines and legend."""

from __future__ import annotations

import math

import pytest

from rosbridge_mcp_server.pictures.charts import draw_chart, stats
from rosbridge_mcp_server.pictures.drawing import SERIES_COLOURS
from rosbridge_mcp_server.robot.series import FieldError, Series, unit_of, value_at

ODOM = {"twist": {"twist": {"linear": {"x": 0.5, "y": 0.0}}}, "ranges": [1.0, None], "ok": True, "name": "a"}


def test_a_dotted_path_reads_nested_fields_array_items_and_booleans() -> None:
    """Nested fields, indices, booleans as 1, null as a gap (NaN)."""
    assert value_at(ODOM, "twist.twist.linear.x") == 0.5
    assert value_at(ODOM, "ranges.0") == 1.0
    assert math.isnan(value_at(ODOM, "ranges.1"))
    assert value_at(ODOM, "ok") == 1.0


@pytest.mark.parametrize(
    ("path", "complaint"),
    [
        ("twist.twist.linear.q", "there is no 'q' in twist.twist.linear; the fields there are: x, y"),
        ("twist.twist", "is a message, not a number; its fields: linear"),
        ("ranges.5", "is an array of 2; use an index 0-1, e.g. ranges.0"),
        ("name", "is a str, not a number"),
        ("ok.value", "ok is a bool, not a message"),
    ],
)
def test_a_path_that_is_not_a_number_says_what_is_there(path: str, complaint: str) -> None:
    """Each wrong path names the fields or the kind of value found."""
    with pytest.raises(FieldError, match=complaint.replace("(", r"\(").replace(")", r"\)")):
        value_at(ODOM, path)


@pytest.mark.parametrize(
    ("msg_type", "path", "unit"),
    [
        ("geometry_msgs/msg/Twist", "linear.x", "m/s"),
        ("nav_msgs/msg/Odometry", "twist.twist.angular.z", "rad/s"),
        ("nav_msgs/msg/Odometry", "pose.pose.position.y", "m"),
        ("sensor_msgs/msg/Imu", "linear_acceleration.x", "m/s²"),
        ("geometry_msgs/msg/AccelStamped", "accel.linear.x", "m/s²"),
        ("turtlesim/Pose", "x", "m"),
        ("geometry_msgs/msg/Pose2D", "y", "m"),
        ("turtlesim/msg/Pose", "theta", "rad"),
        ("sensor_msgs/msg/LaserScan", "ranges.0", "m"),
        ("std_msgs/msg/Float64", "data", ""),
    ],
)
def test_units_come_from_the_field_and_type(msg_type: str, path: str, unit: str) -> None:
    """SI units where REP 103 and the type tell them; none where they do not."""
    assert unit_of(msg_type, path) == unit


def test_figures_skip_gaps() -> None:
    """min / max / mean / last over the finite samples; the count includes gaps."""
    line = Series("/x", "data", "", [0.0, 1.0, 2.0, 3.0], [1.0, math.nan, 3.0, 2.0])
    found = stats(line)
    assert (found.count, found.min, found.max, found.mean, found.last) == (4, 1.0, 3.0, 2.0, 2.0)
    assert stats(Series("/x", "data", "")).min is None


def test_the_chart_draws_each_series_in_its_colour_at_its_value() -> None:
    """Two constant series: the first's colour at its height, the second's at its own, higher up."""
    low = Series("/a", "v", "m/s", [0.5 * i for i in range(11)], [0.0] * 11)
    high = Series("/b", "v", "m/s", [0.5 * i for i in range(11)], [1.0] * 11)
    image = draw_chart([low, high], 5.0, 800, 400)
    # Across a few columns: the second series is dashed.
    rows = {(x, y): image.getpixel((x, y)) for x in range(580, 620) for y in range(image.height)}
    low_rows = [y for (x, y), c in rows.items() if c == SERIES_COLOURS[0] and x > 560]
    high_rows = [y for (x, y), c in rows.items() if c == SERIES_COLOURS[1]]
    assert low_rows
    assert high_rows
    assert max(high_rows) < min(low_rows)


def test_a_long_series_is_drawn_through_each_columns_min_and_max() -> None:
    """60,000 samples of a fast sine still reach the top and bottom of their range."""
    times = [i / 1000 for i in range(60_000)]
    line = Series("/fast", "data", "", times, [math.sin(t * 200) for t in times])
    image = draw_chart([line], 60.0, 800, 400)
    coloured = [y for y in range(image.height) for x in (400,) if image.getpixel((x, y)) == SERIES_COLOURS[0]]
    assert max(coloured) - min(coloured) > 250


def test_coinciding_series_both_show() -> None:
    """Two series with the same values: the second is dashed, so the first shows through its gaps."""
    times = [0.1 * i for i in range(51)]
    first = Series("/cmd_vel", "linear.x", "m/s", times, [0.5] * 51)
    second = Series("/odom", "twist.twist.linear.x", "m/s", times, [0.5] * 51)
    image = draw_chart([first, second], 5.0, 800, 400)
    seen = {image.getpixel((x, y)) for x in range(200, 600) for y in range(image.height)}
    assert SERIES_COLOURS[0] in seen
    assert SERIES_COLOURS[1] in seen


def test_each_unit_has_its_own_panel_and_scale() -> None:
    """m/s and rad/s: two panels, one above the other, each spanning its own range and named by its unit."""
    times = [0.1 * i for i in range(51)]
    speed = Series("/cmd_vel", "linear.x", "m/s", times, [0.2] * 51)
    turn = Series("/cmd_vel", "angular.z", "rad/s", times, [3.0 + 0.01 * i for i in range(51)])
    image = draw_chart([speed, turn], 5.0, 800, 400)
    rows_of = {
        colour: [y for x in range(300, 500) for y in range(image.height) if image.getpixel((x, y)) == colour]
        for colour in SERIES_COLOURS[:2]
    }
    speed_rows, turn_rows = rows_of[SERIES_COLOURS[0]], rows_of[SERIES_COLOURS[1]]
    assert speed_rows
    assert turn_rows
    # The rad/s series is in the lower panel, although its values are larger.
    assert max(speed_rows) < min(turn_rows)
    # Its own scale: 0.5 rad/s of rise spans a good part of its panel, not a sliver of a shared axis.
    assert max(turn_rows) - min(turn_rows) > 40
