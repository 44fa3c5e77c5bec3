"""End to end over stdio: the real command with a policy file, an audit file and a person answering
elicitation, against a simulated robot watched from its own side."""

from __future__ import annotations

import asyncio
import json
import sys
from pathlib import Path
from typing import Any

from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 90.0  # a bound on an event, not a pause: a busy machine (load 10 on 2 cores) still passes
CMD_VEL = "/turtle1/cmd_vel"
POLICY = """
confirm = "motion"
[topics]
deny = ["/rosout"]
[velocity]
max_linear = 0.5
"""


class Client:
    """A hand-written MCP client on the server's stdin/stdout that answers elicitation with ``answer``."""

    def __init__(self, process: asyncio.subprocess.Process, answer: dict[str, Any] | None) -> None:
        self.process = process
        self.answer = answer
        self.questions: list[str] = []
        self._next_id = 0

    async def send(self, message: dict[str, Any]) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write((json.dumps(message) + "\n").encode())
        await self.process.stdin.drain()

    async def request(self, method: str, params: dict[str, Any] | None = None) -> dict[str, Any]:
        self._next_id += 1
        request_id = self._next_id
        await self.send({"jsonrpc": "2.0", "id": request_id, "method": method, "params": params or {}})
        assert self.process.stdout is not None
        while True:
            line = await asyncio.wait_for(self.process.stdout.readline(), WAIT)
            assert line, "the server closed stdout"
            message = json.loads(line)
            if message.get("method") == "elicitation/create":
                self.questions.append(message["params"]["message"])
                assert self.answer is not None, "a client without elicitation was asked"
                await self.send({"jsonrpc": "2.0", "id": message["id"], "result": self.answer})
            elif message.get("id") == request_id and ("result" in message or "error" in message):
                return message

    async def initialize(self, *, elicitation: bool) -> None:
        capabilities: dict[str, Any] = {"elicitation": {"form": {}}} if elicitation else {}
        await self.request(
            "initialize",
            {
                "protocolVersion": "2025-06-18",
                "capabilities": capabilities,
                "clientInfo": {"name": "e2e-safety", "version": "0"},
            },
        )
        await self.send({"jsonrpc": "2.0", "method": "notifications/initialized"})

    async def call(self, name: str, arguments: dict[str, Any]) -> dict[str, Any]:
        reply = await self.request("tools/call", {"name": name, "arguments": arguments})
        result: dict[str, Any] = reply["result"]
        return result

    async def finish(self) -> str:
        assert self.process.stdin is not None
        self.process.stdin.close()
        _, stderr = await asyncio.wait_for(self.process.communicate(), WAIT)
        assert await self.process.wait() == 0
        return stderr.decode()


async def start(*args: str, answer: dict[str, Any] | None = None) -> Client:
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosbridge_mcp_server",
        *args,
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    return Client(process, answer)


def twist(x: float) -> dict[str, Any]:
    return {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "message": {"linear": {"x": x}}}


def text(result: dict[str, Any]) -> str:
    return "\n".join(block["text"] for block in result["content"] if block["type"] == "text")


async def test_a_policy_over_stdio_caps_confirms_stops_and_audits(tmp_path: Path) -> None:
    """Over stdio: an over-cap Twist is refused unasked, an accepted one arrives, stop_robot sends a zero,
    and each acting call is a stderr line and a JSON line."""
    policy, audit = tmp_path / "policy.toml", tmp_path / "audit.jsonl"
    policy.write_text(POLICY, encoding="utf-8")
    async with SimulatedRobot(port=0) as robot:
        client = await start(
            "--url", robot.url, "--policy", str(policy), "--audit-log", str(audit),
            answer={"action": "accept", "content": {"approve": True}},
        )  # fmt: skip
        await client.initialize(elicitation=True)
        refused = await client.call("publish_topic", twist(2.0))
        assert client.questions == []
        allowed = await client.call("publish_topic", twist(0.3))
        stopped = await client.call("stop_robot", {})
        stderr = await client.finish()
        received = [m.msg["linear"]["x"] for m in robot.world.published[CMD_VEL]]
    assert refused["isError"] is True
    assert "max_linear 0.5 m/s; you asked 2" in text(refused)
    assert allowed["isError"] is False
    [question] = client.questions
    assert "Tool: publish_topic" in question
    assert "  linear.x: 0.3\n" in question
    assert stopped["isError"] is False
    assert received == [0.3, 0.0]
    audit_lines = [line for line in stderr.splitlines() if "rosbridge_mcp_server.audit:" in line]
    assert len(audit_lines) == 3
    assert "refused ([velocity] max_linear 0.5 m/s; you asked 2)" in stderr
    entries = [json.loads(line) for line in audit.read_text(encoding="utf-8").splitlines()]
    assert [(e["tool"], e["outcome"]) for e in entries] == [
        ("publish_topic", "refused"),
        ("publish_topic", "confirmed"),
        ("stop_robot", "e-stop"),
    ]


async def test_read_only_over_stdio_lists_and_sends_nothing_that_acts() -> None:
    """--read-only on the command line: tools/list holds only reading tools, publish_topic is an error."""
    async with SimulatedRobot(port=0) as robot:
        client = await start("--url", robot.url, "--read-only")
        await client.initialize(elicitation=False)
        listed = (await client.request("tools/list"))["result"]["tools"]
        refused = await client.call("publish_topic", twist(0.1))
        await client.finish()
        assert CMD_VEL not in robot.world.published
    assert listed
    assert all(tool["annotations"]["readOnlyHint"] is True for tool in listed)
    assert refused["isError"] is True


async def test_a_client_without_elicitation_cannot_confirm_so_nothing_moves(tmp_path: Path) -> None:
    """confirm = "motion" and a client that declared no elicitation: refused with the reason, nothing sent."""
    policy = tmp_path / "policy.toml"
    policy.write_text(POLICY, encoding="utf-8")
    async with SimulatedRobot(port=0) as robot:
        client = await start("--url", robot.url, "--policy", str(policy))
        await client.initialize(elicitation=False)
        refused = await client.call("publish_topic", twist(0.1))
        await client.finish()
        assert CMD_VEL not in robot.world.published
    assert refused["isError"] is True
    assert "cannot ask (it does not support elicitation)" in text(refused)


async def test_approvals_console_never_asks_a_self_approving_client(tmp_path: Path) -> None:
    """approvals = "console" over stdio: a client that would accept anything is never asked; without a console
    the motion is refused saying so, nothing moves, and the start-up log warned of it."""
    policy = tmp_path / "policy.toml"
    policy.write_text('approvals = "console"\n' + POLICY, encoding="utf-8")
    async with SimulatedRobot(port=0) as robot:
        client = await start(
            "--url",
            robot.url,
            "--policy",
            str(policy),
            answer={"action": "accept", "content": {"approve": True}},
        )
        await client.initialize(elicitation=True)
        refused = await client.call("publish_topic", twist(0.1))
        stderr = await client.finish()
        assert CMD_VEL not in robot.world.published
    assert client.questions == []
    assert refused["isError"] is True
    assert "approvals = 'console'" in text(refused)
    assert "no console is served (--console)" in stderr
