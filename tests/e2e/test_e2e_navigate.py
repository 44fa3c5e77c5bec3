"""End to end over stdio: navigate_to through the real command with a policy (a keep-out zone, named places,
``[navigation] confirm = "motion"``) and a person answering elicitation, on the simulated Nav2 world."""

from __future__ import annotations

import asyncio
import json
import math
from pathlib import Path
from typing import Any

import pytest
from test_e2e_safety import WAIT, Client, start, text

from rosbridge_mcp_server.sim import SimulatedRobot

POLICY = """
[navigation]
confirm = "motion"
robot_radius = 0.25
[navigation.keep_out]
corner = [[8.0, 1.0], [10.5, 1.0], [10.5, 3.0], [8.0, 3.0]]
[places]
dock = [3.0, 3.0, 180]
"""


class ProgressClient(Client):
    """The e2e client, also asking for progress and keeping each notification's message."""

    progress: list[str]

    async def call_with_progress(self, name: str, arguments: dict[str, Any]) -> dict[str, Any]:
        self.progress = []
        self._next_id += 1
        request_id = self._next_id
        params = {"name": name, "arguments": arguments, "_meta": {"progressToken": f"p{request_id}"}}
        await self.send({"jsonrpc": "2.0", "id": request_id, "method": "tools/call", "params": params})
        assert self.process.stdout is not None
        while True:
            line = await asyncio.wait_for(self.process.stdout.readline(), WAIT)
            assert line, "the server closed stdout"
            message = json.loads(line)
            if message.get("method") == "notifications/progress":
                self.progress.append(message["params"].get("message", ""))
            elif message.get("method") == "elicitation/create":
                self.questions.append(message["params"]["message"])
                await self.send({"jsonrpc": "2.0", "id": message["id"], "result": self.answer})
            elif message.get("id") == request_id:
                result: dict[str, Any] = message["result"]
                return result


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_navigate_to_over_stdio_asks_drives_reports_and_refuses_the_keep_out(
    tmp_path: Path, dialect: str
) -> None:
    policy = tmp_path / "policy.toml"
    policy.write_text(POLICY, encoding="utf-8")
    async with SimulatedRobot(dialect=dialect, port=0, world="nav2") as robot:
        robot.nav2.navigator.speed = 8.0
        started = await start(
            "--url", robot.url, "--policy", str(policy),
            answer={"action": "accept", "content": {"approve": True}},
        )  # fmt: skip
        client = ProgressClient(started.process, started.answer)
        await client.initialize(elicitation=True)
        refused = await client.call("navigate_to", {"goal": {"x": 9.0, "y": 2.0}})
        asked_before = list(client.questions)
        reached = await client.call_with_progress("navigate_to", {"goal": "dock"})
        pose = await client.call("get_transform", {"target_frame": "map", "source_frame": "base_link"})
        await client.finish()
    assert refused["isError"] is True
    assert "keep-out zone 'corner'" in text(refused)
    assert asked_before == []
    assert [block["type"] for block in refused["content"]] == ["text", "image"]
    assert reached["isError"] is False, text(reached)
    assert reached["structuredContent"]["succeeded"] is True
    [question] = client.questions
    assert "Tool: navigate_to" in question
    assert "Goal in map: x=3.00 y=3.00 m yaw=180°" in question
    assert any("m to go" in message for message in client.progress)
    assert [block["type"] for block in reached["content"]] == ["text", "image"]
    where = pose["structuredContent"]
    assert math.hypot(where["translation"]["x"] - 3.0, where["translation"]["y"] - 3.0) < 0.2
    yaw = where["rotation"]["yaw"]
    assert abs(math.remainder(yaw - 180.0, 360.0)) < 10
