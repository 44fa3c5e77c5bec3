"""Forward kinematics (robot/arm/kinematics.py) against poses worked out by hand, and its speed."""

from __future__ import annotations

import math

import pytest

from rosbridge_mcp_server.robot.arm.kinematics import (
    Chain,
    MissingJointsError,
    compose,
    from_origin,
    inverse,
    link_poses,
    quaternion,
    rpy,
    translation,
)
from rosbridge_mcp_server.robot.arm.urdf import Origin, parse_urdf

LIMIT = '<limit lower="-3" upper="3" velocity="1"/>'


def _joint(name: str, parent: str, child: str, body: str, kind: str = "revolute") -> str:
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>{body}</joint>'
    )


PLANAR = (
    '<robot name="planar">'
    + "".join(f'<link name="{name}"/>' for name in ("base", "a", "b", "tool0", "finger"))
    + _joint("j1", "base", "a", f'<axis xyz="0 0 1"/>{LIMIT}')
    + _joint("j2", "a", "b", f'<origin xyz="1 0 0"/><axis xyz="0 0 1"/>{LIMIT}')
    + _joint("tool", "b", "tool0", '<origin xyz="0.5 0 0" rpy="0 0 1.5707963267948966"/>', "fixed")
    + _joint(
        "finger",
        "tool0",
        "finger",
        '<axis xyz="1 0 0"/><limit lower="0" upper="1" velocity="1"/><mimic joint="j2" multiplier="0.1"/>',
        "prismatic",
    )
    + "</robot>"
)


def test_a_two_link_planar_arm_puts_the_tool_where_trigonometry_does() -> None:
    """Tool at (cos a + 0.5 cos(a+b), sin a + 0.5 sin(a+b)), turned a+b+90°."""
    chain = Chain(parse_urdf(PLANAR), "base", "tool0")
    a, b = 0.3, -1.1
    pose = chain.tip_pose({"j1": a, "j2": b})
    x, y, z = translation(pose)
    assert x == pytest.approx(math.cos(a) + 0.5 * math.cos(a + b))
    assert y == pytest.approx(math.sin(a) + 0.5 * math.sin(a + b))
    assert z == pytest.approx(0.0)
    assert rpy(pose)[2] == pytest.approx(a + b + math.pi / 2)
    assert [link for link, _ in chain.poses({"j1": a, "j2": b})] == ["a", "b", "tool0"]


def test_a_mimic_joint_follows_its_leader() -> None:
    """The finger slides 0.1 × j2 along the tool's x (which points along the arm's +y at zero)."""
    poses = link_poses(parse_urdf(PLANAR), {"j1": 0.0, "j2": 0.5})
    finger, tool = translation(poses["finger"]), translation(poses["tool0"])
    along = (math.cos(0.5 + math.pi / 2), math.sin(0.5 + math.pi / 2))
    assert finger[0] - tool[0] == pytest.approx(0.05 * along[0])
    assert finger[1] - tool[1] == pytest.approx(0.05 * along[1])


def test_a_missing_joint_position_is_named() -> None:
    """Without j2's position, the error names j2 (and the pose is not guessed)."""
    with pytest.raises(MissingJointsError, match="j2") as caught:
        Chain(parse_urdf(PLANAR), "base", "tool0").tip_pose({"j1": 0.0})
    assert caught.value.missing == ("j2",)


def test_rotations_round_trip_through_rpy_quaternion_and_inverse() -> None:
    """An origin's rpy comes back from its transform; t ∘ t⁻¹ is the identity; the quaternion is unit."""
    t = from_origin(Origin((0.1, -0.2, 0.3), (0.4, -0.5, 0.6)))
    assert rpy(t) == pytest.approx((0.4, -0.5, 0.6))
    assert compose(t, inverse(t)) == pytest.approx((1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0), abs=1e-12)
    assert math.fsum(c * c for c in quaternion(t)) == pytest.approx(1.0)


def test_a_general_axis_matches_the_coordinate_axis_fast_path() -> None:
    """An axis spelled unnormalised gives the same pose; a slanted axis turns x as Rodrigues says."""
    spelled = PLANAR.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 3"/>', 1)
    a = Chain(parse_urdf(PLANAR), "base", "tool0").tip_pose({"j1": 0.7, "j2": 0.2})
    b = Chain(parse_urdf(spelled), "base", "tool0").tip_pose({"j1": 0.7, "j2": 0.2})
    assert a == pytest.approx(b)
    tilted = PLANAR.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 1 1"/>', 1)
    pose = Chain(parse_urdf(tilted), "base", "tool0").tip_pose({"j1": math.pi, "j2": 0.0})
    assert translation(pose) == pytest.approx((-1.5, 0.0, 0.0))  # x turned half a turn about (0, 1, 1)/√2


def seven_joint_urdf() -> str:
    """A 7-joint arm with alternating axes and rotated origins (the worst case for the fast paths)."""
    links = "".join(f'<link name="l{i}"/>' for i in range(8))
    joints = "".join(
        _joint(
            f"j{i}",
            f"l{i}",
            f"l{i + 1}",
            f'<origin xyz="0 0.05 0.2" rpy="0.1 0 0"/><axis xyz="{axis}"/>{LIMIT}',
        )
        for i, axis in enumerate(["0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1", "0 1 0", "1 0 0"])
    )
    return f'<robot name="seven">{links}{joints}</robot>'
