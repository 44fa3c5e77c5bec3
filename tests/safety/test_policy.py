"""The policy file: every key optional, unknown keys a start-up error naming them, globs like rosbridge's."""

from __future__ import annotations

from pathlib import Path

import pytest

from rosbridge_mcp_server.config import ConfigError, load_config
from rosbridge_mcp_server.safety import NameRules, Policy, PolicyError, load_policy, parse_policy

FULL = """
read_only = false
confirm = "motion"
confirm_timeout = 45
[topics]
allow = ["/turtle1/*"]
deny = ["/rosout"]
[services]
deny = ["/rosapi/*"]
[actions]
allow = ["/fibonacci"]
[parameters]
allow = []
[velocity]
max_linear = 0.5
max_angular = 1
mode = "clamp"
[publish]
max_rate_hz = 20
max_duration = 30
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "policy.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_an_empty_file_allows_everything(tmp_path: Path) -> None:
    """No keys at all is the same as no policy: nothing restricted, nobody asked."""
    policy = load_policy(write(tmp_path, ""))
    assert not policy.restricts
    assert policy.confirm == "never"
    assert policy.topics.allow is None


def test_every_key_of_the_sample_is_read(tmp_path: Path) -> None:
    """The documented sample loads into the values it spells."""
    policy = load_policy(write(tmp_path, FULL))
    assert policy.confirm == "motion"
    assert policy.confirm_timeout == 45.0
    assert policy.topics == NameRules(allow=("/turtle1/*",), deny=("/rosout",))
    assert policy.services == NameRules(allow=None, deny=("/rosapi/*",))
    assert policy.parameters.allow == ()
    assert policy.velocity.max_linear == 0.5
    assert policy.velocity.max_angular == 1.0
    assert policy.velocity.mode == "clamp"
    assert policy.publish.max_rate_hz == 20.0
    assert policy.publish.max_duration == 30.0
    assert policy.restricts


@pytest.mark.parametrize(
    ("text", "named", "suggested"),
    [
        ("confrim = 'always'", "'confrim'", "'confirm'"),
        ("[velocity]\nmax_linaer = 0.5", "[velocity] 'max_linaer'", "'max_linear'"),
        ("[topic]\nallow = ['/a']", "'topic'", "'topics'"),
        ("[topics]\nalow = ['/a']", "[topics] 'alow'", "'allow'"),
        ("[publish]\nmax_rate = 5", "[publish] 'max_rate'", "'max_rate_hz'"),
    ],
)
def test_a_misspelt_key_is_an_error_naming_it_with_a_suggestion(
    tmp_path: Path, text: str, named: str, suggested: str
) -> None:
    """A key the loader does not know would leave the robot unprotected, so it stops the start."""
    with pytest.raises(PolicyError) as caught:
        load_policy(write(tmp_path, text))
    message = str(caught.value)
    assert named in message
    assert f"did you mean {suggested}" in message
    assert "\n" not in message


def test_a_policy_error_is_a_configuration_error(tmp_path: Path) -> None:
    """Through the configuration it is a ConfigError, which the CLI's bad-configuration path catches."""
    with pytest.raises(ConfigError, match=r"unknown key 'nonsense_key_entirely'"):
        load_config({"ROSBRIDGE_MCP_POLICY": str(write(tmp_path, "nonsense_key_entirely = 1"))})


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("confirm = 'sometimes'", "confirm must be one of"),
        ("read_only = 'yes'", "read_only must be true or false"),
        ("[velocity]\nmax_linear = -1", "max_linear must be a number of m/s"),
        ("[velocity]\nmax_linear = 'fast'", "max_linear must be a number"),
        ("[velocity]\nmode = 'slow'", "mode must be 'refuse' or 'clamp'"),
        ("[topics]\nallow = '/a'", "allow must be a list"),
        ("[publish]\nmax_rate_hz = 0", "max_rate_hz must be more than 0"),
        ("confirm_timeout = 0", "confirm_timeout must be more than 0"),
        ("confirm_timeout = 'long'", "confirm_timeout must be a number of seconds"),
        ("topics = 3", "topics must be a table"),
        ("read_only = tru", "not valid TOML"),
        ("approvals = 'anyone'", "approvals must be one of 'client', 'console'"),
        ("[services]\nmotion = '/arm/move'", r"\[services\] motion must be a list"),
        ("[actions]\nmotion = ['/a']", r"unknown key \[actions\] 'motion'"),
    ],
)
def test_a_bad_value_is_an_error_saying_what_fits(tmp_path: Path, text: str, fragment: str) -> None:
    """Wrong types and values are one line naming the key and what it takes."""
    with pytest.raises(PolicyError, match=fragment):
        load_policy(write(tmp_path, text))


def test_a_missing_file_is_an_error_naming_it(tmp_path: Path) -> None:
    """A policy path that does not exist does not silently mean "no policy"."""
    with pytest.raises(PolicyError, match=r"does not exist"):
        load_policy(tmp_path / "nope.toml")


@pytest.mark.parametrize(
    ("name", "allowed"),
    [
        ("/turtle1/cmd_vel", True),
        ("/turtle1/deep/er/topic", True),  # * crosses "/", as in rosbridge's topics_glob
        ("/turtle2/cmd_vel", False),
        ("/Turtle1/cmd_vel", False),  # ROS names are case-sensitive
        ("/turtle1/secret", False),  # denied although allowed: deny wins
    ],
)
def test_allow_and_deny_globs_follow_fnmatch_and_deny_wins(name: str, allowed: bool) -> None:
    """Shell-style globs, * crossing slashes, case-sensitive, deny over allow."""
    rules = NameRules(allow=("/turtle1/*",), deny=("/turtle1/secret",))
    assert (rules.refusal(name, "topics") is None) is allowed


