"""The guard: rules, then caps, then the person; every decision audited; refusals name the rule."""

from __future__ import annotations

import asyncio
import io
import json
import logging
import math
from typing import Any

import pytest

from rosbridge_mcp_server.errors import PolicyRefusal, RosbridgeError
from rosbridge_mcp_server.robot.approval import Act, Answer, AskPerson, asking
from rosbridge_mcp_server.robot.velocity import measure
from rosbridge_mcp_server.safety import Audit, Policy, PolicyGuard, parse_policy, question


class Person(AskPerson):
    """Answers every question with ``answer`` and keeps the questions."""

    def __init__(self, answer: Answer = "accept") -> None:
        self.answer: Answer = answer
        self.questions: list[str] = []

    async def __call__(self, text: str) -> Answer:
        self.questions.append(text)
        return self.answer


def twist(x: float = 0.0, z: float = 0.0, *, y: float = 0.0) -> dict[str, Any]:
    return {"linear": {"x": x, "y": y, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": z}}


def cmd(message: Any, type_name: str = "geometry_msgs/msg/Twist", topic: str = "/cmd_vel", **kw: Any) -> Act:
    return Act("publish_topic", "topic", topic, type_name, message, **kw)


def guard(policy: dict[str, Any], stream: io.StringIO | None = None) -> PolicyGuard:
    return PolicyGuard(parse_policy(policy, where="test.toml"), Audit(stream))


async def test_no_policy_approves_every_act_unchanged_and_asks_no_one() -> None:
    """``Policy()`` is the behaviour without a policy file."""
    person = Person("decline")
    act = cmd(twist(5.0, 9.0))
    assert await PolicyGuard(Policy()).approve(act, person) is act
    assert person.questions == []


async def test_read_only_refuses_every_kind_of_act() -> None:
    """read_only leaves nothing that can act, whatever its kind."""
    g = guard({"read_only": True})
    for kind in ("topic", "service", "action", "parameter"):
        with pytest.raises(PolicyRefusal, match=r"read_only"):
            await g.approve(Act("some_tool", kind, "/x", "", {}), Person())


async def test_a_refusal_is_a_rosbridge_error_saying_nothing_was_sent() -> None:
    """The server turns it into an isError answer like every other client error."""
    g = guard({"services": {"deny": ["/reset"]}})
    with pytest.raises(RosbridgeError) as caught:
        await g.approve(Act("publish_service", "service", "/reset", "std_srvs/srv/Empty", {}), Person())
    assert isinstance(caught.value, PolicyRefusal)
    assert "[services] deny '/reset' matches /reset" in str(caught.value)
    assert "nothing was sent" in str(caught.value)


@pytest.mark.parametrize(
    ("kind", "section"),
    [("topic", "topics"), ("service", "services"), ("action", "actions"), ("parameter", "parameters")],
)
async def test_each_kind_is_ruled_by_its_own_section(kind: str, section: str) -> None:
    """[topics] rules publishing, [services] calls, [actions] goals, [parameters] set_parameter."""
    g = guard({section: {"allow": ["/ok/*"]}})
    await g.approve(Act("t", kind, "/ok/thing", "", {}), Person())
    with pytest.raises(PolicyRefusal, match=rf"\[{section}\] allow lists only"):
        await g.approve(Act("t", kind, "/other", "", {}), Person())
    other_kind = "service" if kind != "service" else "topic"
    await g.approve(Act("t", other_kind, "/other", "", {}), Person())


@pytest.mark.parametrize("type_name", ["geometry_msgs/msg/Twist", "geometry_msgs/Twist"])
async def test_the_linear_cap_refuses_a_faster_twist_in_either_spelling(type_name: str) -> None:
    """The rule and the asked speed are in the refusal: "max_linear 0.5 m/s; you asked 2"."""
    g = guard({"velocity": {"max_linear": 0.5}})
    with pytest.raises(PolicyRefusal, match=r"max_linear 0\.5 m/s; you asked 2\b"):
        await g.approve(cmd(twist(2.0), type_name, topic="/any/topic/at/all"), Person())
    await g.approve(cmd(twist(0.5), type_name), Person())


async def test_the_cap_measures_the_length_of_the_vector_not_each_axis() -> None:
    """0.4 forward and 0.4 sideways is 0.57 m/s: over a 0.5 cap although each axis is under it."""
    g = guard({"velocity": {"max_linear": 0.5}})
    with pytest.raises(PolicyRefusal, match=r"you asked 0\.565"):
        await g.approve(cmd(twist(0.4, y=0.4)), Person())


@pytest.mark.parametrize("type_name", ["geometry_msgs/msg/TwistStamped", "geometry_msgs/TwistStamped"])
async def test_the_angular_cap_applies_to_twist_stamped(type_name: str) -> None:
    """A TwistStamped's twist is measured, header aside."""
    g = guard({"velocity": {"max_angular": 1.0}})
    message = {"header": {"frame_id": "base_link"}, "twist": twist(0.0, -3.0)}
    with pytest.raises(PolicyRefusal, match=r"max_angular 1 rad/s; you asked 3"):
        await g.approve(cmd(message, type_name), Person())


async def test_clamp_scales_the_command_down_to_the_cap_keeping_its_direction() -> None:
    """mode = "clamp" sends the command at the cap, in the same direction, and the audit says so."""
    audit = io.StringIO()
    g = guard({"velocity": {"max_linear": 0.5, "max_angular": 1.0, "mode": "clamp"}}, audit)
    message = {"header": {"frame_id": "odom"}, "twist": twist(3.0, 2.0, y=4.0)}
    approved = await g.approve(cmd(message, "geometry_msgs/msg/TwistStamped"), Person())
    speed = measure(approved.type, approved.payload)
    assert math.isclose(speed.linear, 0.5)
    assert math.isclose(speed.angular, 1.0)
    linear = approved.payload["twist"]["linear"]
    assert math.isclose(linear["x"] / linear["y"], 3.0 / 4.0)
    assert approved.payload["header"] == {"frame_id": "odom"}
    entry = json.loads(audit.getvalue())
    assert entry["outcome"] == "clamped"
    assert "linear 5 → 0.5 m/s" in entry["detail"]


async def test_a_command_that_is_not_a_finite_number_is_refused_even_when_clamping() -> None:
    """NaN compares false with every cap; it is refused rather than waved through."""
    g = guard({"velocity": {"max_linear": 0.5, "mode": "clamp"}})
    with pytest.raises(PolicyRefusal, match=r"not a finite number"):
        await g.approve(cmd(twist(math.nan)), Person())
    with pytest.raises(PolicyRefusal, match=r"not a finite number"):
        await g.approve(cmd({"linear": {"x": "fast"}}), Person())


async def test_velocity_caps_leave_other_types_alone() -> None:
    """A String that happens to hold "linear" is not a velocity command."""
    g = guard({"velocity": {"max_linear": 0.5}})
    act = cmd({"data": "linear 9"}, "std_msgs/msg/String")
    assert await g.approve(act, Person()) is act


@pytest.mark.parametrize(
    ("rate", "duration", "rule"),
    [
        (50.0, 5.0, r"max_rate_hz 20 Hz; you asked 50 Hz"),
        (10.0, 60.0, r"max_duration 30 s; you asked 60 s"),
        (10.0, None, r"max_duration 30 s; you asked for an endless stream"),
    ],
)
async def test_stream_limits_refuse_faster_or_longer_streams(
    rate: float, duration: float | None, rule: str
) -> None:
    """[publish] max_rate_hz and max_duration bound publish_topic's rate streams."""
    g = guard({"publish": {"max_rate_hz": 20, "max_duration": 30}})
    with pytest.raises(PolicyRefusal, match=rule):
        await g.approve(cmd({"data": "x"}, "std_msgs/msg/String", rate_hz=rate, duration=duration), Person())
    await g.approve(cmd({"data": "x"}, "std_msgs/msg/String", rate_hz=20.0, duration=30.0), Person())


async def test_motion_asks_for_velocity_commands_and_goals_only() -> None:
    """confirm = "motion": Twists (on any topic) and goals ask; a String or a service call does not."""
    g = guard({"confirm": "motion"})
    person = Person()
    await g.approve(cmd({"data": "hi"}, "std_msgs/msg/String"), person)
    await g.approve(
        Act("publish_service", "service", "/add", "example_interfaces/srv/AddTwoInts", {}), person
    )
    assert person.questions == []
    await g.approve(cmd(twist(0.1), topic="/not/named/like/cmd_vel"), person)
    await g.approve(Act("publish_action", "action", "/fibonacci", "x/action/Fibonacci", {"order": 3}), person)
    assert len(person.questions) == 2


async def test_always_asks_for_every_act() -> None:
    """confirm = "always": a service call asks too."""
    person = Person()
    await guard({"confirm": "always"}).approve(
        Act("publish_service", "service", "/add", "t", {"a": 1}), person
    )
    assert len(person.questions) == 1


async def test_the_question_shows_exactly_what_will_be_sent() -> None:
    """Tool, name, type and the message as sent (after clamping), and the stream's rate."""
    person = Person()
    g = guard({"confirm": "motion", "velocity": {"max_linear": 0.5, "mode": "clamp"}})
    approved = await g.approve(cmd(twist(2.0), rate_hz=10.0, duration=3.0), person)
    (text,) = person.questions
    assert "Tool: publish_topic" in text
    assert "Topic: /cmd_vel" in text
    assert "Type: geometry_msgs/msg/Twist" in text
    assert approved.payload["linear"]["x"] == 0.5
    assert "  linear.x: 0.5\n" in text
    assert "10 Hz for 3 s" in text
    assert "scaled down" in text


@pytest.mark.parametrize(
    ("answer", "said"),
    [
        ("decline", "The person declined"),
        ("cancel", "dismissed the confirmation"),
        ("unsupported", r"cannot ask \(it does not support elicitation\)"),
        ("error", "Could not ask the person"),
    ],
)
async def test_anything_but_accept_refuses_and_says_which(answer: str, said: str) -> None:
    """Declined, cancelled, a client that cannot ask: refused, nothing sent, and the answer says which."""
    g = guard({"confirm": "always"})
    with pytest.raises(PolicyRefusal, match=said) as caught:
        await g.approve(cmd(twist(0.1)), Person(answer))
    assert "nothing was sent" in str(caught.value)


async def test_a_person_who_cannot_be_asked_because_asking_failed_has_not_said_yes() -> None:
    """An exception from the elicitation (client gone, timeout) is a refusal, not an approval."""

    async def broken(text: str) -> Answer:
        raise RuntimeError("client went away")

    with pytest.raises(PolicyRefusal, match=r"Could not ask"):
        await guard({"confirm": "always"}).approve(cmd(twist(0.1)), asking(broken))


async def test_rules_refuse_before_anyone_is_asked() -> None:
    """A denied name is not put to the person: the policy's no is final."""
    person = Person()
    g = guard({"confirm": "always", "topics": {"deny": ["/cmd_vel"]}, "velocity": {"max_linear": 0.1}})
    with pytest.raises(PolicyRefusal, match=r"deny"):
        await g.approve(cmd(twist(0.05)), person)
    with pytest.raises(PolicyRefusal, match=r"max_linear"):
        await g.approve(cmd(twist(1.0), topic="/other"), person)
    assert person.questions == []


async def test_every_decision_is_one_audit_line_on_stderr_and_in_the_file(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Allowed, confirmed, clamped and refused each write one stderr line and one JSON line."""
    caplog.set_level(logging.INFO, logger="rosbridge_mcp_server.audit")
    audit = io.StringIO()
    g = guard({"confirm": "motion", "topics": {"deny": ["/bad"]}}, audit)
    await g.approve(cmd({"data": "a"}, "std_msgs/msg/String", topic="/chatter"), Person())
    await g.approve(cmd(twist(0.1)), Person())
    with pytest.raises(PolicyRefusal):
        await g.approve(cmd(twist(0.1)), Person("decline"))
    with pytest.raises(PolicyRefusal):
        await g.approve(cmd({}, "std_msgs/msg/Empty", topic="/bad"), Person())
    g.record(cmd({}, "std_msgs/msg/Empty"), "sent")
    g.record(cmd({}, "std_msgs/msg/Empty", topic="/bad"), "refused: Refused by the safety policy")
    g.record(cmd({}, "std_msgs/msg/Empty"), "failed: not connected")

    entries = [json.loads(line) for line in audit.getvalue().splitlines()]
    assert [e["outcome"] for e in entries] == [
        "allowed",
        "confirmed",
        "refused",
        "refused",
        "failed: not connected",
    ]
    assert entries[2]["detail"] == "person: decline"
    assert entries[3]["detail"] == "[topics] deny '/bad' matches /bad"
    assert entries[1]["payload"] == twist(0.1)
    assert {"time", "tool", "kind", "name", "type", "rate_hz", "duration"} <= set(entries[0])
    lines = [r.getMessage() for r in caplog.records if r.name == "rosbridge_mcp_server.audit"]
    assert len(lines) == 5
    assert lines[0].startswith("audit: publish_topic topic /chatter std_msgs/msg/String: allowed")


def test_a_huge_message_is_shortened_in_the_question() -> None:
    """A camera image is not read in a dialog; the question says how much is not shown."""
    text = question(cmd({"data": "x" * 10_000}, "std_msgs/msg/String"))
    assert "(10000 characters, 9880 not shown)" in text
    assert len(text) < 1000


async def test_a_person_who_does_not_answer_in_time_has_said_no() -> None:
    """confirm_timeout: silence is a refusal, so a late yes cannot send a command whose moment has passed."""

    async def silent(text: str) -> Answer:
        await asyncio.Event().wait()
        return "accept"

    g = guard({"confirm": "always", "confirm_timeout": 0.05})
    with pytest.raises(PolicyRefusal, match=r"did not answer the confirmation .* within 0\.05 s"):
        await g.approve(cmd(twist(0.1)), asking(silent))


async def test_a_huge_payload_is_cut_in_the_audit_file_with_its_length() -> None:
    """A camera frame does not land whole in every audit line; its length is kept."""
    audit = io.StringIO()
    await guard({}, audit).approve(cmd({"data": "x" * 100_000}, "std_msgs/msg/String"), Person())
    entry = json.loads(audit.getvalue())
    assert entry["payload"]["characters"] > 100_000
    assert len(audit.getvalue()) < 20_000
