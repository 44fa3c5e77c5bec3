"""End to end: diagnose and read_logs over stdio on --demo --demo-world nav2, healthy and broken with
--demo-fault, in both dialects."""

from __future__ import annotations

import asyncio
import time
from typing import Any

import pytest
from test_e2e_stdio import StdioServer, _finish, _start

WAIT = 60.0


async def _call(server: StdioServer, name: str, arguments: dict[str, Any]) -> dict[str, Any]:
    answer = (await server.request("tools/call", {"name": name, "arguments": arguments}))["result"]
    assert answer["isError"] is False, (name, answer)
    return dict(answer)


@pytest.mark.parametrize(
    ("dialect", "faults"),
    [("ros2", ""), ("ros2", "scan-stopped,log-errors"), ("ros1", "scan-stopped,log-errors")],
)
async def test_diagnose_over_stdio_names_the_demo_robots_faults(dialect: str, faults: str) -> None:
    args = ["--demo", "--demo-dialect", dialect, "--demo-world", "nav2"]
    server = await _start(*args, *(["--demo-fault", faults] if faults else []))
    try:
        hello = {
            "protocolVersion": "2025-06-18",
            "capabilities": {},
            "clientInfo": {"name": "e2e", "version": "0"},
        }
        await server.request("initialize", hello)
        await server.send({"jsonrpc": "2.0", "method": "notifications/initialized"})
        if faults:
            # The controller logs an error every second: read the log until the first one is in.
            deadline = time.monotonic() + WAIT
            while not (await _call(server, "read_logs", {"level": "error"}))["structuredContent"]["groups"]:
                assert time.monotonic() < deadline, "no error logged"
                await asyncio.sleep(0.2)
        answer = await _call(server, "diagnose", {})
        text = answer["content"][0]["text"]
        data = answer["structuredContent"]
    finally:
        _, _, code = await _finish(server)
    assert code == 0
    if not faults:
        assert text.startswith("No problem found."), text
        assert data["findings"] == []
        return
    head = text.splitlines()[:5]
    assert head[0].startswith("2 problems"), text
    assert any("/rplidar_node publishes /scan but nothing arrived" in line for line in head), text
    assert any("[ERROR] /controller_server: Failed to make progress" in line for line in head), text
    assert [f["subject"] for f in data["findings"][:2]] == ["/scan", "/controller_server"]
