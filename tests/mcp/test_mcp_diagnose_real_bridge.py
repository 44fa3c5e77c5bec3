"""diagnose and read_logs on a real bridge (the labs): a look within its time, the logs the nodes' own.

Skipped unless ``ROSBRIDGE_TEST_URL`` names a bridge. Nothing is broken on purpose here (the labs are shared:
their faults are set and healed by hand, see docs/performance.md, item 13).
"""

from __future__ import annotations

import asyncio
import os

import pytest
from mcp_harness import open_session, text_of
from test_mcp_diagnose import TOOLS, keeper_of

from rosbridge_mcp_server.tools.paging import TEXT_BUDGET

REAL_URL = os.environ.get("ROSBRIDGE_TEST_URL")
WAIT = 15.0

pytestmark = pytest.mark.skipif(
    REAL_URL is None, reason="set ROSBRIDGE_TEST_URL=ws://host:port to run against a real bridge"
)


async def test_diagnose_and_read_logs_on_a_real_bridge() -> None:
    assert REAL_URL is not None
    async with open_session(REAL_URL, request_timeout=WAIT, tools=TOOLS) as session:
        keeper = keeper_of(session.ros)
        await asyncio.wait_for(keeper.ready.wait(), WAIT)
        # How long it takes on a real bridge is the benchmark's figure (scripts/bench.py), not a bound here.
        result = await session.ok("diagnose")
        logs = await session.ok("read_logs", {"level": "debug"})
    data = result.structured_content
    assert data is not None
    assert len(text_of(result)) <= TEXT_BUDGET
    assert {"graph", "logs"} <= set(data["checked"]) | set(data["unavailable"])
    facts = session.ros.session_facts
    version = facts.dialect.version if facts is not None else 2
    if version == 1:
        assert data["unavailable"]["lifecycle"] == "ROS 1 has no lifecycle nodes"
    page = logs.structured_content
    assert page is not None
    assert page["source"] in ("/rosout", "/rosout_agg")
    # Every line names the node that logged it (rosbridge's own lines at least, as it saw us connect).
    assert all(group["node"].startswith("/") and group["node"] != "/?" for group in page["groups"])
