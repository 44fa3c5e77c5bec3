"""Velocity commands are recognised in either line's spelling of their type, and nothing else is."""

from __future__ import annotations

import pytest

from rosbridge_mcp_server.robot.velocity import is_velocity_type, stamped


@pytest.mark.parametrize(
    ("type_name", "velocity", "is_stamped"),
    [
        ("geometry_msgs/msg/Twist", True, False),
        ("geometry_msgs/Twist", True, False),
        ("/geometry_msgs/msg/Twist", True, False),
        ("geometry_msgs/msg/TwistStamped", True, True),
        ("geometry_msgs/TwistStamped", True, True),
        ("geometry_msgs/msg/TwistWithCovariance", False, False),
        ("my_msgs/msg/TwistStamped", False, False),
        ("std_msgs/msg/String", False, False),
    ],
)
def test_a_velocity_type_is_known_in_either_spelling(
    type_name: str, velocity: bool, is_stamped: bool
) -> None:
    """Twist and TwistStamped as ROS 2 or ROS 1 spell them; a look-alike of another package is not one."""
    assert (is_velocity_type(type_name), stamped(type_name)) == (velocity, is_stamped)
