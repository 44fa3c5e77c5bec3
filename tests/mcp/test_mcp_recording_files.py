"""read_recording and ``--play`` on files put in the recordings folder, through a real MCP client session:
hostile files refused in every mode with a worded error (never "Error executing tool"), a name round-trips
without its ``.mcap``, and the map mode places an ``odom`` path in the map with the recording's own ``/tf``.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import subprocess
import sys
from collections.abc import AsyncIterator, Awaitable, Callable
from pathlib import Path

import pytest
import websockets
from mcp_harness import Session, open_session, text_of

import recording_bombs as bombs
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.player import PlayError

MakeSim = Callable[..., Awaitable[SimulatedRobot]]
#: Each class, small enough for a test, and the words its refusal holds.
HOSTILE = {
    "declared.mcap": (bombs.chunk_declaring, "declares 2000000000 bytes uncompressed"),
    "fanout.mcap": (lambda d: bombs.fanout(d, chunks=40, entries=2000), "name the same message index"),
    "tiny.mcap": (lambda d: bombs.tiny_messages(d, 400_000), "compression bomb"),
    "empty.mcap": (bombs.empty_records, "over this server's budget"),
    "huge.mcap": (bombs.huge_length, "but only 64 are left"),
    "huge-index.mcap": (bombs.huge_index, "points past the end of the file"),
    "truncated.mcap": (bombs.truncated, "cut off"),
}
#: Every mode, with the arguments it needs.
MODES = (
    {},
    {"mode": "stats", "fields": ["/data data"]},
    {"mode": "plot", "fields": ["/data data"]},
    {"mode": "messages", "at": 0.0},
    {"mode": "map", "topics": ["/data", "/data"]},
)


@pytest.fixture
async def folder_session(sim_ros2: SimulatedRobot, tmp_path: Path) -> AsyncIterator[tuple[Session, Path]]:
    directory = tmp_path / "recordings"
    directory.mkdir()
    async with open_session(sim_ros2.url, record_dir=str(directory)) as opened:
        yield opened, directory


async def test_every_mode_refuses_each_hostile_file_with_what_is_wrong(
    folder_session: tuple[Session, Path],
) -> None:
    session, directory = folder_session
    for name, (write, words) in HOSTILE.items():
        path = write(directory)
        assert path.name == name
        for arguments in MODES:
            text = await session.error("read_recording", {"file": name, **arguments})
            assert words in text, (name, arguments, text)
            assert name in text
            assert "Error executing tool" not in text
    # The server still answers afterwards.
    listing = await session.ok("read_recording", {})
    assert "truncated.mcap" in text_of(listing)


async def test_schemas_that_recurse_and_deep_json_are_refused_when_decoded(
    folder_session: tuple[Session, Path],
) -> None:
    session, directory = folder_session
    bombs.recursive_schema(directory)
    bombs.deep_schema(directory, levels=5000)
    bombs.deep_json(directory)
    bombs.empty_elements(directory)
    bombs.free_objects(directory)
    cases = {
        "recursive.mcap": "has a type that contains itself",
        "deep.mcap": "nests types over 64 levels deep",
        "deep-json.mcap": "nests over 64 levels deep",
        "elements-ros1.mcap": "has an array of pkg/Nothing, a type that takes no bytes",
        "free-objects.mcap": "objects from 0 bytes",
    }
    for name, words in cases.items():
        summary = await session.ok("read_recording", {"file": name})
        assert "/data" in text_of(summary)
        text = await session.error("read_recording", {"file": name, "mode": "messages", "at": 0})
        assert words in text
        assert "Error executing tool" not in text


async def test_a_name_given_to_record_finds_its_file_without_the_suffix(
    session_dir: tuple[Session, Path],
) -> None:
    """record {"name": "drive1"} writes drive1.mcap; read_recording {"file": "drive1"} reads it."""
    session, directory = session_dir
    await session.ok("record", {"topics": ["/turtle1/pose"], "duration": 0.5, "name": "drive1"})
    assert (directory / "drive1.mcap").is_file()
    summary = await session.ok("read_recording", {"file": "drive1"})
    assert "/turtle1/pose" in text_of(summary)
    missing = await session.error("read_recording", {"file": "drive2"})
    assert "There is no recording 'drive2'" in missing


async def test_the_map_mode_places_odom_in_the_map_with_the_recorded_tf(
    make_sim: MakeSim, tmp_path: Path
) -> None:
    """On the Nav2 world (map → odom at (5.54, 5.54)): the /odom path starts at the robot's map position, not
    at the map's corner; /tf as the path topic gives the same poses; /plan draws the plan; a topic without
    poses says what can be drawn."""
    robot = await make_sim(dialect="ros2", world="nav2")
    directory = tmp_path / "recordings"
    async with open_session(robot.url, record_dir=str(directory)) as session:
        await session.ok(
            "record", {"topics": ["/map", "/odom", "/tf", "/plan", "/scan"], "duration": 1.5, "name": "nav"}
        )
        odom = await session.ok("read_recording", {"file": "nav", "mode": "map", "topics": ["/map", "/odom"]})
        text = text_of(odom)
        assert "to (5.54, 5.54) in map" in text, text
        assert "coincided" not in text
        assert odom.structured_content["details"]["placed"] is True
        tf = await session.ok("read_recording", {"file": "nav", "mode": "map", "topics": ["/map", "/tf"]})
        assert "to (5.54, 5.54) in map" in text_of(tf)
        assert tf.structured_content["details"]["poses"] > 0
        plan = await session.ok("read_recording", {"file": "nav", "mode": "map", "topics": ["/map", "/plan"]})
        assert "/plan has no message in the recording: no path drawn." in text_of(plan)  # no goal, no plan
        scan = await session.ok("read_recording", {"file": "nav", "mode": "map", "topics": ["/map", "/scan"]})
        assert "holds no pose: a path is read from Odometry" in text_of(scan)


async def test_the_map_mode_draws_a_recorded_plan(sim_ros2: SimulatedRobot, tmp_path: Path) -> None:
    """The turtle world's planner publishes /plan (nav_msgs/Path): its last plan is the path drawn."""
    directory = tmp_path / "recordings"
    async with open_session(sim_ros2.url, record_dir=str(directory)) as session:
        await session.ok("record", {"topics": ["/map", "/plan"], "duration": 1.5, "name": "plan"})
        arguments = {"file": "plan", "mode": "map", "topics": ["/map", "/plan"]}
        plan = await session.ok("read_recording", arguments)
    assert plan.structured_content["details"]["poses"] > 1, text_of(plan)
    assert plan.structured_content["details"]["placed"] is True
    assert "to (9.50, 3.00) in map" in text_of(plan)


