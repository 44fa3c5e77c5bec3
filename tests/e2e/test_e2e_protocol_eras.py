"""Both protocol eras on every transport: the 2025 handshake (``initialize``) and 2026-07-28
(``server/discover``, no session), in memory, over stdio and over Streamable HTTP, with the SDK's own client.

Each session lists the tools, reads the robot, acts with the person's confirmation (asked mid-call in a
handshake session, through an input round in a 2026 one), gets a tool's error for a wrong argument, and sees a
goal's feedback as progress; what reaches the robot is read from the simulated robot itself.
"""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
from e2e_transports import serving
from mcp.client.context import ClientRequestContext
from mcp.types import CallToolResult, ElicitRequestParams, ElicitResult, TextContent

from mcp import Client
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import PolicyGuard, parse_policy
from rosbridge_mcp_server.server import build_server
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.tools import TOOL_MODULES

pytestmark = [
    pytest.mark.parametrize("mode", ["legacy", "auto"]),
    pytest.mark.parametrize("transport", ["memory", "stdio", "http"]),
]

CMD_VEL = "/turtle1/cmd_vel"
TWIST = {"linear": {"x": 0.3, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.1}}
FIB = "/fibonacci"
WAIT = 30.0


def _text(result: CallToolResult) -> str:
    return "\n".join(block.text for block in result.content if isinstance(block, TextContent))


@contextlib.asynccontextmanager
async def connected(
    transport: str, mode: str, sim: SimulatedRobot, policy: Path, **client: Any
) -> AsyncIterator[Client]:
    """An MCP session in *mode* on a server for *sim* under *policy*, over *transport*."""
    if transport != "memory":
        async with (
            serving(transport, "--url", sim.url, "--policy", str(policy)) as served,
            served.connect(mode=mode, **client) as session,
        ):
            yield session
        return
    config = Config(
        url=sim.url, connect_timeout=2.0, policy=parse_policy({"confirm": "motion"}, where=str(policy))
    )
    ros = RosbridgeClient(
        sim.url, connect_timeout=config.connect_timeout, request_timeout=config.request_timeout
    )
    server = build_server(RobotSession(ros, PolicyGuard(config.policy)), config)
    async with Client(server, mode=mode, **client) as session:
        await ros.wait_connected(WAIT)
        yield session


async def test_each_era_lists_reads_acts_with_confirmation_fails_clearly_and_reports_progress(
    transport: str, mode: str, sim_ros2: SimulatedRobot, tmp_path: Path
) -> None:
    asked: list[str] = []

    async def person(context: ClientRequestContext, params: ElicitRequestParams) -> ElicitResult:
        asked.append(params.message)
        return ElicitResult(action="accept", content={"approve": True})

    policy = tmp_path / "confirm.toml"
    policy.write_text('confirm = "motion"\n')
    progress: list[tuple[float, float | None, str | None]] = []

    async def on_progress(value: float, total: float | None, message: str | None) -> None:
        progress.append((value, total, message))

    async with connected(transport, mode, sim_ros2, policy, elicitation_callback=person) as client:
        listed = await client.list_tools()
        topics = await client.call_tool("list_topics", {})
        acted = await client.call_tool(
            "publish_topic", {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "message": TWIST}
        )
        wrong = await client.call_tool(
            "publish_topic", {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "mesage": TWIST}
        )
        goal = await client.call_tool(
            "publish_action",
            {"action_name": FIB, "action_type": "example_interfaces/action/Fibonacci", "goal": {"order": 3}},
            progress_callback=on_progress,
        )

    assert sorted(tool.name for tool in listed.tools) == sorted(m.SPEC.name for m in TOOL_MODULES)
    assert not topics.is_error, _text(topics)
    assert topics.structured_content is not None
    assert CMD_VEL in [row["name"] for row in topics.structured_content["topics"]]
    # The person was asked about the twist (which then went out once) and about the goal, nothing else.
    assert len(asked) == 2
    assert f"Topic: {CMD_VEL}" in asked[0]
    assert f"Action: {FIB}" in asked[1]
    assert not acted.is_error, _text(acted)
    await sim_ros2.wait_for(lambda world: CMD_VEL in world.published, WAIT)
    assert [m.msg["linear"]["x"] for m in sim_ros2.world.published[CMD_VEL]] == [0.3]
    # A misspelt argument: a tool's error naming it, nothing sent.
    assert wrong.is_error
    assert "unknown argument 'mesage' (did you mean message?)" in _text(wrong)
    assert len(sim_ros2.world.published[CMD_VEL]) == 1
    # The goal's feedback arrived as progress, one notification a feedback.
    assert not goal.is_error, _text(goal)
    assert goal.structured_content is not None
    assert goal.structured_content["result"] == {"sequence": [0, 1, 1, 2]}
    assert goal.structured_content["feedback_count"] >= 1
    assert [value for value, _, _ in progress] == list(
        range(1, goal.structured_content["feedback_count"] + 1)
    )
