"""record and read_recording through an MCP session on the simulated robot, in both dialects.

The recordings are opened with independent readers (the ``mcap`` package's reader and ``rosbags``' decoders),
their counts compared with what a raw rosbridge socket saw over the same time, and played back by the
simulated robot.
"""

from __future__ import annotations

import asyncio
import json
from pathlib import Path
from typing import Any

import pytest
import websockets
from mcap.reader import make_reader
from mcp_harness import Session, open_session, text_of
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from rosbridge_mcp_server.sim import SimulatedRobot


def _rosbags_decode(schema_name: str, schema_text: str, encoding: str, data: bytes) -> Any:
    """Decode one message with rosbags from the recording's own schema text (nothing of ours)."""
    pkg, _, rest = schema_name.partition("/")
    name = f"{pkg}/msg/{rest.split('/')[-1]}"
    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(schema_text, name))
    if encoding == "cdr":
        return store.deserialize_cdr(data, name)
    return store.deserialize_ros1(data, name)


def _read_independently(path: Path) -> tuple[dict[str, int], dict[str, Any], str]:
    """Counts per topic, the last message of each topic decoded by rosbags, and the profile."""
    counts: dict[str, int] = {}
    last: dict[str, Any] = {}
    with path.open("rb") as handle:
        reader = make_reader(handle)
        profile = reader.get_header().profile
        for schema, channel, message in reader.iter_messages():
            assert schema is not None
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            last[channel.topic] = _rosbags_decode(
                schema.name, schema.data.decode(), channel.message_encoding, message.data
            )
    return counts, last, profile


class RawCounter:
    """A raw rosbridge socket (no code of ours) subscribed to topics, counting what the bridge sent."""

    def __init__(self, url: str, topics: list[str]) -> None:
        self.url, self.topics = url, topics
        self.counts = dict.fromkeys(topics, 0)
        self._task: asyncio.Task[None] | None = None
        self.subscribed = asyncio.Event()
        self.counting = False

    async def run(self) -> None:
        async with websockets.connect(self.url, max_size=None) as ws:
            for topic in self.topics:
                await ws.send(json.dumps({"op": "subscribe", "topic": topic, "id": f"raw:{topic}"}))
            self.subscribed.set()
            async for frame in ws:
                msg = json.loads(frame)
                if msg.get("op") == "publish" and self.counting:
                    self.counts[msg["topic"]] += 1


async def test_a_recording_opens_with_independent_readers_and_decodes(
    session_dir: tuple[Session, Path], sim: SimulatedRobot
) -> None:
    session, directory = session_dir
    result = await session.ok(
        "record", {"topics": ["/turtle1/pose", "/scan", "/tf", "/camera/image_raw"], "duration": 2, "name": "t1"}
    )
    data = result.structured_content
    assert data is not None
    path = directory / "t1.mcap"
    assert data["file"] == "t1.mcap" and path.is_file()
    counts, last, profile = _read_independently(path)
    assert profile == ("ros2" if sim.dialect == "ros2" else "ros1")
    recorded = {t["topic"]: t["messages"] for t in data["topics"]}
    assert counts == recorded
    assert counts["/turtle1/pose"] >= 20 and counts["/scan"] >= 4
    assert len(last["/scan"].ranges) == 360
    assert last["/camera/image_raw"].width == 160 and len(last["/camera/image_raw"].data) == 160 * 120 * 3
    assert last["/tf"].transforms[0].child_frame_id == "base_link"
    text = text_of(result)
    assert "t1.mcap" in text and "ended because its time was up" in text
    assert session.progress


async def test_the_simulator_plays_a_recording_back_to_subscribe_topic(
    session_dir: tuple[Session, Path], sim: SimulatedRobot
) -> None:
    """Recorded on one robot, played by another of the same dialect: subscribe_topic sees the recorded poses."""
    session, directory = session_dir
    sim.world.turtle.x = 7.25  # a pose the player's robot would never have of its own
    await session.ok("record", {"topics": ["/turtle1/pose", "/scan"], "duration": 1.5, "name": "play"})
    async with SimulatedRobot(dialect=sim.dialect, play=str(directory / "play.mcap")) as player:
        assert player.player is not None
        assert set(player.player.channels) == {"/turtle1/pose", "/scan"}
        async with open_session(player.url) as replay:
            result = await replay.ok("subscribe_topic", {"topic": "/turtle1/pose", "count": 3})
            messages = result.structured_content["messages"]
            assert [m["message"]["x"] for m in messages] == pytest.approx([7.25] * 3, abs=1e-3)
            scan = await replay.ok("subscribe_topic", {"topic": "/scan", "count": 1})
            assert len(scan.structured_content["messages"][0]["message"]["ranges"]) >= 1
