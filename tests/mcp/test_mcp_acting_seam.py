"""The safety seam: each acting tool asks the guard after checking, before sending, and tells it the end."""

from __future__ import annotations

import dataclasses
from typing import Any

from mcp.client.context import ClientRequestContext
from mcp.types import ElicitRequestParams, ElicitResult
from mcp_harness import open_session, types_for

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.errors import PolicyRefusal
from rosbridge_mcp_server.robot.approval import ALLOW_ALL, Act, Answer, AskPerson
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.tools.base import ToolContext

CMD_VEL = "/turtle1/cmd_vel"


class RecordingGuard:
    """Approves (optionally changing the payload, or refusing) and keeps every act and outcome."""

    def __init__(self, *, refuse: str | None = None, clamp: Any = None, ask: str | None = None) -> None:
        self.refuse = refuse
        self.clamp = clamp
        self.ask = ask
        self.asked: list[Act] = []
        self.records: list[tuple[Act, str]] = []
        self.answers: list[Answer] = []

    async def approve(self, act: Act, ask: AskPerson) -> Act:
        self.asked.append(act)
        if self.ask is not None:
            answer = await ask(self.ask)
            self.answers.append(answer)
            if answer != "accept":
                raise PolicyRefusal(f"the person did not approve ({answer})")
        if self.refuse is not None:
            raise PolicyRefusal(self.refuse)
        if self.clamp is not None:
            return dataclasses.replace(act, payload=self.clamp)
        return act

    def record(self, act: Act, outcome: str) -> None:
        self.records.append((act, outcome))

    def held(self) -> str | None:
        return None

    def send_interval(self, act: Act) -> float:
        return 0.0


async def test_a_refused_publish_is_an_error_naming_the_rule_and_nothing_is_sent(sim: SimulatedRobot) -> None:
    """The refusal's text reaches the model, the guard records it, and the robot gets no message."""
    guard = RecordingGuard(refuse="rule 'no motion': cmd_vel is blocked")
    async with open_session(sim.url, guard=guard) as session:
        text = await session.error(
            "publish_topic",
            {"topic": "turtle1/cmd_vel", "message_type": types_for(sim)["twist"], "message": {}},
        )
    assert "rule 'no motion': cmd_vel is blocked" in text
    [act] = guard.asked
    assert (act.tool, act.kind, act.name, act.type) == (
        "publish_topic",
        "topic",
        CMD_VEL,
        types_for(sim)["twist"],
    )
    assert [outcome for _, outcome in guard.records] == ["refused: rule 'no motion': cmd_vel is blocked"]
    assert CMD_VEL not in sim.world.published


async def test_a_message_that_does_not_fit_never_reaches_the_guard(sim: SimulatedRobot) -> None:
    """Checking comes first: the guard only sees acts that could be sent."""
    guard = RecordingGuard()
    async with open_session(sim.url, guard=guard) as session:
        await session.error(
            "publish_topic",
            {"topic": CMD_VEL, "message_type": types_for(sim)["twist"], "message": {"linear": {"x": "fast"}}},
        )
    assert guard.asked == []
    assert guard.records == []


async def test_the_act_the_guard_returns_is_the_one_sent(sim: SimulatedRobot) -> None:
    """A clamped copy replaces the message: the robot and the answer both get the clamped one."""
    clamped = {"linear": {"x": 0.2}}
    guard = RecordingGuard(clamp=clamped)
    async with open_session(sim.url, guard=guard) as session:
        result = await session.ok(
            "publish_topic",
            {"topic": CMD_VEL, "message_type": types_for(sim)["twist"], "message": {"linear": {"x": 5.0}}},
        )
    assert result.structured_content is not None
    assert result.structured_content["message"] == clamped
    await sim.world.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) == 1)
    assert sim.world.published[CMD_VEL][0].msg["linear"]["x"] == 0.2
    assert [outcome for _, outcome in guard.records] == ["sent"]


async def test_services_and_goals_go_through_the_guard_once_each(sim: SimulatedRobot) -> None:
    """publish_service and publish_action each ask once, with the absolute name, and record how it went."""
    guard = RecordingGuard()
    types = types_for(sim)
    async with open_session(sim.url, guard=guard) as session:
        await session.ok(
            "publish_service",
            {"service": "add_two_ints", "service_type": types["add_two_ints"], "request": {"a": 1, "b": 2}},
        )
        await session.ok(
            "publish_action",
            {
                "action_name": "fibonacci",
                "action_type": types["fibonacci"],
                "goal": {"order": 2},
                "timeout": 10,
            },
        )
    assert [(act.tool, act.kind, act.name) for act in guard.asked] == [
        ("publish_service", "service", "/add_two_ints"),
        ("publish_action", "action", "/fibonacci"),
    ]
    assert guard.asked[0].payload == {"a": 1, "b": 2}
    assert guard.asked[1].payload == {"order": 2}
    assert [outcome for _, outcome in guard.records] == ["sent", "sent"]


async def test_a_failed_send_is_recorded_as_failed(sim_ros2: SimulatedRobot) -> None:
    """A service the bridge does not find is recorded as a failure, after the guard approved it."""
    guard = RecordingGuard()
    async with open_session(sim_ros2.url, guard=guard) as session:
        await session.error(
            "publish_service", {"service": "/nowhere", "service_type": "std_srvs/srv/Trigger", "request": {}}
        )
    [(act, outcome)] = guard.records
    assert act.name == "/nowhere"
    assert outcome.startswith("failed: ServiceError")


async def test_the_guard_can_ask_the_person_through_elicitation(sim_ros2: SimulatedRobot) -> None:
    """The question reaches the MCP client; a decline there is a refusal and nothing is published."""
    questions: list[str] = []

    async def decline(context: ClientRequestContext, params: ElicitRequestParams) -> ElicitResult:
        questions.append(params.message)
        return ElicitResult(action="decline")

    guard = RecordingGuard(ask="Drive the turtle forward?")
    async with open_session(sim_ros2.url, guard=guard, elicitation_callback=decline) as session:
        text = await session.error(
            "publish_topic", {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "message": {}}
        )
    assert questions == ["Drive the turtle forward?"]
    assert guard.answers == ["decline"]
    assert "the person did not approve (decline)" in text
    assert CMD_VEL not in sim_ros2.world.published


async def test_without_elicitation_the_person_cannot_be_asked(sim_ros2: SimulatedRobot) -> None:
    """A client that offers no elicitation makes every question answer "unsupported"."""
    guard = RecordingGuard(ask="Drive the turtle forward?")
    async with open_session(sim_ros2.url, guard=guard) as session:
        await session.error(
            "publish_topic", {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "message": {}}
        )
    assert guard.answers == ["unsupported"]


async def test_a_tool_context_asks_nobody_by_default_and_allow_all_approves_unchanged() -> None:
    """A tool context without the server's elicitation never asks the person; its robot's ALLOW_ALL guard
    approves an act unchanged."""
    robot = RobotSession(RosbridgeClient("ws://127.0.0.1:9"), ALLOW_ALL)
    ctx = ToolContext(robot=robot, config=Config())
    act = Act("publish_topic", "topic", CMD_VEL, "geometry_msgs/msg/Twist", {})
    assert ctx.guard is ALLOW_ALL
    assert await ctx.guard.approve(act, ctx.ask_person) is act
    assert await ctx.ask_person("May I?") == "unsupported"
