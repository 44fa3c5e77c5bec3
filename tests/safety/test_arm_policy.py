"""The policy's ``[arm]`` section: read, described, and every bad value an error saying what fits."""

from __future__ import annotations

import tomllib

import pytest

from rosbridge_mcp_server.safety.arm_rules import DEFAULT_SPEED_SCALE, ArmRules
from rosbridge_mcp_server.safety.policy import Policy, PolicyError, parse_policy

ARM = """
[arm]
speed_scale = 0.5
frame = "/base_link"
margin = 0.05
confirm = "motion"
max_gripper_effort = 20
[arm.workspace]
table = [[0.1, -0.5, 0.0], [0.8, 0.5, 1.0]]
[arm.keep_out]
person = [[-1, 0.6, 0], [1, 2, 2]]
"""


def test_the_arm_section_is_read_and_described() -> None:
    """Every key of [arm] lands in ArmRules, and check's description names the boxes and the scale."""
    policy = parse_policy(tomllib.loads(ARM), where="p.toml")
    arm = policy.arm
    assert arm.speed_scale == 0.5
    assert arm.frame == "base_link"
    assert arm.margin == 0.05
    assert arm.confirm == "motion"
    assert arm.max_gripper_effort == 20
    assert arm.workspace == (("table", (0.1, -0.5, 0.0), (0.8, 0.5, 1.0)),)
    assert arm.keep_out == (("person", (-1.0, 0.6, 0.0), (1.0, 2.0, 2.0)),)
    assert arm.configured
    described = "\n".join(policy.describe())
    assert "[arm] every joint within its URDF limits, at most 0.5 of its URDF speed" in described
    assert "the tool inside table; no link in person" in described


def test_without_an_arm_section_the_urdf_limits_hold_at_a_quarter_of_their_speed() -> None:
    """No [arm]: the default scale, no boxes, nobody asked; the policy restricts nothing more than none."""
    policy = parse_policy({}, where="p.toml")
    assert policy.arm == ArmRules()
    assert policy.arm.speed_scale == DEFAULT_SPEED_SCALE == 0.25
    assert not policy.arm.configured
    assert policy == Policy(source="p.toml")


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("[arm]\nspeed_scale = 0", "[arm] speed_scale must be more than 0 and at most 1"),
        ("[arm]\nspeed_scale = 1.5", "[arm] speed_scale must be more than 0 and at most 1"),
        ('[arm]\nspeed_scale = "fast"', "[arm] speed_scale must be a finite number"),
        ("[arm]\nspeed_scale = nan", "[arm] speed_scale must be a finite number"),
        ("[arm]\nmargin = -0.1", "[arm] margin must be a number of metres"),
        ('[arm]\nconfirm = "always"', "[arm] confirm must be 'never' or 'motion'"),
        ("[arm]\nmax_gripper_effort = 0", "[arm] max_gripper_effort must be more than 0 N"),
        ('[arm]\nframe = ""', "[arm] frame must be a link name"),
        ("[arm]\nspeed_scael = 0.1", "did you mean 'speed_scale'?"),
        ("[arm.workspace]\nt = [[0, 0, 0], [1, 1]]", "[arm.workspace] t must be two corners"),
        ("[arm.keep_out]\np = [[1, 0, 0], [0, 1, 1]]", "the first smaller on every axis"),
        ('[arm]\nkeep_out = "everywhere"', "[arm] keep_out must be a table of named boxes"),
        ("arm = 3", "arm must be a table ([arm])"),
    ],
)
def test_a_bad_arm_value_is_an_error_saying_what_fits(text: str, fragment: str) -> None:
    """A misspelt or out-of-range [arm] value stops the start with a sentence naming it."""
    with pytest.raises(PolicyError) as raised:
        parse_policy(tomllib.loads(text), where="p.toml")
    assert fragment in str(raised.value)
    assert str(raised.value).startswith("p.toml: ")