async def test_an_odom_path_without_tf_says_plainly_it_could_not_be_placed(
    make_sim: MakeSim, tmp_path: Path
) -> None:
    robot = await make_sim(dialect="ros2", world="nav2")
    directory = tmp_path / "recordings"
    async with open_session(robot.url, record_dir=str(directory)) as session:
        await session.ok("record", {"topics": ["/map", "/odom"], "duration": 1.0, "name": "notf"})
        answer = await session.ok("read_recording", {"file": "notf", "mode": "map"})
        assert "no map → odom transform on /tf" in text_of(answer)
        assert answer.structured_content["details"]["placed"] is False


@pytest.mark.parametrize("name", ["declared.mcap", "tiny.mcap", "truncated.mcap", "huge.mcap"])
async def test_the_simulator_refuses_to_play_a_hostile_file(name: str, tmp_path: Path) -> None:
    write, words = HOSTILE[name]
    path = write(tmp_path)
    with pytest.raises(PlayError, match="cannot be played") as caught:
        async with SimulatedRobot(play=str(path)):
            pass
    assert words in str(caught.value)


async def test_the_simulator_plays_no_topic_whose_schema_makes_objects_from_nothing(tmp_path: Path) -> None:
    """A file claiming a type the simulator knows, with a schema that decodes into billions of objects: its
    only topic is not played (decoding it froze the simulator's loop), so there is nothing to play."""
    with pytest.raises(PlayError, match="has no topic this simulator can play"):
        async with SimulatedRobot("ros1", play=str(bombs.empty_elements(tmp_path, name="std_msgs/String"))):
            pass


