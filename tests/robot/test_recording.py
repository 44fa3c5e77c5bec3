"""The recorder against the simulated robot, below MCP: a nearly full disk ends a recording cleanly, the
encoders agree with an independent decoder, and the summary comes from the index."""

from __future__ import annotations

import asyncio
import os
import struct
from pathlib import Path

import pytest
from mcap.reader import make_reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.robot.approval import ALLOW_ALL
from rosbridge_mcp_server.robot.recording.files import PathRefused, create_recording, resolve_recording
from rosbridge_mcp_server.robot.recording.reading import NotARecording, summarize_recording
from rosbridge_mcp_server.robot.recording.recorder import choose_topics, record_topics
from rosbridge_mcp_server.robot.recording.writing import DISK_RESERVE
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.sim import SimulatedRobot
from sim_transport import client_for


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is recorded is what is tested."""
    return True


async def _robot(sim: SimulatedRobot) -> tuple[RosbridgeClient, RobotSession]:
    client = client_for(sim, connect_timeout=2.0, request_timeout=5.0)
    await client.start()
    await client.wait_connected(30.0)
    return client, RobotSession(client, ALLOW_ALL)


async def test_a_nearly_full_disk_ends_the_recording_with_a_readable_file(
    sim: SimulatedRobot, tmp_path: Path
) -> None:
    """The free space falls under the reserve after a few messages: recording stops, the file is finished
    (summary and index written) and holds what was written."""
    client, robot = await _robot(sim)
    try:
        free = [DISK_RESERVE * 4]

        def free_bytes() -> int:
            # The disk fills by 1 MB per probe (the writer probes every half second).
            free[0] -= DISK_RESERVE
            return free[0]

        path, fd = create_recording(tmp_path, "full")
        topics = await choose_topics(robot.graph, ["/turtle1/pose"])
        result = await record_topics(
            client, robot.graph, topics, path=path, fd=fd, duration=20, max_bytes=10**9, free_bytes=free_bytes
        )
    finally:
        await client.close()
    assert result.ended == "disk"
    assert result.seconds < 10
    assert result.finish_error is None
    summary = summarize_recording(path)
    assert summary.indexed
    assert summary.topics[0].timing.count == result.topics[0].timing.count >= 1


async def test_encoded_messages_decode_with_rosbags_in_both_dialects(
    sim: SimulatedRobot, tmp_path: Path
) -> None:
    client, robot = await _robot(sim)
    try:
        topics = await choose_topics(robot.graph, ["/odom", "/camera/depth/image_raw", "/plan", "/map"])
        path, fd = create_recording(tmp_path, "all")
        await record_topics(
            client,
            robot.graph,
            topics,
            path=path,
            fd=fd,
            duration=3.0,  # 1.5 s saw no message at a load of 25
            max_bytes=10**9,
            free_bytes=lambda: 10**12,
        )
    finally:
        await client.close()
    seen = set()
    with path.open("rb") as handle:
        for schema, channel, message in make_reader(handle).iter_messages():
            assert schema is not None
            pkg, _, rest = schema.name.partition("/")
            name = f"{pkg}/msg/{rest.split('/')[-1]}"
            store = get_typestore(Stores.EMPTY)
            store.register(get_types_from_msg(schema.data.decode(), name))
            if channel.message_encoding == "cdr":
                decoded = store.deserialize_cdr(message.data, name)
            else:
                assert channel.message_encoding == "ros1"
                decoded = store.deserialize_ros1(message.data, name)
            seen.add(channel.topic)
            if channel.topic == "/map":
                assert decoded.info.width * decoded.info.height == len(decoded.data)
                assert decoded.header.frame_id == "map"
            if channel.topic == "/camera/depth/image_raw":
                assert decoded.encoding == "16UC1"
    assert seen == {"/odom", "/camera/depth/image_raw", "/plan", "/map"}


async def test_a_glob_that_matches_nothing_names_the_topics(sim: SimulatedRobot) -> None:
    client, robot = await _robot(sim)
    try:
        with pytest.raises(ValueError, match=r"matches no topic.*/turtle1/pose"):
            await choose_topics(robot.graph, ["/lidar*"])
        with pytest.raises(ValueError, match=r"is not in the ROS graph.*/chatter"):
            await choose_topics(robot.graph, ["/chat"])
        assert [t for t, _ in await choose_topics(robot.graph, ["/tf*", "tf"])] == ["/tf", "/tf_static"]
    finally:
        await client.close()


def test_paths_stay_inside_the_recording_directory(tmp_path: Path) -> None:
    directory = tmp_path / "rec"
    directory.mkdir()
    (tmp_path / "outside.mcap").write_bytes(b"x")
    os.symlink(tmp_path, directory / "up")
    for given in ("../outside.mcap", str(tmp_path / "outside.mcap"), "up/outside.mcap"):
        with pytest.raises(PathRefused, match="outside the recording directory"):
            resolve_recording(directory, given)
    # A symlink planted where a new recording would go is never written through.
    os.symlink(tmp_path / "target.mcap", directory / "planted.mcap")
    with pytest.raises((PathRefused, OSError)):
        create_recording(directory, "planted")
    assert not (tmp_path / "target.mcap").exists()


def test_files_that_are_not_mcap_are_refused_with_what_they_are(tmp_path: Path) -> None:
    cases = {
        "empty.mcap": (b"", "an empty file"),
        "bag.mcap": (b"#ROSBAG V2.0\n....", "ROS 1 bag"),
        "db.mcap": (b"SQLite format 3\x00....", "SQLite"),
        "text.mcap": (b"hello there", "starting with b'hello th'"),
    }
    for name, (content, reason) in cases.items():
        (tmp_path / name).write_bytes(content)
        with pytest.raises(NotARecording, match="not an MCAP recording") as caught:
            summarize_recording(tmp_path / name)
        assert reason in str(caught.value)


async def test_a_recording_cut_off_without_its_summary_is_still_read(
    sim: SimulatedRobot, tmp_path: Path
) -> None:
    """A recorder killed mid-way leaves no summary section: the file is read through instead."""
    client, robot = await _robot(sim)
    try:
        path, fd = create_recording(tmp_path, "whole")
        topics = await choose_topics(robot.graph, ["/turtle1/pose"])
        result = await record_topics(
            client,
            robot.graph,
            topics,
            path=path,
            fd=fd,
            duration=1.0,
            max_bytes=10**9,
            free_bytes=lambda: 10**12,
        )
    finally:
        await client.close()
    data = path.read_bytes()
    # The footer (before the closing magic) says where the summary starts: cut the file there.
    (summary_start,) = struct.unpack_from("<Q", data, len(data) - 8 - 29 + 9)
    assert 0 < summary_start < len(data)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[:summary_start])
    summary = await asyncio.to_thread(summarize_recording, cut)
    assert not summary.indexed
    assert summary.topics[0].timing.count == result.topics[0].timing.count > 0
