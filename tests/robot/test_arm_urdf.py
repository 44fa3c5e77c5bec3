"""Robot descriptions read safely (robot/arm/urdf.py): what a URDF says, and hostile ones refused in words."""

from __future__ import annotations

import pytest

from rosbridge_mcp_server.robot.arm.controllers import parse_controllers, parse_srdf
from rosbridge_mcp_server.robot.arm.urdf import MAX_JOINTS, UrdfError, parse_urdf


def joint(name: str, kind: str, parent: str, child: str, extra: str = "") -> str:
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>{extra}</joint>'
    )


def robot(links: list[str], joints: list[str], head: str = "") -> str:
    body = "".join(f'<link name="{link}"/>' for link in links) + "".join(joints)
    return f'{head}<robot name="r">{body}</robot>'


LIMIT = '<limit lower="-1.5" upper="1.5" velocity="2.0" effort="10"/>'
TWO = robot(
    ["base", "upper", "fore", "tool0", "finger"],
    [
        joint("j1", "revolute", "base", "upper", f'<origin xyz="0 0 0.1"/><axis xyz="0 0 2"/>{LIMIT}'),
        joint("j2", "prismatic", "upper", "fore", '<limit lower="0" upper="0.2" velocity="0.1"/>'),
        joint("tool_joint", "fixed", "fore", "tool0"),
        joint("f", "prismatic", "tool0", "finger", '<limit upper="0.04"/><mimic joint="j2" multiplier="2"/>'),
    ],
)


def test_a_description_gives_joints_limits_axes_and_the_tree() -> None:
    """Joint types, limits, a normalised axis, mimic, the root, the chain and the end effector are read."""
    parsed = parse_urdf(TWO)
    j1 = parsed.joint("j1")
    assert j1 is not None
    assert (j1.type, j1.axis, j1.origin.xyz) == ("revolute", (0.0, 0.0, 1.0), (0.0, 0.0, 0.1))
    assert (j1.limits.lower, j1.limits.upper, j1.limits.velocity) == (-1.5, 1.5, 2.0)
    assert parsed.root == "base"
    assert [j.name for j in parsed.chain("base", "tool0")] == ["j1", "j2", "tool_joint"]
    assert [j.name for j in parsed.movable_joints] == ["j1", "j2"]
    assert parsed.end_effectors() == ("tool0",)
    finger = parsed.joint("f")
    assert finger is not None
    assert finger.mimic is not None
    assert finger.mimic.multiplier == 2.0


def _refusal(text: str | bytes) -> str:
    with pytest.raises(UrdfError) as caught:
        parse_urdf(text)
    return str(caught.value)


def test_an_entity_bomb_is_refused_before_any_entity_expands() -> None:
    """A billion-laughs DTD is refused for having a DTD, before any entity expands (the test's own timeout
    bounds it: expanded, the name would be 10^9 characters)."""
    bomb = '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa">'
    bomb += "".join(f'<!ENTITY a{i} "{"&a;" * 10 if i == 0 else f"&a{i - 1};" * 10}">' for i in range(9))
    bomb += ']><robot name="&a8;"><link name="l"/></robot>'
    assert "DTD" in _refusal(bomb)


def test_an_external_entity_is_refused() -> None:
    """An external entity (a file on the server's disk) is never read."""
    text = '<!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]><robot name="&x;"><link name="l"/></robot>'
    assert "DTD" in _refusal(text)


def test_a_huge_description_is_refused_by_its_size() -> None:
    """More than 2 MB is refused before it is parsed, naming the size and the limit."""
    huge = robot(["l"], []).replace("</robot>", "<!--" + "x" * 2_100_000 + "--></robot>")
    assert "at most 2,000,000" in _refusal(huge)


def test_deep_nesting_is_refused() -> None:
    """Elements nested thousands deep are refused at the nesting bound, not followed."""
    deep = "<robot name='r'><link name='l'>" + "<a>" * 5000 + "</a>" * 5000 + "</link></robot>"
    assert "nests elements deeper" in _refusal(deep)


def test_too_many_joints_are_refused() -> None:
    """A description with more joints than the bound is refused, naming the count."""
    links = [f"l{i}" for i in range(MAX_JOINTS + 2)]
    joints = [joint(f"j{i}", "fixed", f"l{i}", f"l{i + 1}") for i in range(MAX_JOINTS + 1)]
    assert f"at most {MAX_JOINTS} joints" in _refusal(robot(links, joints))


@pytest.mark.parametrize(
    ("joints", "words"),
    [
        ([joint("a", "fixed", "x", "y"), joint("b", "fixed", "y", "x")], "cycle"),
        ([joint("a", "fixed", "x", "y"), joint("b", "fixed", "z", "y")], "child of two joints"),
        ([joint("a", "fixed", "x", "y")], "2 root links"),
        ([joint("a", "revolute", "x", "nowhere", LIMIT)], "not in the description"),
        ([joint("a", "revolute", "x", "y", '<limit lower="nan" upper="1" velocity="1"/>')], "not a finite"),
        ([joint("a", "revolute", "x", "y", '<limit lower="0" upper="inf" velocity="1"/>')], "not a finite"),
        ([joint("a", "revolute", "x", "y", '<limit lower="2" upper="1" velocity="1"/>')], "above upper"),
        ([joint("a", "revolute", "x", "y")], "has no <limit>"),
        ([joint("a", "revolute", "x", "y", f'<axis xyz="0 0 0"/>{LIMIT}')], "zero length"),
        ([joint("a", "hinge", "x", "y")], "a URDF joint is one of"),
        ([joint("a", "revolute", "x", "y", f'{LIMIT}<mimic joint="a"/>')], "not another joint"),
    ],
)
def test_a_description_that_is_not_a_tree_or_has_bad_numbers_is_refused_in_words(
    joints: list[str], words: str
) -> None:
    """Cycles, two parents or roots, unknown links, NaN/inf/inverted limits, zero axes: refused in words."""
    assert words in _refusal(robot(["x", "y", "z"], joints))


