"""Safety through MCP sessions on the simulated robot, watched from the robot's side.

What the policy refuses never arrives, what it clamps arrives clamped, confirmation needs a person's yes, and
stop_robot stops what the session started.
"""

from __future__ import annotations

import asyncio
import io
import json
import logging
import math
from typing import Any

import pytest
from mcp.client.context import ClientRequestContext
from mcp.types import ElicitRequestParams, ElicitResult
from mcp_harness import guarded, open_session, text_of, types_for

from mcp import Client
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import load_config
from rosbridge_mcp_server.safety import Audit, Policy, PolicyGuard, parse_policy
from rosbridge_mcp_server.server import build_server
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.tools import TOOL_MODULES

CMD_VEL = "/turtle1/cmd_vel"
WAIT = 30.0


def policy(**sections: Any) -> Policy:
    return parse_policy(sections, where="test-policy.toml")


def twist_call(sim: SimulatedRobot, x: float = 0.0, z: float = 0.0, topic: str = CMD_VEL) -> dict[str, Any]:
    return {
        "topic": topic,
        "message_type": types_for(sim)["twist"],
        "message": {"linear": {"x": x}, "angular": {"z": z}},
    }


def acting_calls(sim: SimulatedRobot) -> dict[str, dict[str, Any]]:
    """One call of every acting tool, each of which would reach the robot if allowed."""
    t = types_for(sim)
    return {
        "publish_topic": twist_call(sim, 1.0),
        "publish_service": {
            "service": "/add_two_ints",
            "service_type": t["add_two_ints"],
            "request": {"a": 1},
        },
        "publish_action": {"action_name": "/fibonacci", "action_type": t["fibonacci"], "goal": {"order": 3}},
        "cancel_action": {"action_name": "/fibonacci"},
        "stop_robot": {},
    }


def nothing_reached(sim: SimulatedRobot) -> None:
    assert CMD_VEL not in sim.world.published
    assert sim.world.service_calls.get("/add_two_ints", 0) == 0
    assert sim.world.goals == {}


def last_on(sim: SimulatedRobot, topic: str) -> dict[str, Any]:
    return sim.world.published[topic][-1].msg


class Person:
    """The person at the MCP client: answers each confirmation with ``action`` (and ``approve``)."""

    def __init__(self, action: str = "accept", approve: bool = True) -> None:
        self.action = action
        self.approve = approve
        self.questions: list[str] = []

    async def __call__(self, context: ClientRequestContext, params: ElicitRequestParams) -> ElicitResult:
        self.questions.append(params.message)
        if self.action == "accept":
            return ElicitResult(action="accept", content={"approve": self.approve})
        return ElicitResult(action=self.action)  # type: ignore[arg-type]


# --- read-only ---------------------------------------------------------------------------------------------


async def test_read_only_lists_only_reading_tools_and_refuses_every_acting_call(sim: SimulatedRobot) -> None:
    """No acting tool is listed, each one called by name anyway is an error, and nothing reaches the robot."""
    stream = io.StringIO()
    guard = PolicyGuard(Policy(read_only=True), Audit(stream))
    async with open_session(sim.url, guard=guard, policy=Policy(read_only=True)) as session:
        listed = (await session.mcp.list_tools()).tools
        calls = acting_calls(sim)
        errors = {name: await session.error(name, arguments) for name, arguments in calls.items()}
        topics = await session.ok("list_topics")
        unknown = await session.error("no_such_tool", {})
    assert all(tool.annotations is not None and tool.annotations.read_only_hint for tool in listed)
    acting = {m.SPEC.name for m in TOOL_MODULES if not m.SPEC.hints.read_only}
    assert acting >= set(calls)
    assert not acting & {tool.name for tool in listed}
    assert all("is not available: this server is read-only" in text for text in errors.values()), errors
    assert "Unknown tool" in unknown
    audited = [json.loads(line) for line in stream.getvalue().splitlines()]
    assert [(e["tool"], e["outcome"]) for e in audited] == [(name, "withheld: read-only") for name in calls]
    assert topics.structured_content is not None
    nothing_reached(sim)


# --- caps, globs ------------------------------------------------------------------------------------------


