"""record and read_recording through an MCP session on the simulated robot, in both dialects.

The recordings are opened with independent readers (the ``mcap`` package's reader and ``rosbags``' decoders),
their counts compared with what a raw rosbridge socket saw over the same time, and played back by the
simulated robot.
"""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import websockets
from mcap.reader import make_reader
from mcp_harness import Session, open_session, text_of
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from rosbridge_mcp_server.safety.policy import parse_policy
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
        "record",
        {"topics": ["/turtle1/pose", "/scan", "/tf", "/camera/image_raw"], "duration": 2, "name": "t1"},
    )
    data = result.structured_content
    assert data is not None
    path = directory / "t1.mcap"
    assert data["file"] == "t1.mcap"
    assert path.is_file()
    counts, last, profile = _read_independently(path)
    assert profile == ("ros2" if sim.dialect == "ros2" else "ros1")
    recorded = {t["topic"]: t["messages"] for t in data["topics"]}
    assert counts == recorded
    assert counts["/turtle1/pose"] >= 2  # ~60 Hz for 2 s on a quiet machine; a busy one publishes fewer
    assert counts["/scan"] >= 1
    assert len(last["/scan"].ranges) == 360
    assert last["/camera/image_raw"].width == 160
    assert len(last["/camera/image_raw"].data) == 160 * 120 * 3
    assert last["/tf"].transforms[0].child_frame_id == "base_link"
    text = text_of(result)
    assert "t1.mcap" in text
    assert "ended because its time was up" in text
    assert session.progress


async def test_the_simulator_plays_a_recording_back_to_subscribe_topic(
    session_dir: tuple[Session, Path], sim: SimulatedRobot
) -> None:
    """Recorded on one robot, played by another of that dialect: subscribe_topic sees the recorded poses."""
    session, directory = session_dir
    sim.world.turtle.x = 7.25  # a pose the player's robot would never have of its own
    await session.ok("record", {"topics": ["/turtle1/pose", "/scan"], "duration": 1.5, "name": "play"})
    # Played over and over: a 1.5 s recording played once can be over before a loaded machine's second
    # subscription opens (seen in CI: /scan's one message never came).
    async with SimulatedRobot(
        dialect=sim.dialect, play=str(directory / "play.mcap"), play_loop=True
    ) as player:
        assert player.player is not None
        assert set(player.player.channels) == {"/turtle1/pose", "/scan"}
        async with open_session(player.url) as replay:
            result = await replay.ok("subscribe_topic", {"topic": "/turtle1/pose", "count": 3})
            messages = result.structured_content["messages"]
            assert [m["message"]["x"] for m in messages] == pytest.approx([7.25] * 3, abs=1e-3)
            scan = await replay.ok("subscribe_topic", {"topic": "/scan", "count": 1})
            assert len(scan.structured_content["messages"][0]["message"]["ranges"]) >= 1


async def test_counts_match_what_a_raw_socket_saw(
    session_dir: tuple[Session, Path], sim: SimulatedRobot
) -> None:
    """A raw socket publishes 60 numbered messages while record runs; another raw socket and the recording
    both hold all 60, in order."""
    session, directory = session_dir
    msg_type = "std_msgs/msg/String" if sim.dialect == "ros2" else "std_msgs/String"
    async with websockets.connect(sim.url) as publisher, websockets.connect(sim.url) as watcher:
        await publisher.send(json.dumps({"op": "advertise", "topic": "/numbered", "type": msg_type}))
        await watcher.send(json.dumps({"op": "subscribe", "topic": "/numbered", "type": msg_type}))
        async with asyncio.timeout(5):
            # The simulator has no event for a new subscription: its graph is polled, within the timeout.
            while not sim.bridge.has_subscribers("/numbered") or "/numbered" not in sim.graph.topic_types:  # noqa: ASYNC110
                await asyncio.sleep(0.01)
        recording = asyncio.create_task(
            session.ok("record", {"topics": ["/numb*"], "duration": 4, "name": "numbered"})
        )
        async with asyncio.timeout(5):  # wait until record's own subscription is in place
            while sum(1 for c in sim.bridge.connections.values() if "/numbered" in c.subscriptions) < 2:  # noqa: ASYNC110
                await asyncio.sleep(0.01)
        for index in range(60):
            await publisher.send(
                json.dumps({"op": "publish", "topic": "/numbered", "msg": {"data": f"n{index}"}})
            )
            await asyncio.sleep(0.005)
        seen = []
        async with asyncio.timeout(5):
            while len(seen) < 60:
                frame = json.loads(await watcher.recv())
                if frame.get("op") == "publish":
                    seen.append(frame["msg"]["data"])
        result = await recording
    assert seen == [f"n{i}" for i in range(60)]
    counts, last, _ = _read_independently(directory / "numbered.mcap")
    assert counts == {"/numbered": 60}
    assert last["/numbered"].data == "n59"
    assert result.structured_content["topics"][0]["lost"] == 0


