"""Defence in depth at the bridge (issue 35, What 7): ``check --policy`` prints the rosbridge launch arguments
that hold the policy's allow lists at the bridge itself.

rosbridge reads each glob argument by cutting the brackets, splitting at commas and stripping spaces and
single quotes, then matches each name with ``fnmatch`` (rosbridge_websocket.py and rosapi's glob_helper,
2.x); :func:`as_rosbridge_reads` does the same to what ``check`` printed, so these tests hold the printed
arguments to what the bridge would then let through.
"""

from __future__ import annotations

import fnmatch
import io
import re
import shlex

import pytest

from rosbridge_mcp_server.cli.check import run_check
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.safety.bridge_globs import bridge_arguments
from rosbridge_mcp_server.sim import SimulatedRobot

POLICY = parse_policy(
    {
        "topics": {"allow": ["/turtle1/*", "/chatter"], "deny": ["/turtle1/pose"]},
        "services": {"allow": ["/turtle1/teleport_*"]},
        "actions": {"allow": ["/fibonacci"]},
        "parameters": {"allow": ["/turtlesim:background_*"]},
    },
    where="test.toml",
)


def as_rosbridge_reads(command: str) -> dict[str, list[str]]:
    """Each ``name:="[...]"`` argument of a launch command as rosbridge parses it."""
    read: dict[str, list[str]] = {}
    for word in shlex.split(command):
        match = re.fullmatch(r"(\w+):=(\[.*\])", word)
        if match:
            value = match.group(2)
            items = (element.strip().strip("'") for element in value[1:-1].split(","))
            read[match.group(1)] = [item for item in items if item]
    return read


def lets(globs: list[str], name: str) -> bool:
    return any(fnmatch.fnmatch(name, glob) for glob in globs)


def test_ros2_arguments_let_through_what_the_policy_allows_and_nothing_else() -> None:
    read = as_rosbridge_reads(bridge_arguments(POLICY, 2).launch(2))
    assert lets(read["topics_glob"], "/turtle1/cmd_vel")
    assert lets(read["topics_glob"], "/chatter")
    for refused in ("/cmd_vel", "/tf", "/initialpose", "/turtle2/cmd_vel"):
        assert not lets(read["topics_glob"], refused)
    for allowed in (
        "/turtle1/teleport_absolute",
        "/rosapi/topics",
        "/rosapi/get_param",
        "/turtlesim/get_parameters",
        "/turtlesim/list_parameters",
        "/turtlesim/set_parameters",
        "/fibonacci/_action/send_goal",
    ):
        assert lets(read["services_glob"], allowed), allowed
    for refused in ("/reset", "/clear", "/controller_server/set_parameters", "/spawn"):
        assert not lets(read["services_glob"], refused), refused
    assert read["params_glob"] == ["background_*"]


def test_ros1_arguments_carry_the_allowed_actions_topics() -> None:
    read = as_rosbridge_reads(bridge_arguments(POLICY, 1).launch(1))
    assert lets(read["topics_glob"], "/fibonacci/goal")
    assert lets(read["topics_glob"], "/fibonacci/cancel")
    assert not lets(read["topics_glob"], "/move_base/goal")
    assert read["params_glob"] == ["/turtlesim:background_*"]
    assert bridge_arguments(POLICY, 1).launch(1).startswith("roslaunch rosbridge_server")


def test_an_empty_allow_list_allows_nothing_at_the_bridge_too() -> None:
    """On rosbridge 2.x ``[]`` means "no filtering"; an empty allow list must still allow nothing."""
    policy = parse_policy({"topics": {"allow": []}}, where="test.toml")
    read = as_rosbridge_reads(bridge_arguments(policy, 2).launch(2))
    assert read["topics_glob"]
    assert not any(lets(read["topics_glob"], name) for name in ("/", "/cmd_vel", "/a/b", "/rosout"))


def test_rosbridge_42_splits_publishing_from_subscribing() -> None:
    command = bridge_arguments(POLICY, 2).launch(2, split_topics=True)
    read = as_rosbridge_reads(command)
    assert "topics_glob" not in read
    assert lets(read["topics_pub_glob"], "/turtle1/cmd_vel")


def test_a_policy_without_allow_lists_needs_no_arguments() -> None:
    policy = parse_policy({"topics": {"deny": ["/cmd_vel"]}, "confirm": "motion"}, where="test.toml")
    assert bridge_arguments(policy, 2).arguments == {}


def test_a_glob_rosbridge_cannot_read_is_said() -> None:
    policy = parse_policy({"topics": {"allow": ["/turtle[1,2]/*"]}}, where="test.toml")
    assert any("cannot be given to it" in note for note in bridge_arguments(policy, 2).notes)


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_check_with_a_policy_prints_the_launch_arguments(dialect: str) -> None:
    async with SimulatedRobot(port=0, dialect=dialect) as robot:
        with_policy, without = io.StringIO(), io.StringIO()
        assert await run_check(Config(url=robot.url, policy=POLICY), with_policy) == 0
        assert await run_check(Config(url=robot.url), without) == 0
    text = with_policy.getvalue()
    launch = "ros2 launch rosbridge_server" if dialect == "ros2" else "roslaunch rosbridge_server"
    [command] = [line.strip() for line in text.splitlines() if line.strip().startswith(launch)][:1]
    read = as_rosbridge_reads(command)
    assert set(read) == {"topics_glob", "services_glob", "params_glob"}
    assert "deny lists" in text
    assert "docs/deployment.md" in text
    assert "topics_glob" not in without.getvalue()
