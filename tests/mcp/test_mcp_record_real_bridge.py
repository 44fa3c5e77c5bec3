"""record on a real rosbridge: the recording decodes with rosbags from its own schemas, and its counts match
what a raw socket saw. Skipped unless ``ROSBRIDGE_TEST_URL`` names a bridge, e.g.::

    LAB=/work/labs/jazzy /work/shared/labs/ros2/inns env ROSBRIDGE_TEST_URL=ws://127.0.0.1:9091 \\
        uv run --no-sync pytest tests/mcp/test_mcp_record_real_bridge.py -q
"""

from __future__ import annotations

import asyncio
import json
import os
from pathlib import Path
from typing import Any

import pytest
import websockets
from mcap.reader import make_reader
from mcp_harness import open_session, text_of
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

REAL_URL = os.environ.get("ROSBRIDGE_TEST_URL")

pytestmark = [
    pytest.mark.real_bridge,
    pytest.mark.skipif(
        REAL_URL is None, reason="set ROSBRIDGE_TEST_URL=ws://host:port to run against a real bridge"
    ),
]


def _decode_all(path: Path) -> tuple[str, dict[str, int], dict[str, list[Any]]]:
    counts: dict[str, int] = {}
    decoded: dict[str, list[Any]] = {}
    with path.open("rb") as handle:
        reader = make_reader(handle)
        profile = reader.get_header().profile
        for schema, channel, message in reader.iter_messages():
            assert schema is not None
            pkg, _, rest = schema.name.partition("/")
            name = f"{pkg}/msg/{rest.split('/')[-1]}"
            store = get_typestore(Stores.EMPTY)
            store.register(get_types_from_msg(schema.data.decode(), name))
            decode = store.deserialize_cdr if channel.message_encoding == "cdr" else store.deserialize_ros1
            decoded.setdefault(channel.topic, []).append(decode(message.data, name))
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    return profile, counts, decoded


async def test_a_real_bridge_recording_decodes_and_counts_match(tmp_path: Path) -> None:
    assert REAL_URL is not None
    async with open_session(REAL_URL, request_timeout=10.0, record_dir=str(tmp_path)) as session:
        topics = (await session.ok("list_topics", {})).structured_content
        assert topics is not None
        have = {t["name"] for t in topics["topics"]}
        wanted = [t for t in ("/chatter", "/tf", "/odom", "/scan", "/camera/image_raw", "/map") if t in have]
        assert "/chatter" in wanted
        chatter_type = next(t["type"] for t in topics["topics"] if t["name"] == "/chatter")
        seen: list[str] = []
        async with websockets.connect(REAL_URL, max_size=None) as raw:
            await raw.send(json.dumps({"op": "subscribe", "topic": "/chatter", "type": chatter_type}))

            async def watch() -> None:
                async for frame in raw:
                    msg = json.loads(frame)
                    if msg.get("op") == "publish" and msg.get("topic") == "/chatter":
                        seen.append(msg["msg"]["data"])

            watcher = asyncio.create_task(watch())
            result = await session.ok("record", {"topics": wanted, "duration": 5, "name": "real"})
            await asyncio.sleep(0.5)  # the raw socket's last messages arrive
            watcher.cancel()
    data = result.structured_content
    assert data is not None
    profile, counts, decoded = _decode_all(tmp_path / "real.mcap")
    assert profile in ("ros1", "ros2")
    assert counts == {t["topic"]: t["messages"] for t in data["topics"] if t["messages"]}
    assert counts["/chatter"] >= 3
    # The raw socket subscribed before and stayed after: what it saw from the first /chatter message recorded
    # to the last is exactly what was recorded, in order.
    recorded = [m.data for m in decoded["/chatter"]]
    first, last = seen.index(recorded[0]), seen.index(recorded[-1])
    assert seen[first : last + 1] == recorded
    assert "ended because its time was up" in text_of(result)