async def test_a_twist_over_the_cap_is_refused_naming_the_rule_and_never_arrives(sim: SimulatedRobot) -> None:
    """max_linear refuses 2 m/s with the rule and the asked speed; 0.4 m/s then arrives alone."""
    async with open_session(sim.url, guard=None, policy=policy(velocity={"max_linear": 0.5})) as session:
        text = await session.error("publish_topic", twist_call(sim, 2.0))
        assert "max_linear 0.5 m/s; you asked 2" in text
        assert "nothing was sent" in text
        await session.ok("publish_topic", twist_call(sim, 0.4))
    [arrived] = sim.world.published[CMD_VEL]
    assert arrived.msg["linear"]["x"] == pytest.approx(0.4)


async def test_the_angular_cap_holds_on_any_topic_carrying_a_twist(sim: SimulatedRobot) -> None:
    """Caps look at the type, not the topic name: a Twist on /other/drive is capped too."""
    async with open_session(sim.url, guard=None, policy=policy(velocity={"max_angular": 1.0})) as session:
        text = await session.error("publish_topic", twist_call(sim, z=3.0, topic="/other/drive"))
    assert "max_angular 1 rad/s; you asked 3" in text
    assert "/other/drive" not in sim.world.published


async def test_clamp_sends_the_command_at_the_cap_and_says_so(sim: SimulatedRobot) -> None:
    """mode = "clamp": the robot gets 0.5 m/s for 2 m/s asked, and the answer says it was scaled down."""
    caps = policy(velocity={"max_linear": 0.5, "max_angular": 1.0, "mode": "clamp"})
    async with open_session(sim.url, guard=None, policy=caps) as session:
        result = await session.ok("publish_topic", twist_call(sim, 2.0, z=0.5))
    assert "scaled down to the [velocity] caps: linear 2 → 0.5 m/s" in text_of(result)
    assert result.structured_content is not None
    assert result.structured_content["adjusted"].startswith("scaled down")
    arrived = last_on(sim, CMD_VEL)
    assert arrived["linear"]["x"] == pytest.approx(0.5)
    assert arrived["angular"]["z"] == pytest.approx(0.5)
    assert len(sim.world.published[CMD_VEL]) == 1


async def test_topic_globs_refuse_outside_allow_and_inside_deny(sim: SimulatedRobot) -> None:
    """[topics] allow /turtle1/*, deny /turtle1/secret*: /chatter and /turtle1/secret_x are refused."""
    rules = policy(topics={"allow": ["/turtle1/*"], "deny": ["/turtle1/secret*"]})
    string = types_for(sim)["string"]
    async with open_session(sim.url, guard=None, policy=rules) as session:
        outside = await session.error(
            "publish_topic", {"topic": "/chatter", "message_type": string, "message": {"data": "x"}}
        )
        denied = await session.error(
            "publish_topic", {"topic": "/turtle1/secret_x", "message_type": string, "message": {"data": "x"}}
        )
        await session.ok("publish_topic", twist_call(sim, 0.1))
    assert "[topics] allow lists only '/turtle1/*'; /chatter matches none of them" in outside
    assert "[topics] deny '/turtle1/secret*' matches /turtle1/secret_x" in denied
    assert set(sim.world.published) == {CMD_VEL}


async def test_a_denied_service_is_never_called(sim: SimulatedRobot) -> None:
    """[services] deny: the call is refused and the service's counter on the robot stays at zero."""
    rules = policy(services={"deny": ["/add_*"]})
    async with open_session(sim.url, guard=None, policy=rules) as session:
        text = await session.error("publish_service", acting_calls(sim)["publish_service"])
    assert "[services] deny '/add_*' matches /add_two_ints" in text
    assert sim.world.service_calls.get("/add_two_ints", 0) == 0


async def test_an_action_outside_the_allow_list_gets_no_goal(sim: SimulatedRobot) -> None:
    """[actions] allow lists only /navigate_to_pose: a /fibonacci goal is refused and never arrives."""
    rules = policy(actions={"allow": ["/navigate_to_pose"]})
    async with open_session(sim.url, guard=None, policy=rules) as session:
        text = await session.error("publish_action", acting_calls(sim)["publish_action"])
    assert "[actions] allow lists only '/navigate_to_pose'" in text
    assert sim.world.goals == {}


