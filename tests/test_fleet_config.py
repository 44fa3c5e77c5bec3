"""Reading the robots of a fleet: --robot NAME=URL and the [robots.NAME] TOML file."""

from __future__ import annotations

from pathlib import Path

import pytest

from rosbridge_mcp_server.cli.demo import demo_settings
from rosbridge_mcp_server.config import Config, ConfigError
from rosbridge_mcp_server.config.fleet import load_fleet
from rosbridge_mcp_server.safety import parse_policy

BASE = Config(headers=(("Authorization", "Bearer base"),))


def test_no_robot_flags_is_one_robot_mode() -> None:
    """Neither flag: an empty fleet, and the server drives the robot the connection flags name."""
    assert load_fleet(BASE) == ()


def test_robot_flags_take_everything_but_the_url_from_the_command_line() -> None:
    """--robot NAME=URL keeps the base headers and policy; the order given is kept."""
    base = Config(policy=parse_policy({"read_only": True}))
    fleet = load_fleet(base, robots=["b=ws://10.0.0.2:9090", "a=ws://10.0.0.1:9090"])
    assert [name for name, _ in fleet] == ["b", "a"]
    assert fleet[1][1].url == "ws://10.0.0.1:9090"
    assert fleet[1][1].policy.read_only


def test_a_fleet_file_gives_each_robot_its_url_headers_and_policy(tmp_path: Path) -> None:
    """Paths are relative to the file; read_only and headers apply to their robot only."""
    (tmp_path / "arm.toml").write_text("[velocity]\nmax_linear = 0.1\n")
    path = tmp_path / "fleet.toml"
    path.write_text(
        '[robots.base]\nurl = "ws://10.0.0.5:9090"\nheaders = { Authorization = "Bearer b" }\n\n'
        '[robots.arm]\nurl = "ws://10.0.0.6:9090"\npolicy = "arm.toml"\n\n'
        '[robots.cam]\nurl = "ws://10.0.0.7:9090"\nread_only = true\n'
    )
    fleet = dict(load_fleet(BASE, robots_file=str(path)))
    assert fleet["base"].headers == (("Authorization", "Bearer b"),)
    assert fleet["arm"].headers == BASE.headers
    assert fleet["arm"].policy.velocity.max_linear == 0.1
    assert not fleet["base"].policy.read_only
    assert fleet["cam"].policy.read_only


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ('[robots.a]\nurl = "http://x"\n', "ws://"),
        ("[robots.a]\n", "url"),
        ('[robots.a]\nurl = "ws://x:1"\ncolour = "red"\n', "unknown key 'colour'"),
        ('[robots."1st"]\nurl = "ws://x:1"\n', "must start with a letter"),
        ('[robots.a]\nurl = "ws://x:1"\npolicy = "missing.toml"\n', "does not exist"),
        ("robots = 3\n", "no robots"),
        ('[robot.a]\nurl = "ws://x:1"\n', "unknown key 'robot'"),
        ('[robots.a]\nurl = "ws://x:1"\nnamespace = "robot 2"\n', "not a ROS namespace"),
        ('[robots.a]\nurl = "ws://x:1"\nnamespace = 2\n', "namespace must be a string"),
    ],
)
def test_fleet_file_mistakes_are_named(tmp_path: Path, text: str, problem: str) -> None:
    """Each mistake is one line naming the robot's table and the key."""
    path = tmp_path / "fleet.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=problem):
        load_fleet(BASE, robots_file=str(path))


def test_a_robot_named_twice_or_without_url_is_refused(tmp_path: Path) -> None:
    """--robot needs NAME=URL, each name once (the file's names included)."""
    with pytest.raises(ConfigError, match="NAME=URL"):
        load_fleet(BASE, robots=["base"])
    with pytest.raises(ConfigError, match="named twice"):
        load_fleet(BASE, robots=["a=ws://x:1", "a=ws://y:1"])
    fleet = load_fleet(BASE, robots=["a=ws://x:1"])
    with pytest.raises(ConfigError, match="--demo runs one simulated robot"):
        demo_settings(True, fleet=fleet)


def test_a_robot_of_the_fleet_may_carry_its_namespace_on_a_shared_bridge(tmp_path: Path) -> None:
    """Two robots on one bridge: each entry's namespace (made absolute); an entry without one finds it."""
    path = tmp_path / "fleet.toml"
    path.write_text(
        '[robots.one]\nurl = "ws://10.0.0.5:9090"\nnamespace = "robot1"\n\n'
        '[robots.two]\nurl = "ws://10.0.0.5:9090"\nnamespace = "/robot2/"\n\n'
        '[robots.root]\nurl = "ws://10.0.0.5:9090"\nnamespace = ""\n\n'
        '[robots.any]\nurl = "ws://10.0.0.6:9090"\n'
    )
    fleet = dict(load_fleet(BASE, robots_file=str(path)))
    assert [fleet[name].namespace for name in ("one", "two", "root", "any")] == [
        "/robot1",
        "/robot2",
        "",
        None,
    ]
