"""Run by ``test_e2e_tasks_peer.py`` in a separate virtual environment that has FastMCP's tasks client
(``fastmcp-tasks``), which is no dependency of ours: it drives our server over stdio as a tasks host would.

Usage: ``python tasks_peer.py stdio SERVER_PYTHON ROBOT_URL`` (it starts the server) or
``python tasks_peer.py http MCP_URL TOKEN``. Prints one JSON object: what it saw.
"""

from __future__ import annotations

import asyncio
import json
import sys
from typing import Any

from fastmcp import Client
from fastmcp.client.transports import StdioTransport, StreamableHttpTransport
from fastmcp_tasks.client import call_tool_task

TERMINAL = ("completed", "failed", "cancelled")


async def main(how: str, first: str, second: str) -> dict[str, Any]:
    transport: Any
    if how == "http":
        transport = StreamableHttpTransport(first, auth=second)
    else:
        server = ["-m", "rosbridge_mcp_server", "--url", second, "--log-level", "WARNING"]
        transport = StdioTransport(first, server)
    seen: dict[str, Any] = {"messages": []}
    async with Client(transport) as client:
        # A drive as a task, polled to its end by hand, then its answer fetched.
        task = await call_tool_task(client, "navigate_to", {"goal": {"x": 2.5, "y": 7.5, "yaw": 90}})
        async with asyncio.timeout(60):
            while (status := await task.status()).status not in TERMINAL:
                seen["messages"].append(status.status_message or "")
                await asyncio.sleep(0.1)
        seen["status"] = status.status
        result = await task.result()
        seen["succeeded"] = bool((result.structured_content or {}).get("succeeded"))
        seen["kinds"] = sorted({block.type for block in result.content})
        # The client's transparent path: call_tool resolves the task to the tool's answer.
        plain = await client.call_tool("navigate_to", {"forward": 0.3})
        seen["transparent"] = bool((plain.structured_content or {}).get("succeeded"))
        # A far goal, cancelled once the robot drives.
        far = await call_tool_task(client, "navigate_to", {"goal": {"x": 1.5, "y": 9.0}})
        async with asyncio.timeout(60):
            while "m to go" not in ((await far.status()).status_message or ""):  # noqa: ASYNC110 (polling is the protocol)
                await asyncio.sleep(0.05)
        await far.cancel()
        async with asyncio.timeout(60):
            while (status := await far.status()).status not in TERMINAL:  # noqa: ASYNC110 (polling is the protocol)
                await asyncio.sleep(0.05)
        seen["cancelled"] = [status.status, status.status_message]
    return seen


if __name__ == "__main__":
    print(json.dumps(asyncio.run(main(sys.argv[1], sys.argv[2], sys.argv[3]))))