def test_a_refusal_names_the_rule_that_refused() -> None:
    """The refusal text says which list and which glob decided."""
    rules = NameRules(allow=("/turtle1/*",), deny=("/rosout",))
    assert rules.refusal("/rosout", "topics") == "[topics] deny '/rosout' matches /rosout"
    assert "[topics] allow lists only '/turtle1/*'" in (rules.refusal("/other", "topics") or "")


def test_describe_lists_what_the_policy_restricts() -> None:
    """``check`` shows each restriction in a line a person can read."""
    policy = parse_policy(
        {"confirm": "always", "topics": {"deny": ["/rosout"]}, "velocity": {"max_linear": 0.5}},
        where="robot.toml",
    )
    text = "\n".join(policy.describe())
    assert "robot.toml" in text
    assert "confirm = always" in text
    assert "[topics] allow everything; deny /rosout" in text
    assert "linear ≤ 0.5 m/s" in text
    assert "no restrictions" in Policy().describe()[0]
    assert "read_only" in "\n".join(Policy(read_only=True).describe())


def test_confirm_never_says_the_navigation_goals_are_still_asked() -> None:
    """Only ``[navigation] confirm = "motion"``: the top line does not say nobody is asked (seen on the ROS 1
    lab: the start-up log read "nobody is asked", then "[navigation] the person confirms each goal")."""
    text = "\n".join(parse_policy({"navigation": {"confirm": "motion"}}, where="p.toml").describe())
    assert "confirm = never: nobody is asked, except for the motion goals [navigation] confirms" in text
    assert "[navigation] the person confirms each goal" in text


def test_approvals_and_motion_services_are_read_and_described(tmp_path: Path) -> None:
    """approvals = "console" and [services] motion load, and check / the start-up log name them."""
    text = 'confirm = "motion"\napprovals = "console"\n[services]\nmotion = ["/arm/move_to"]\n'
    text += '[topics]\nmotion = ["/arm/command"]\n'
    policy = load_policy(write(tmp_path, text))
    assert policy.approvals == "console"
    assert policy.motion_services == ("/arm/move_to",)
    assert policy.motion_topics == ("/arm/command",)
    assert policy.services == NameRules()
    described = "\n".join(policy.describe())
    assert "approvals = console: only the person at the operator console confirms" in described
    assert "[services] motion: /arm/move_to" in described
    assert "[topics] motion: /arm/command" in described
    assert load_policy(write(tmp_path, "")).approvals == "client"


@pytest.mark.parametrize(
    ("name", "deny", "refused"),
    [
        ("/turtlesim", "/turtlesim/background_r", True),
        ("/turtlesim", "/turtlesim/*", True),
        ("/turtlesim", "/turtle*", True),
        ("/turtlesim", "/turtlesim", True),
        ("/turtlesim", "/turtlesimulator/x", False),
        ("/turtlesim", "/camera/*", False),
        ("/turtlesim/background_r", "/turtlesim/background_g", False),
    ],
)
def test_a_subtree_write_is_refused_when_a_deny_may_match_under_it(
    name: str, deny: str, refused: bool
) -> None:
    """A ROS 1 write replaces everything under its name, so a deny below it refuses it."""
    rules = NameRules(deny=(deny,))
    assert (rules.refusal(name, "parameters", subtree=True) is not None) is refused


NAVIGATION = """
[navigation]
robot_radius = 0.3
max_goal_distance = 12
confirm = "motion"
[navigation.allowed_zones]
lab = [[0, 0], [10, 0], [10, 10], [0, 10]]
[navigation.keep_out]
stairs = [[8, 8], [9, 8], [9, 9.5]]
[places]
dock = [1.0, 2.0, 90]
door = {x = 4, y = 5}
"""


def test_the_navigation_section_and_the_places_are_read(tmp_path: Path) -> None:
    path = tmp_path / "policy.toml"
    path.write_text(NAVIGATION, encoding="utf-8")
    policy = load_policy(path)
    nav = policy.navigation
    assert nav.robot_radius == 0.3
    assert nav.max_goal_distance == 12
    assert nav.confirm == "motion"
    assert nav.allowed_zones == (("lab", ((0, 0), (10, 0), (10, 10), (0, 10))),)
    assert nav.keep_out == (("stairs", ((8, 8), (9, 8), (9, 9.5))),)
    assert dict(policy.places) == {"dock": (1.0, 2.0, 90.0), "door": (4.0, 5.0, 0.0)}
    described = "\n".join(policy.describe())
    assert "[navigation] goals inside lab; none in stairs; at most 12 m away" in described
    assert "[places] dock, door" in described


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ('[navigation]\nconfirm = "always"', "[navigation] confirm must be 'never' or 'motion'"),
        ("[navigation]\nmax_goal_distance = -1", "[navigation] max_goal_distance must be a number of metres"),
        (
            "[navigation.keep_out]\nstairs = [[0, 0], [1, 1]]",
            "[navigation.keep_out] stairs must be a polygon",
        ),
        (
            '[navigation.allowed_zones]\nlab = [[0, 0], [1, "a"], [2, 2]]',
            "allowed_zones] lab must be a polygon",
        ),
        ("[navigation]\nmax_goal_distanse = 3", "did you mean 'max_goal_distance'?"),
        ('[places]\ndock = "here"', "[places] dock must be [x, y, yaw]"),
        ("[places]\ndock = {x = 1, z = 2}", "[places] dock must be [x, y, yaw]"),
    ],
)
def test_a_bad_navigation_value_is_an_error_saying_what_fits(text: str, fragment: str) -> None:
    import tomllib

    with pytest.raises(PolicyError) as raised:
        parse_policy(tomllib.loads(text), where="p.toml")
    assert fragment in str(raised.value)