async def test_read_recording_answers_each_mode_within_the_budget(
    session_dir: tuple[Session, Path], sim: SimulatedRobot
) -> None:
    session, _directory = session_dir
    await session.ok(
        "record", {"topics": ["/turtle1/pose", "/odom", "/map", "/scan"], "duration": 3, "name": "r"}
    )
    listing = await session.ok("read_recording", {})
    assert "r.mcap" in text_of(listing)
    summary = await session.ok("read_recording", {"file": "r.mcap"})
    topics = {t["topic"]: t for t in summary.structured_content["details"]["topics"]}
    assert topics["/turtle1/pose"]["messages"] >= 2
    assert topics["/map"]["messages"] == 1
    assert summary.structured_content["details"]["indexed"] is True
    stats = await session.ok(
        "read_recording", {"file": "r.mcap", "mode": "stats", "fields": ["/turtle1/pose x y"]}
    )
    series = stats.structured_content["details"]["series"]
    assert series[0]["min"] == pytest.approx(5.544, abs=0.01)
    assert len(series[0]["windows"]) >= 3
    around = await session.ok(
        "read_recording", {"file": "r.mcap", "mode": "messages", "at": 1.5, "window": 0.5}
    )
    assert around.structured_content["details"]["total"] >= 3
    plot = await session.ok(
        "read_recording", {"file": "r.mcap", "mode": "plot", "fields": ["/odom pose.pose.position.x"]}
    )
    assert any(block.type == "image" for block in plot.content)
    drawn = await session.ok("read_recording", {"file": "r.mcap", "mode": "map", "topics": ["/map", "/odom"]})
    assert any(block.type == "image" for block in drawn.content)
    for result in (listing, summary, stats, around, plot, drawn):
        assert len(text_of(result)) <= 8000
    wrong = await session.error(
        "read_recording", {"file": "r.mcap", "mode": "stats", "fields": ["/odom nope"]}
    )
    assert "nope" in wrong


async def test_bad_input_is_refused_with_the_reason(
    session_dir: tuple[Session, Path], tmp_path: Path
) -> None:
    session, directory = session_dir
    text = await session.error("record", {"topics": ["/nothing/*"], "duration": 1})
    assert "matches no topic" in text
    assert "/turtle1/pose" in text
    assert not directory.exists() or not list(directory.glob("*.mcap"))
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "notes.mcap").write_text("hello, not a recording")
    text = await session.error("read_recording", {"file": "notes.mcap"})
    assert "not an MCAP recording" in text
    (tmp_path / "secret.mcap").write_bytes(b"\x89MCAP0\r\n")
    for outside in ("../secret.mcap", str(tmp_path / "secret.mcap")):
        text = await session.error("read_recording", {"file": outside})
        assert "outside the recording directory" in text
    (directory / "link.mcap").symlink_to(tmp_path / "secret.mcap")
    text = await session.error("read_recording", {"file": "link.mcap"})
    assert "outside the recording directory" in text
    text = await session.error("record", {"topics": ["/chatter"], "duration": 1, "name": "../escape"})
    assert "bare file name" in text
    assert not (tmp_path / "escape.mcap").exists()