def test_the_play_command_says_why_a_hostile_file_cannot_play(tmp_path: Path) -> None:
    path = bombs.chunk_declaring(tmp_path)
    done = subprocess.run(
        [sys.executable, "-m", "rosbridge_mcp_server.sim", "--port", "0", "--play", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 2
    assert "declares 2000000000 bytes uncompressed" in done.stderr


async def _publish_maps(url: str, done: asyncio.Event) -> None:
    """A raw client publishing a 112 x 112 /map twice a second, as a SLAM node updating its map does."""
    grid = {
        "header": {"frame_id": "map"},
        "info": {"resolution": 0.1, "width": 112, "height": 112, "origin": {"orientation": {"w": 1.0}}},
        "data": [0] * (112 * 112),
    }
    async with websockets.connect(url, max_size=None) as ws:
        await ws.send(json.dumps({"op": "advertise", "topic": "/map", "type": "nav_msgs/msg/OccupancyGrid"}))
        while not done.is_set():
            await ws.send(json.dumps({"op": "publish", "topic": "/map", "msg": grid}))
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(done.wait(), 0.5)


async def test_a_played_back_map_is_latched_and_view_map_draws_it_at_once(
    make_sim: MakeSim, tmp_path: Path
) -> None:
    """A map recorded several times (a SLAM node's updates) plays latched, as map_server publishes it:
    view_map gets the latest at once instead of waiting for the next one the recording holds."""
    robot = await make_sim(dialect="ros2", world="nav2")
    directory = tmp_path / "recordings"
    done = asyncio.Event()
    publisher = asyncio.create_task(_publish_maps(robot.url, done))
    try:
        async with open_session(robot.url, record_dir=str(directory)) as session:
            await session.ok("record", {"topics": ["/map", "/odom"], "duration": 2.0, "name": "maps"})
            summary = await session.ok("read_recording", {"file": "maps"})
    finally:
        done.set()
        await publisher
    [maps] = [t for t in summary.structured_content["details"]["topics"] if t["topic"] == "/map"]
    assert maps["messages"] >= 2
    async with SimulatedRobot(dialect="ros2", play=str(directory / "maps.mcap"), play_loop=True) as player:
        assert player.player is not None
        assert "/map" in player.graph.latched
        async with open_session(player.url) as replay:
            await replay.ok("subscribe_topic", {"topic": "/odom", "count": 1})  # the player is playing
            answer = await replay.ok("view_map", {"timeout": 2})
            assert "did not arrive" not in text_of(answer)


async def _subscription(robot: SimulatedRobot, topic: str, other_than: object = None) -> object:
    """The bridge's subscription object for ``topic`` once there is one (other than ``other_than``: a new
    subscribe op), the graph polled, bounded: the simulated bridge announces no subscription."""
    async with asyncio.timeout(10):
        while True:
            found = [c.subscriptions.get(topic) for c in robot.bridge.connections.values()]
            fresh = [sub for sub in found if sub is not None and sub is not other_than]
            if fresh:
                return fresh[0]
            await asyncio.sleep(0.01)


async def test_view_map_says_a_late_small_map_was_not_latched_not_that_cbor_dropped_it(
    sim_ros2: SimulatedRobot,
) -> None:
    """A 112 x 112 map published only after view_map's first wait ended (as a played-back, unlatched map
    comes): the note names the missing latch, not CBOR."""
    grid = {
        "header": {"frame_id": "map"},
        "info": {"resolution": 0.1, "width": 112, "height": 112, "origin": {"orientation": {"w": 1.0}}},
        "data": [0] * (112 * 112),
    }
    async with websockets.connect(sim_ros2.url, max_size=None) as ws, open_session(sim_ros2.url) as session:
        await ws.send(
            json.dumps({"op": "advertise", "topic": "/slam_map", "type": "nav_msgs/msg/OccupancyGrid"})
        )
        call = asyncio.create_task(session.ok("view_map", {"topic": "/slam_map", "timeout": 1}))
        first = await _subscription(sim_ros2, "/slam_map")  # the first wait (CBOR)
        await _subscription(sim_ros2, "/slam_map", other_than=first)  # the second: the first ended empty
        await ws.send(json.dumps({"op": "publish", "topic": "/slam_map", "msg": grid}))
        text = text_of(await call)
    assert "(12544 cells) did not arrive within 1 s and came on a second wait" in text
    assert "does not latch it" in text
    assert "CBOR" not in text


async def test_a_symlink_loop_in_the_folder_is_named_and_the_rest_still_listed(
    folder_session: tuple[Session, Path],
) -> None:
    """A link to itself in the recordings folder: the listing still lists the good file; reading it, or
    recording under its name, is refused in our words (was "unexpected error (RuntimeError)" for each)."""
    session, directory = folder_session
    bombs.good_json(directory)
    (directory / "loop.mcap").symlink_to(directory / "loop.mcap")
    listing = await session.ok("read_recording", {})
    assert "good.mcap" in text_of(listing)
    for name, arguments in (("read_recording", {"file": "loop.mcap"}), ("record", {"name": "loop"})):
        text = await session.error(
            name, {**arguments, "topics": ["/rosout"]} if name == "record" else arguments
        )
        assert "'loop.mcap' is a link that leads to itself" in text, text
        assert "unexpected error" not in text


async def test_log_times_over_the_signed_range_are_read(folder_session: tuple[Session, Path]) -> None:
    """An MCAP log time is unsigned: 2**64 - 1 ns is read (was "unexpected error (OverflowError)")."""
    session, directory = folder_session
    body = bombs.schema(name="", text=b"", enc="") + bombs.channel(sid=0, enc="json")
    body += bombs.message(log_time=2**64 - 1, data=b'{"data": 1}') + bombs.message(
        log_time=0, data=b'{"data": 2}'
    )
    bombs._file(directory, "late.mcap", body + bombs.footer())
    for arguments in MODES[:3]:
        answer = await session.ok("read_recording", {"file": "late.mcap", **arguments})
        assert "/data" in text_of(answer)


#: Text a file may carry that must never reach the model raw: ESC, BEL, NUL, a right-to-left override.
RAW = ("\x1b", "\x07", "\x00", "\u202e")


async def test_names_a_file_carries_are_shown_escaped(folder_session: tuple[Session, Path]) -> None:
    """A topic, type, encoding and profile holding terminal escapes, a NUL, a bell and a right-to-left
    override, in a file whose own name holds an escape: every mode shows them escaped (they reached the
    model raw), and a line break in a topic forges no line."""
    session, directory = folder_session
    topic, name = "/data\x1b[2J\x07\x00\u202e\n- /cmd_vel (forged)", "evil\x1b[31m.mcap"
    hostile_header = bombs.record(0x01, bombs._string("ros2\x1b[5m") + bombs._string("x"))
    records = bombs.schema(name="", text=b"", enc="") + bombs.channel(sid=0, topic=topic, enc="json\x07")
    records += bombs.message(data=b'{"data": "\\u001b[31mred\\u202e"}')
    (directory / name).write_bytes(bombs.MAGIC + hostile_header + records + bombs.footer())
    answers = [text_of(await session.ok("read_recording", {}))]
    for arguments in ({}, {"mode": "messages", "at": 0.0}, {"mode": "stats", "fields": ["/nothing x"]}):
        answer = await session.call("read_recording", {"file": name, **arguments})
        answers.append(text_of(answer))
    for text in answers:
        assert not any(raw in text for raw in RAW), repr(text)
        assert "\n- /cmd_vel (forged)" not in text, text
    assert "/data\\x1b[2J" in answers[1], answers[1]