# --- confirmation ---------------------------------------------------------------------------------------


async def test_an_accepting_person_lets_a_motion_through_after_seeing_exactly_it(sim: SimulatedRobot) -> None:
    """confirm = "motion": the person sees tool, topic, type and message, says yes, and the twist arrives."""
    person = Person()
    async with open_session(
        sim.url, guard=None, policy=policy(confirm="motion"), elicitation_callback=person
    ) as session:
        await session.ok("publish_topic", twist_call(sim, 0.3))
    [question] = person.questions
    assert "Tool: publish_topic" in question
    assert f"Topic: {CMD_VEL}" in question
    assert f"Type: {types_for(sim)['twist']}" in question
    assert "  linear.x: 0.3\n" in question
    assert last_on(sim, CMD_VEL)["linear"]["x"] == pytest.approx(0.3)


@pytest.mark.parametrize(
    ("person", "said"),
    [
        (Person("decline"), "The person declined"),
        (Person("cancel"), "dismissed the confirmation"),
        (Person("accept", approve=False), "The person declined"),
        (None, "cannot ask (it does not support elicitation)"),
    ],
)
async def test_anything_but_a_yes_sends_nothing_and_says_why(
    sim: SimulatedRobot, person: Person | None, said: str
) -> None:
    """Declined, dismissed, an unticked box, or a client without elicitation: refused, nothing sent."""
    async with open_session(
        sim.url, guard=None, policy=policy(confirm="motion"), elicitation_callback=person
    ) as session:
        move = await session.error("publish_topic", twist_call(sim, 0.3))
        goal = await session.error("publish_action", acting_calls(sim)["publish_action"])
    assert said in move
    assert said in goal
    assert "nothing was sent" in move
    nothing_reached(sim)


async def test_motion_does_not_ask_for_a_string_and_reading_tools_never_ask(sim: SimulatedRobot) -> None:
    """confirm = "motion" leaves other messages alone; under "always" reading still asks no one."""
    person = Person("decline")
    string = {"topic": "/chatter", "message_type": types_for(sim)["string"], "message": {"data": "hi"}}
    async with open_session(
        sim.url, guard=None, policy=policy(confirm="motion"), elicitation_callback=person
    ) as session:
        await session.ok("publish_topic", string)
    async with open_session(
        sim.url, guard=None, policy=policy(confirm="always"), elicitation_callback=person
    ) as session:
        await session.ok("list_topics")
        await session.ok("get_topic_info", {"topic": CMD_VEL})
        await session.ok("list_services")
        await session.ok("list_actions")
        assert person.questions == []
        await session.error("publish_service", acting_calls(sim)["publish_service"])
    assert len(person.questions) == 1
    assert "/chatter" in sim.world.published


async def test_no_tool_or_argument_lets_the_model_confirm_for_the_person(sim_ros2: SimulatedRobot) -> None:
    """No tool is about confirming, and no acting tool takes an argument that could stand for a yes."""
    async with open_session(sim_ros2.url, guard=None, policy=policy(confirm="always")) as session:
        listed = (await session.mcp.list_tools()).tools
        # An argument the tool does not know is refused by name; without it the person still cannot be asked.
        sneaky = dict(twist_call(sim_ros2, 0.3), confirmed=True, approve=True)
        refused = await session.error("publish_topic", sneaky)
        text = await session.error("publish_topic", twist_call(sim_ros2, 0.3))
    words = ("confirm", "approve", "consent", "person", "elicit")
    for tool in listed:
        assert not any(word in tool.name for word in words)
        for parameter in tool.input_schema.get("properties", {}):
            assert not any(word in parameter for word in words), (tool.name, parameter)
    assert "'confirmed'" in refused
    assert "cannot ask" in text
    assert CMD_VEL not in sim_ros2.world.published


