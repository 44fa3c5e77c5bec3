"""Adding a tool (docs/architecture.md, "Adding a tool"): what an acting tool must say is asked where it is
written, and nothing falls into a silent default."""

from __future__ import annotations

import io
import json

import pytest
from mcp_harness import open_session
from pydantic import BaseModel

from rosbridge_mcp_server.safety import Audit, Policy, PolicyGuard
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.tools import TOOL_MODULES
from rosbridge_mcp_server.tools.base import ACTS_ON_ROBOT, READS_ROBOT, ToolSpec


class _Answer(BaseModel):
    done: bool


def test_an_acting_tool_that_does_not_say_what_it_acts_on_fails_where_its_spec_is_written() -> None:
    """A forgotten ``acts_on`` is a TypeError naming the tool when the module is imported, and a reading tool
    cannot claim one."""
    with pytest.raises(TypeError, match=r"new_tool: an acting tool's ToolSpec must say acts_on="):
        ToolSpec(name="new_tool", title="New", description="d", hints=ACTS_ON_ROBOT, output=_Answer)
    with pytest.raises(TypeError, match=r"new_reader: a reading tool acts on nothing"):
        ToolSpec(
            name="new_reader",
            title="New",
            description="d",
            hints=READS_ROBOT,
            output=_Answer,
            acts_on="topic",
        )


def test_every_acting_tool_says_what_it_acts_on() -> None:
    acting = {m.SPEC.name: m.SPEC.acts_on for m in TOOL_MODULES if not m.SPEC.hints.read_only}
    assert acting == {
        "publish_topic": "topic",
        "publish_service": "service",
        "publish_action": "action",
        "cancel_action": "action",
        "set_parameter": "parameter",
        "stop_robot": "topic",
        "navigate_to": "action",
        "record": "topic",
        "move_arm": "action",
        "move_gripper": "action",
    }


async def test_a_withheld_tool_is_audited_with_what_it_acts_on(sim_ros2: SimulatedRobot) -> None:
    """A read-only server refusing navigate_to and set_parameter audits each as what it acts on (an action,
    a parameter), not as a topic by default."""
    stream = io.StringIO()
    guard = PolicyGuard(Policy(read_only=True), Audit(stream))
    async with open_session(sim_ros2.url, guard=guard, policy=Policy(read_only=True)) as session:
        await session.error("navigate_to", {"forward": 1.0})
        await session.error("set_parameter", {"name": "/turtlesim:background_r", "value": 1})
    audited = [json.loads(line) for line in stream.getvalue().splitlines()]
    assert [(e["tool"], e["kind"], e["outcome"]) for e in audited] == [
        ("navigate_to", "action", "withheld: read-only"),
        ("set_parameter", "parameter", "withheld: read-only"),
    ]
    assert sim_ros2.world.goals == {}