def test_a_cycle_among_links_below_the_root_is_named() -> None:
    """Links on a cycle of their own (each with one parent) are named, not looped over."""
    joints = [joint("a", "fixed", "x", "y"), joint("b", "fixed", "z", "w"), joint("c", "fixed", "w", "z")]
    assert "sit on a cycle" in _refusal(robot(["x", "y", "z", "w"], joints))


def test_a_name_with_a_direction_override_or_a_control_character_is_refused() -> None:
    """A right-to-left override or a newline in a link name would show a model something else: refused."""
    assert "direction characters" in _refusal(robot(["base\u202eknil"], []))
    assert "direction characters" in _refusal(robot(["a&#10;b"], []))
    hidden = parse_controllers({"controller": [{"name": "arm\u200b_controller", "state": "active"}]})
    assert hidden == ()


def test_what_is_not_xml_is_refused_in_words() -> None:
    """Text that is not XML, and XML whose root is not <robot>, are named as such."""
    assert "not well-formed XML" in _refusal("<robot><link name='a'>")
    assert "no <robot>" in _refusal("<html/>")


def test_controllers_are_read_from_a_list_controllers_reply_and_bounded() -> None:
    """Name, state and claimed joints are read; junk items are left out; at most 64 items looked at."""
    reply = {
        "controller": [
            {
                "name": "arm_controller",
                "type": "joint_trajectory_controller/JointTrajectoryController",
                "state": "active",
                "claimed_interfaces": ["shoulder_pan_joint/position", "elbow_joint/position"],
            },
            {"name": 5},
            "junk",
        ]
        + [{"name": f"c{i}", "state": "inactive"} for i in range(100)]
    }
    controllers = parse_controllers(reply)
    assert len(controllers) == 62  # the first 64 items looked at, two of them junk
    assert controllers[0].active
    assert controllers[0].joints == ("shoulder_pan_joint", "elbow_joint")


def test_named_poses_come_from_the_srdf_and_a_dtd_there_is_refused() -> None:
    """group_state poses are read with their joints; an SRDF with a DTD is refused like a URDF."""
    srdf = (
        '<robot name="r"><group name="arm"><chain base_link="base" tip_link="tool0"/></group>'
        '<group_state name="home" group="arm"><joint name="j1" value="0.5"/></group_state></robot>'
    )
    semantic = parse_srdf(srdf)
    home = semantic.pose("home")
    assert home is not None
    assert home.positions == {"j1": 0.5}
    assert semantic.groups["arm"] == ("base→tool0",)
    with pytest.raises(UrdfError, match="DTD"):
        parse_srdf('<!DOCTYPE r [<!ENTITY a "b">]><robot name="r"/>')
    with pytest.raises(UrdfError, match="finite"):
        parse_srdf(
            '<robot><group_state name="h" group="a"><joint name="j" value="nan"/></group_state></robot>'
        )


def shaped(link: str, inner: str) -> str:
    return f'<robot name="r"><link name="{link}">{inner}</link></robot>'


@pytest.mark.parametrize(
    ("inner", "radius"),
    [
        ('<collision><geometry><cylinder radius="0.04" length="0.3"/></geometry></collision>', 0.04),
        ('<collision><geometry><sphere radius="0.07"/></geometry></collision>', 0.07),
        # A box: its longest side along the link, half the diagonal of the other two.
        ('<collision><geometry><box size="0.06 0.08 0.5"/></geometry></collision>', 0.05),
        # Collision wins over visual; the larger of several shapes.
        (
            '<visual><geometry><sphere radius="0.5"/></geometry></visual>'
            '<collision><geometry><sphere radius="0.02"/></geometry></collision>'
            '<collision><geometry><cylinder radius="0.03" length="1"/></geometry></collision>',
            0.03,
        ),
        ('<visual><geometry><cylinder radius="0.045" length="0.3"/></geometry></visual>', 0.045),
        # Unknown sizes: a mesh, a bad number, a huge radius, nothing.
        ('<collision><geometry><mesh filename="package://a/b.stl"/></geometry></collision>', None),
        ('<collision><geometry><cylinder radius="nan" length="1"/></geometry></collision>', None),
        ('<collision><geometry><sphere radius="-1"/></geometry></collision>', None),
        ('<collision><geometry><sphere radius="9"/></geometry></collision>', None),
        ('<collision><geometry><box size="0.1 0.1"/></geometry></collision>', None),
        ("", None),
    ],
)
def test_a_links_radius_comes_from_its_collision_else_visual_geometry(
    inner: str, radius: float | None
) -> None:
    radii = parse_urdf(shaped("body", inner)).radii
    assert radii.get("body") == (pytest.approx(radius) if radius is not None else None)