async def test_the_size_cap_ends_the_recording_with_a_readable_file(
    session_dir: tuple[Session, Path],
) -> None:
    session, directory = session_dir
    result = await session.ok(
        "record", {"topics": ["/camera/image_raw"], "duration": 30, "max_megabytes": 0.5, "name": "capped"}
    )
    data = result.structured_content
    assert data["ended"] == "size"
    assert data["seconds"] < 20
    assert "size cap" in text_of(result)
    counts, _, _ = _read_independently(directory / "capped.mcap")
    assert counts["/camera/image_raw"] == data["topics"][0]["messages"] >= 1
    assert (directory / "capped.mcap").stat().st_size <= 0.5e6


async def test_stop_ends_a_running_recording(session_dir: tuple[Session, Path]) -> None:
    session, directory = session_dir
    recording = asyncio.create_task(
        session.ok("record", {"topics": ["/chatter"], "duration": 60, "name": "long"})
    )
    async with asyncio.timeout(10):
        while True:
            answer = await session.ok("record", {"stop": True})
            if answer.structured_content["stopped"]:
                break
            await asyncio.sleep(0.05)
    result = await asyncio.wait_for(recording, 10)
    assert result.structured_content["ended"] == "stopped"
    counts, _, _ = _read_independently(directory / "long.mcap")
    assert counts.get("/chatter", 0) == result.structured_content["topics"][0]["messages"]


async def test_reading_a_recording_still_being_written_says_so(session_dir: tuple[Session, Path]) -> None:
    """read_recording on the file a running recording writes: it says the recording is still running and how
    to end it (it said the file was "not an MCAP recording: an empty file"); once ended, it reads."""
    session, _ = session_dir
    recording = asyncio.create_task(
        session.ok("record", {"topics": ["/chatter"], "duration": 60, "name": "live"})
    )
    async with asyncio.timeout(10):  # polled: the file and its registration give no event
        while "is still being recorded" not in (
            text := await session.error("read_recording", {"file": "live"})
        ):
            assert "not an MCAP recording" not in text, text
            await asyncio.sleep(0.05)
    assert 'record {"stop": true, "name": "live"}' in text, text
    await session.ok("record", {"stop": True, "name": "live"})
    await asyncio.wait_for(recording, 10)
    # It reads (whether /chatter's first message came before the stop is the load's: seen with none).
    assert text_of(await session.ok("read_recording", {"file": "live"})).startswith("live: ")


async def test_the_policy_can_forbid_or_cap_recording(sim_ros2: SimulatedRobot, tmp_path: Path) -> None:
    directory = tmp_path / "rec"
    forbid = parse_policy({"recording": {"enabled": False}})
    async with open_session(sim_ros2.url, policy=forbid, record_dir=str(directory)) as session:
        text = await session.error("record", {"topics": ["/chatter"], "duration": 1})
        assert "forbids recording" in text
    assert not directory.exists()
    capped = parse_policy({"recording": {"max_seconds": 2, "max_megabytes": 0.3}})
    async with open_session(sim_ros2.url, policy=capped, record_dir=str(directory)) as session:
        text = await session.error("record", {"topics": ["/chatter"], "duration": 5})
        assert "cap of 2 s" in text
        result = await session.ok(
            "record", {"topics": ["/camera/image_raw"], "duration": 2, "max_megabytes": 50}
        )
        assert result.structured_content["ended"] == "size"
        assert result.structured_content["bytes"] <= 0.3e6


async def test_a_ros2_recording_plays_on_a_ros1_robot(session_ros2: Session, tmp_path: Path) -> None:
    """The ros2msg schemas name types the ROS 1 simulator has too: the ROS 1 robot plays them."""
    async with open_session(session_ros2.ros.url, record_dir=str(tmp_path)) as session:
        await session.ok("record", {"topics": ["/turtle1/pose", "/chatter"], "duration": 1.5, "name": "x"})
    async with SimulatedRobot(dialect="ros1", play=str(tmp_path / "x.mcap"), play_loop=True) as player:
        assert player.player is not None
        assert set(player.player.channels) == {"/turtle1/pose", "/chatter"}
        async with open_session(player.url) as replay:
            result = await replay.ok("subscribe_topic", {"topic": "/chatter", "count": 2})
            texts = [m["message"]["data"] for m in result.structured_content["messages"]]
            assert all(t.startswith("Hello World: ") for t in texts)
            info = await replay.ok("get_topic_info", {"topic": "/chatter"})
            assert "/player" in text_of(info)