# --- stop_robot -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("confirm", ["never", "always"])
async def test_stop_robot_zeroes_every_velocity_topic_this_session_drove(
    sim: SimulatedRobot, confirm: str
) -> None:
    """After Twists on two topics, stop_robot sends one zero on each, asking no one whatever confirm says."""
    person = Person()
    async with open_session(
        sim.url, guard=None, policy=policy(confirm=confirm), elicitation_callback=person
    ) as session:
        await session.ok("publish_topic", twist_call(sim, 0.4, z=0.2))
        await session.ok("publish_topic", twist_call(sim, 0.2, topic="/base/cmd_vel"))
        asked = len(person.questions)
        result = await session.ok("stop_robot")
        assert len(person.questions) == asked
    for topic in (CMD_VEL, "/base/cmd_vel"):
        last = last_on(sim, topic)
        assert all(last[v][axis] == 0 for v in ("linear", "angular") for axis in ("x", "y", "z")), last
    assert result.structured_content is not None
    assert sorted(result.structured_content["zeroed_topics"]) == ["/base/cmd_vel", CMD_VEL]
    assert "Published a zero velocity command" in text_of(result)


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_stop_robot_cancels_a_running_goal(make_sim: Any, dialect: str) -> None:
    """A long goal started by publish_action (8 s) is cancelled on the robot by stop_robot."""
    sim: SimulatedRobot = await make_sim(dialect=dialect, action_step=0.2)
    async with open_session(sim.url) as session:
        call = asyncio.create_task(
            session.call(
                "publish_action",
                {
                    "action_name": "/fibonacci",
                    "action_type": types_for(sim)["fibonacci"],
                    "goal": {"order": 40},
                    "timeout": 60,
                },
            )
        )
        await sim.world.wait_for(lambda w: any(not g.finished for g in w.goals.values()), WAIT)
        stopped = await session.ok("stop_robot")
        await sim.world.wait_for(lambda w: all(g.finished for g in w.goals.values()), WAIT)
        outcome = await asyncio.wait_for(call, WAIT)
    [goal] = sim.world.goals.values()
    assert goal.cancel_requested
    assert stopped.structured_content is not None
    assert len(stopped.structured_content["goals_cancelled"]) == 1
    assert outcome.structured_content is not None
    assert outcome.structured_content["status"] in ("canceled", "preempted")
    assert outcome.structured_content["canceled_by"] == "stop_robot"
    assert "it was cancelled by stop_robot" in text_of(outcome)


async def test_stop_robot_with_nothing_started_says_so(sim_ros2: SimulatedRobot) -> None:
    """A fresh session has nothing to stop, and the answer says that rather than pretending."""
    async with open_session(sim_ros2.url, guard=None, policy=Policy()) as session:
        result = await session.ok("stop_robot")
    assert "Nothing to stop" in text_of(result)
    assert sim_ros2.world.published == {}


# --- the audit --------------------------------------------------------------------------------------------


async def test_a_stream_that_ran_its_course_is_audited_at_info_and_a_refusal_at_warning(
    sim_ros2: SimulatedRobot, caplog: pytest.LogCaptureFixture
) -> None:
    """A stream that sent all it planned is no warning; a refusal is."""
    rules = policy(services={"deny": ["/add_two_ints"]})
    with caplog.at_level(logging.INFO, logger="rosbridge_mcp_server.audit"):
        async with open_session(sim_ros2.url, guard=None, policy=rules) as session:
            await session.ok("publish_topic", stream_call(sim_ros2, 0.1, 20.0, 0.2))
            await session.error("publish_service", acting_calls(sim_ros2)["publish_service"])
    audited = [(r.levelno, r.getMessage()) for r in caplog.records if r.getMessage().startswith("audit: ")]
    finished = [level for level, text in audited if ": sent 4 of 4" in text]
    refused = [level for level, text in audited if ": refused" in text]
    assert finished == [logging.INFO], audited
    assert refused == [logging.WARNING], audited


async def test_every_acting_call_is_one_json_line_in_the_audit_file(sim: SimulatedRobot) -> None:
    """Allowed, clamped and refused calls each leave one line; reading tools leave none."""
    stream = io.StringIO()
    rules = policy(velocity={"max_linear": 0.5, "mode": "clamp"}, services={"deny": ["/add_two_ints"]})
    guard = PolicyGuard(rules, Audit(stream))
    async with open_session(sim.url, guard=guard, policy=rules) as session:
        await session.ok("list_topics")
        await session.ok("publish_topic", twist_call(sim, 0.1))
        await session.ok("publish_topic", twist_call(sim, 3.0))
        await session.error("publish_service", acting_calls(sim)["publish_service"])
    entries = [json.loads(line) for line in stream.getvalue().splitlines()]
    assert [(e["tool"], e["outcome"]) for e in entries] == [
        ("publish_topic", "allowed"),
        ("publish_topic", "clamped"),
        ("publish_service", "refused"),
    ]
    assert math.isclose(entries[1]["payload"]["linear"]["x"], 0.5)
    assert entries[2]["detail"] == "[services] deny '/add_two_ints' matches /add_two_ints"


