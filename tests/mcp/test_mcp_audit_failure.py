"""An act whose audit line cannot be written is not sent; a stop still is (docs/safety.md, "The audit").

The audit file is a real file whose writes start failing (closed under the server, as a file on a disk that
went away fails: a portable way to make every write raise); what reaches the robot is watched on a raw
rosbridge socket subscribed to the velocity topic.
"""

from __future__ import annotations

import asyncio
import json
from pathlib import Path
from typing import Any

import websockets
from mcp_harness import open_session, types_for

from rosbridge_mcp_server.safety.guard import Audit, PolicyGuard
from rosbridge_mcp_server.safety.policy import Policy
from rosbridge_mcp_server.sim import SimulatedRobot

CMD_VEL = "/turtle1/cmd_vel"
WAIT = 30.0


class RawWatch:
    """A raw rosbridge socket (no code of ours) subscribed to the velocity topic: every Twist, in order."""

    def __init__(self, url: str) -> None:
        self.url = url
        self.twists: list[dict[str, Any]] = []
        self.arrived = asyncio.Condition()
        self.subscribed = asyncio.Event()

    async def run(self) -> None:
        async with websockets.connect(self.url, max_size=None) as ws:
            await ws.send(json.dumps({"op": "subscribe", "topic": CMD_VEL, "id": "raw:cmd_vel"}))
            self.subscribed.set()
            async for frame in ws:
                msg = json.loads(frame)
                if msg.get("op") == "publish" and msg.get("topic") == CMD_VEL:
                    async with self.arrived:
                        self.twists.append(msg["msg"])
                        self.arrived.notify_all()

    async def until(self, count: int) -> list[dict[str, Any]]:
        async with asyncio.timeout(WAIT), self.arrived:
            await self.arrived.wait_for(lambda: len(self.twists) >= count)
        return list(self.twists)


def _twist(sim: SimulatedRobot, x: float) -> dict[str, Any]:
    return {
        "topic": CMD_VEL,
        "message_type": types_for(sim)["twist"],
        "message": {"linear": {"x": x}, "angular": {"z": 0.0}},
    }


async def test_an_act_whose_audit_line_cannot_be_written_is_not_sent(
    sim: SimulatedRobot, tmp_path: Path
) -> None:
    """Audited, 0.1 m/s arrives; the audit file then fails: 0.5 m/s is refused with the reason and never
    arrives; stop_robot's zero still does, and is the next Twist the robot sees."""
    audit_path = tmp_path / "audit.jsonl"
    audit_file = audit_path.open("a", encoding="utf-8")
    guard = PolicyGuard(Policy(), Audit(audit_file))
    watch = RawWatch(sim.url)
    watcher = asyncio.create_task(watch.run())
    try:
        async with asyncio.timeout(WAIT):
            await watch.subscribed.wait()
        async with open_session(sim.url, guard=guard) as session:
            await session.ok("publish_topic", _twist(sim, 0.1))
            assert [t["linear"]["x"] for t in await watch.until(1)] == [0.1]
            audit_file.close()  # every later write into it raises
            text = await session.error("publish_topic", _twist(sim, 0.5))
            assert "Not sent: the audit log could not be written" in text
            assert "Stopping still works" in text
            await session.ok("stop_robot", {})
            arrived = await watch.until(2)
    finally:
        watcher.cancel()
        await asyncio.gather(watcher, return_exceptions=True)
    assert [t["linear"]["x"] for t in arrived] == [0.1, 0.0]
    assert [m.msg["linear"]["x"] for m in sim.world.published[CMD_VEL]] == [0.1, 0.0]
    lines = [json.loads(line) for line in audit_path.read_text(encoding="utf-8").splitlines()]
    assert [(e["outcome"], e["payload"]["linear"]["x"]) for e in lines] == [("allowed", 0.1)]
