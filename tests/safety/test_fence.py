"""The guard's side of fence writes (pure: the MCP attacks are in ``mcp/test_mcp_fence_writes.py``)."""

from __future__ import annotations

from typing import Any

import pytest

from rosbridge_mcp_server.errors import PolicyRefusal
from rosbridge_mcp_server.robot.approval import Act, Answer, AskPerson
from rosbridge_mcp_server.robot.effects import topic_effects
from rosbridge_mcp_server.safety import PolicyGuard, parse_policy
from rosbridge_mcp_server.safety.policy import PolicyError

POSE = "geometry_msgs/msg/PoseWithCovarianceStamped"
ZONE = {"keep_out": {"pit": [[0, 0], [1, 0], [1, 1]]}}


class Person(AskPerson):
    def __init__(self) -> None:
        self.questions: list[str] = []

    async def __call__(self, question: str) -> Answer:
        self.questions.append(question)
        return "accept"


def relocalise(topic: str = "/initialpose") -> Act:
    return Act("publish_topic", "topic", topic, POSE, {}, effects=topic_effects(topic, POSE))


def guard(**policy: Any) -> PolicyGuard:
    return PolicyGuard(parse_policy(policy, where="test.toml"))


async def test_a_fence_write_the_policy_allows_is_still_asked_under_navigation_confirm() -> None:
    person = Person()
    allowed = guard(navigation={**ZONE, "confirm": "motion", "allow_fence_writes": ["/init*"]})
    await allowed.approve(relocalise(), person)
    assert len(person.questions) == 1
    with pytest.raises(PolicyRefusal, match="allow_fence_writes"):
        await allowed.approve(relocalise("/robot1/initialpose"), person)


async def test_without_zones_or_limits_a_fence_write_is_not_refused_but_confirm_motion_asks() -> None:
    person = Person()
    await guard().approve(relocalise(), person)
    assert person.questions == []
    await guard(confirm="motion").approve(relocalise(), person)
    assert "a change of what the safety fence and localisation read" in person.questions[0]


async def test_max_goal_distance_alone_is_a_fence_too() -> None:
    with pytest.raises(PolicyRefusal, match="fence"):
        await guard(navigation={"max_goal_distance": 3}).approve(relocalise(), Person())


def test_allow_fence_writes_must_be_a_list_of_globs_and_is_described() -> None:
    with pytest.raises(PolicyError, match=r"\[navigation\] allow_fence_writes must be a list"):
        parse_policy({"navigation": {"allow_fence_writes": "/initialpose"}}, where="test.toml")
    policy = parse_policy({"navigation": {**ZONE, "allow_fence_writes": ["/initialpose"]}}, where="t.toml")
    [described] = [line for line in policy.describe() if "writes to what the fence reads" in line]
    assert "only /initialpose" in described