@pytest.mark.parametrize(("person", "arrives"), [(Person(), True), (Person("decline"), False)])
async def test_a_2026_session_asks_through_an_input_round_and_sends_once(
    sim_ros2: SimulatedRobot, person: Person, arrives: bool
) -> None:
    """On the 2026-07-28 protocol the question comes back as input_required; a yes sends the twist once."""
    async with open_session(
        sim_ros2.url, mode="auto", guard=None, policy=policy(confirm="motion"), elicitation_callback=person
    ) as session:
        result = await session.call("publish_topic", twist_call(sim_ros2, 0.2))
    [question] = person.questions
    assert f"Topic: {CMD_VEL}" in question
    assert result.is_error is not arrives
    if arrives:
        assert [m.msg["linear"]["x"] for m in sim_ros2.world.published[CMD_VEL]] == [0.2]
    else:
        assert "The person declined" in text_of(result)
        assert CMD_VEL not in sim_ros2.world.published


class Garbled(Person):
    """A client that supports elicitation but answers the form with what it does not ask for."""

    def __init__(self, content: dict[str, Any] | None) -> None:
        super().__init__()
        self.content = content

    async def __call__(self, context: ClientRequestContext, params: ElicitRequestParams) -> ElicitResult:
        self.questions.append(params.message)
        return ElicitResult(action="accept", content=self.content)  # type: ignore[arg-type]


@pytest.mark.parametrize("mode", ["legacy", "auto"])
@pytest.mark.parametrize(
    ("content", "wrong"),
    [({"approve": "perhaps"}, "approve: Input should be a valid boolean"), ({}, "approve: Field required")],
)
async def test_an_answer_that_does_not_fit_the_form_is_named_in_the_answer_and_the_audit(
    sim_ros2: SimulatedRobot, mode: str, content: dict[str, Any], wrong: str
) -> None:
    """A client with elicitation that answers off the form: refused, nothing sent, and the answer and the
    audit say the answer did not match the form and what was wrong, not that the client cannot ask."""
    stream = io.StringIO()
    rules = policy(confirm="motion")
    person = Garbled(content)
    guard = PolicyGuard(rules, Audit(stream))
    async with open_session(
        sim_ros2.url, mode=mode, guard=guard, policy=rules, elicitation_callback=person
    ) as session:
        text = await session.error("publish_topic", twist_call(sim_ros2, 0.3))
    assert len(person.questions) == 1
    assert "did not match the confirmation form" in text, text
    assert wrong in text, text
    assert "does not support elicitation" not in text, text
    assert "nothing was sent" in text
    [entry] = [json.loads(line) for line in stream.getvalue().splitlines()]
    assert entry["outcome"] == "refused"
    assert entry["detail"].startswith("person: answer not in the form"), entry
    assert wrong in entry["detail"], entry
    nothing_reached(sim_ros2)


# --- streams and parameters -----------------------------------------------------------------------------


def stream_call(sim: SimulatedRobot, x: float, rate_hz: float, duration: float) -> dict[str, Any]:
    return dict(twist_call(sim, x), rate_hz=rate_hz, duration=duration)


