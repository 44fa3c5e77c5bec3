"""The frame tree: look-ups over several hops in either direction, freshness, and unknown frames."""

from __future__ import annotations

import math
from typing import Any

import pytest

from rosbridge_mcp_server.robot.transforms import FrameTree, TransformError


def stamped(
    parent: str, child: str, xyz: tuple[float, float, float], yaw_deg: float = 0.0, sec: int = 0
) -> dict[str, Any]:
    half = math.radians(yaw_deg) / 2
    return {
        "header": {"frame_id": parent, "stamp": {"sec": sec, "nanosec": 0}},
        "child_frame_id": child,
        "transform": {
            "translation": {"x": xyz[0], "y": xyz[1], "z": xyz[2]},
            "rotation": {"x": 0.0, "y": 0.0, "z": math.sin(half), "w": math.cos(half)},
        },
    }


def robot_tree() -> FrameTree:
    """world → odom (static, 1 m in x) → base_link (2 m in y, turned 90°) → laser (0.1 m ahead)."""
    tree = FrameTree()
    tree.add_message({"transforms": [stamped("world", "odom", (1.0, 0.0, 0.0))]}, static=True, received=1.0)
    tree.add_message(
        {"transforms": [stamped("odom", "base_link", (0.0, 2.0, 0.0), 90.0, sec=50)]},
        static=False,
        received=7.0,
    )
    tree.add(stamped("/base_link", "laser", (0.1, 0.0, 0.2)), static=True, received=2.0)
    return tree


def test_a_look_up_down_several_hops_composes_the_links() -> None:
    """world ← laser: the laser 0.1 m ahead of a base turned 90° sits at (1, 2.1, 0.2), yawed 90°."""
    found = robot_tree().lookup("world", "laser")
    assert found.transform.translation == pytest.approx((1.0, 2.1, 0.2))
    assert found.transform.rpy_degrees() == pytest.approx((0.0, 0.0, 90.0))
    assert found.chain == ("world", "odom", "base_link", "laser")
    assert (found.newest_received, found.newest_stamp, found.static_only) == (7.0, 50.0, False)


def test_the_reverse_look_up_is_the_inverse() -> None:
    """laser ← world maps the world origin into the laser frame: the exact inverse of world ← laser."""
    tree = robot_tree()
    forward = tree.lookup("world", "laser").transform
    backward = tree.lookup("laser", "world")
    identity = forward.compose(backward.transform)
    assert identity.translation == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    assert identity.rpy_degrees() == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert backward.chain == ("laser", "base_link", "odom", "world")


def test_a_look_up_across_branches_goes_through_the_common_parent() -> None:
    """Two sensors on one base: camera ← laser goes up to base_link and down again."""
    tree = robot_tree()
    tree.add(stamped("base_link", "camera", (0.0, 0.0, 0.5)), static=True, received=3.0)
    found = tree.lookup("camera", "laser")
    assert found.chain == ("camera", "base_link", "laser")
    assert found.transform.translation == pytest.approx((0.1, 0.0, -0.3))
    assert found.static_only
    assert found.newest_received is None


def test_the_latest_dynamic_link_replaces_the_older_one() -> None:
    """A newer odom → base_link message moves the answer."""
    tree = robot_tree()
    tree.add(stamped("odom", "base_link", (5.0, 0.0, 0.0)), static=False, received=9.0)
    found = tree.lookup("odom", "base_link")
    assert found.transform.translation == pytest.approx((5.0, 0.0, 0.0))
    assert found.newest_received == 9.0


def test_an_unknown_frame_lists_the_frames_seen() -> None:
    """A misspelt frame is an error naming it and every frame heard of."""
    with pytest.raises(
        TransformError, match=r"'base_lnk' has not been seen.*Frames seen: base_link, laser, odom, world"
    ):
        robot_tree().lookup("world", "base_lnk")


def test_frames_in_separate_trees_are_not_connected() -> None:
    """Two trees with no link between them: the error says which roots they reach."""
    tree = robot_tree()
    tree.add(stamped("map", "marker", (0.0, 0.0, 0.0)), static=True, received=1.0)
    with pytest.raises(
        TransformError, match=r"not connected: 'marker' goes up to 'map' and 'laser' up to 'world'"
    ):
        tree.lookup("marker", "laser")


def test_malformed_transforms_are_ignored() -> None:
    """A transform without a rotation, or with a zero quaternion, is not taken."""
    tree = FrameTree()
    broken = stamped("a", "b", (0.0, 0.0, 0.0))
    del broken["transform"]["rotation"]
    zero = stamped("a", "c", (0.0, 0.0, 0.0))
    zero["transform"]["rotation"] = {"x": 0, "y": 0, "z": 0, "w": 0}
    assert tree.add_message({"transforms": [broken, zero]}, static=False, received=0.0) == 0
    assert tree.frames() == []