def test_the_command_refuses_a_file_it_cannot_play(tmp_path: Path) -> None:
    bad = tmp_path / "bad.mcap"
    bad.write_text("not mcap")
    done = subprocess.run(
        [sys.executable, "-m", "rosbridge_mcp_server.sim", "--port", "0", "--play", str(bad)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 2
    assert "not an MCAP file" in done.stderr
    assert done.stdout == ""


async def test_read_only_withholds_record_but_not_read_recording(
    sim_ros2: SimulatedRobot, tmp_path: Path
) -> None:
    """record writes files on the server's host: a read-only server neither lists nor runs it."""
    policy = parse_policy({"read_only": True})
    async with open_session(sim_ros2.url, policy=policy, guard=None, record_dir=str(tmp_path)) as session:
        names = {tool.name for tool in (await session.mcp.list_tools()).tools}
        assert "read_recording" in names
        assert "record" not in names
        await session.error("record", {"topics": ["/chatter"], "duration": 1})
        await session.ok("read_recording", {})
    assert not await asyncio.to_thread(lambda: list(tmp_path.glob("*.mcap")))


async def test_a_bridge_outage_shows_as_a_gap_and_the_recording_goes_on(
    session_dir: tuple[Session, Path], sim: SimulatedRobot
) -> None:
    """The bridge stops for about a second mid-recording: the subscription comes back after the reconnect, and
    the answer names the pause."""
    session, _ = session_dir
    recording = asyncio.create_task(
        session.ok("record", {"topics": ["/turtle1/pose"], "duration": 5, "name": "gap"})
    )
    await sim.wait_for(lambda world: world.turtle is not None, timeout=15)
    async with asyncio.timeout(10):  # record's subscription is in place
        while not sim.bridge.has_subscribers("/turtle1/pose"):  # noqa: ASYNC110
            await asyncio.sleep(0.01)
    await asyncio.sleep(1.0)  # some messages before the outage
    await sim.stop()
    await asyncio.sleep(1.0)  # the outage itself: nothing can arrive
    await sim.start()
    result = await asyncio.wait_for(recording, 20)
    topic = result.structured_content["topics"][0]
    assert topic["gaps"], text_of(result)
    assert topic["gaps"][0]["seconds"] >= 0.9
    assert topic["messages"] > 25  # before and after the outage
    assert "gaps" in text_of(result)


async def test_a_recording_leaves_other_tools_the_topic_as_json(session_dir: tuple[Session, Path]) -> None:
    """record asks for /scan as CBOR; the bridge then sends CBOR to every listener of /scan on the connection,
    and subscribe_topic and view_scan beside the recording still read plain JSON ranges (seen as a bug:
    "Error executing tool subscribe_topic", "The scan has no 'ranges' array")."""
    session, _ = session_dir
    recording = asyncio.create_task(
        session.ok("record", {"topics": ["/scan"], "duration": 60, "name": "scan"})
    )
    try:
        async with asyncio.timeout(10):  # the recorder's subscription shows on the robot's graph
            while True:
                info = await session.ok("get_topic_info", {"topic": "/scan"})
                if info.structured_content["subscribers"]:
                    break
                await asyncio.sleep(0.05)
        read = await session.ok("subscribe_topic", {"topic": "/scan", "count": 2})
        messages = read.structured_content["messages"]
        assert messages
        assert all("ranges" in m["message"] for m in messages), messages
        await session.ok("view_scan", {"topic": "/scan"})
    finally:
        await session.ok("record", {"stop": True})
        result = await asyncio.wait_for(recording, 10)
    assert result.structured_content["topics"][0]["messages"] >= 1


async def test_the_listing_says_a_small_file_s_size_and_counts_one_recording_as_one(
    session_dir: tuple[Session, Path],
) -> None:
    """A 40 KB file is listed as 40 KB, not 0.0 MB, and one file is "1 recording"."""
    session, directory = session_dir
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "small.mcap").write_bytes(b"\0" * 40_000)
    text = text_of(await session.ok("read_recording"))
    assert text.startswith("1 recording in "), text
    assert "- small.mcap: 40 KB, " in text, text