async def test_stop_robot_ends_a_running_stream_and_the_last_message_is_zero(
    sim: SimulatedRobot,
) -> None:
    """A 30 s velocity stream is ended by stop_robot; the stream's call answers normally, saying so."""
    async with open_session(sim.url, guard=None, policy=Policy()) as session:
        streaming = asyncio.create_task(session.call("publish_topic", stream_call(sim, 0.4, 20.0, 30.0)))
        await sim.world.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) >= 3, WAIT)
        stopped = await session.ok("stop_robot")
        streamed = await asyncio.wait_for(streaming, WAIT)
        # A barrier: once this reading call is answered, everything the server sent before has been handled.
        await session.ok("get_topic_info", {"topic": CMD_VEL})
    # The stream ended long before its 30 s (600 messages at 20 Hz) ran out.
    assert len(sim.world.published[CMD_VEL]) < 200
    assert not streamed.is_error, text_of(streamed)
    assert streamed.structured_content is not None
    assert streamed.structured_content["ended_by_stop"] is True
    assert "stop_robot ended the stream" in text_of(streamed)
    assert stopped.structured_content is not None
    assert stopped.structured_content["streams_stopped"] == [CMD_VEL]
    received = [m.msg["linear"]["x"] for m in sim.world.published[CMD_VEL]]
    assert received[-1] == 0
    assert 0.4 in received
    assert len(received) < 20 * 30


@pytest.mark.parametrize(
    ("rate_hz", "duration", "rule"),
    [
        (50.0, 2.0, "[publish] max_rate_hz 20 Hz; you asked 50 Hz"),
        (10.0, 60.0, "[publish] max_duration 10 s; you asked 60 s"),
    ],
)
async def test_a_stream_over_the_publish_limits_is_refused_before_its_first_message(
    sim: SimulatedRobot, rate_hz: float, duration: float, rule: str
) -> None:
    """[publish] max_rate_hz and max_duration: refused with the rule; not one message reaches the robot."""
    limits = policy(publish={"max_rate_hz": 20, "max_duration": 10})
    async with open_session(sim.url, guard=None, policy=limits) as session:
        text = await session.error("publish_topic", stream_call(sim, 0.1, rate_hz, duration))
    assert rule in text
    assert CMD_VEL not in sim.world.published


async def test_a_stream_is_confirmed_once_showing_its_rate_and_capped_like_one_message(
    sim_ros2: SimulatedRobot,
) -> None:
    """confirm = "motion" asks once per stream (rate and duration shown); the cap clamps each message."""
    person = Person()
    rules = policy(confirm="motion", velocity={"max_linear": 0.2, "mode": "clamp"})
    async with open_session(sim_ros2.url, guard=None, policy=rules, elicitation_callback=person) as session:
        result = await session.ok("publish_topic", stream_call(sim_ros2, 1.0, 20.0, 0.2))
    [question] = person.questions
    assert "Repeated at 20 Hz for 0.2 s." in question
    assert "  linear.x: 0.2\n" in question
    assert "scaled down" in text_of(result)
    received = [m.msg["linear"]["x"] for m in sim_ros2.world.published[CMD_VEL]]
    assert set(received) <= {0.2, 0.0}
    assert received[-1] == 0


async def test_a_denied_parameter_is_not_set(sim: SimulatedRobot) -> None:
    """[parameters] deny: set_parameter is refused and the robot's parameter keeps its value."""
    name = "/turtlesim:background_r" if sim.dialect == "ros2" else "/turtlesim/background_r"
    before = sim.world.params[name]
    rules = policy(parameters={"deny": ["/turtlesim*"]})
    async with open_session(sim.url, guard=None, policy=rules) as session:
        text = await session.error("set_parameter", {"name": name, "value": 200})
    assert f"[parameters] deny '/turtlesim*' matches {name}" in text
    assert sim.world.params[name] == before


async def test_read_only_withholds_set_parameter_and_stop_robot_even_when_tools_picks_them(
    sim_ros2: SimulatedRobot,
) -> None:
    """--tools watch,set_parameter under read-only lists neither set_parameter nor stop_robot."""
    config = load_config({"ROSBRIDGE_MCP_READ_ONLY": "1"}, url=sim_ros2.url, tools="watch,set_parameter")
    async with Client(
        build_server(guarded(RosbridgeClient(sim_ros2.url), config), config), mode="legacy"
    ) as mcp:
        names = [tool.name for tool in (await mcp.list_tools()).tools]
        refused = await mcp.call_tool("set_parameter", {"name": "/turtlesim:background_r", "value": 1})
    assert "set_parameter" not in names
    assert "stop_robot" not in names
    assert "get_parameter" in names
    assert refused.is_error
    assert "read-only" in text_of(refused)
