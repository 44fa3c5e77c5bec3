"""Recordings are read within a budget: every class of hostile MCAP file issue 36 found is refused, quickly,
with a sentence naming what is wrong, by the reader ``read_recording`` uses; a good file is still read.

The files are written by ``tests/recording_bombs.py``; counts are kept small where the class does not depend
on them (the benchmark, ``scripts/benchmarks/recording_bombs.py``, writes the issue's sizes and measures RSS).
"""

from __future__ import annotations

import struct
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

import recording_bombs as bombs
from rosbridge_mcp_server.mcapfile import Budget, McapFile, Schema, schema_problem
from rosbridge_mcp_server.robot.recording.reading import (
    NotARecording,
    decoded_messages,
    read_budget,
    summarize_recording,
)

#: Each class, small: (writer, words the refusal must hold).
SMALL = {
    "declared 2 GB chunk": (bombs.chunk_declaring, "declares 2000000000 bytes uncompressed"),
    "chunk indexes sharing a message index": (
        lambda d: bombs.fanout(d, chunks=40, entries=2000),
        "name the same message index",
    ),
    "tiny messages": (lambda d: bombs.tiny_messages(d, 400_000), "compression bomb"),
    "empty records over the budget": (bombs.empty_records, "283 MiB, over this server's budget"),
    "empty records under the budget": (lambda d: bombs.empty_records(d, 2_000_000), "compression bomb"),
    "huge record length": (bombs.huge_length, "declares 4611686018427387904 bytes, but only 64 are left"),
    "huge index length": (bombs.huge_index, "points past the end of the file"),
    "truncated file": (bombs.truncated, "cut off"),
    "100,000 nesting levels": (bombs.deep_schema, "more than any real one"),
    "200 schemas of 1 MiB": (bombs.many_schemas, "chunk indexes would take over 32 MiB"),
}


# A guard, not a measurement (the benchmark's rows 18a-k hold each class to 2 s): unbounded, these files cost
# 30-86 s of CPU each.
@pytest.mark.timeout(30)
@pytest.mark.parametrize("kind", list(SMALL))
def test_each_hostile_file_is_refused_quickly_with_what_is_wrong(kind: str, tmp_path: Path) -> None:
    """The summary and the messages of each bomb: a NotARecording naming the problem, reading bounded work."""
    write, words = SMALL[kind]
    path = write(tmp_path)
    with pytest.raises(NotARecording) as summarised:
        summarize_recording(path)
    assert words in str(summarised.value)
    assert str(summarised.value).startswith(path.name)
    if "index" not in kind:  # the messages are read from the data section, not through the index
        with pytest.raises(NotARecording) as decoded:
            list(decoded_messages(path))
        assert str(decoded.value).startswith(path.name)


def test_a_schema_containing_itself_or_nesting_too_deep_is_refused_before_decoding(tmp_path: Path) -> None:
    """A type holding itself, or 5,000 levels of types, is named; no decoder recursion is reached."""
    for path, words in (
        (bombs.recursive_schema(tmp_path), "has a type that contains itself (pkg/Loop)"),
        (bombs.deep_schema(tmp_path, levels=5000), "nests types over 64 levels deep"),
    ):
        summary = summarize_recording(path)  # the summary reads no message: it answers
        assert summary.topics[0].topic == "/data"
        with pytest.raises(NotARecording, match="cannot be read") as caught:
            list(decoded_messages(path))
        assert words in str(caught.value)


def test_a_json_message_nesting_too_deep_is_refused(tmp_path: Path) -> None:
    path = bombs.deep_json(tmp_path)
    with pytest.raises(NotARecording, match="nests over 64 levels deep"):
        list(decoded_messages(path))


def test_a_good_file_written_by_hand_is_still_read(tmp_path: Path) -> None:
    """The control: the same hand-written records, well formed, read as five JSON messages."""
    path = bombs.good_json(tmp_path)
    summary = summarize_recording(path)
    assert summary.messages == 5
    assert [m["x"] for _, _, m in decoded_messages(path)] == [0, 1, 2, 3, 4]


def test_the_time_budget_stops_a_long_read(tmp_path: Path) -> None:
    """A read over its seconds stops with a sentence saying so (a budget of 0 s, so it is over at once)."""
    path = bombs.tiny_messages(tmp_path, 40_000)  # under the record floor: only the time stops it
    with pytest.raises(NotARecording, match="took over 0 s, this server's time budget"):
        list(decoded_messages(path, budget=Budget(read_budget().memory, 0.0)))


def test_a_message_index_over_the_memory_budget_is_refused(tmp_path: Path) -> None:
    """The index is held to the budget before it is read (a 78 KiB index, a 64 KiB budget)."""
    path = bombs.fanout(tmp_path, chunks=1, entries=5000)
    with pytest.raises(NotARecording, match=r"declares 78.1 KiB, more than any real one \(16 KiB"):
        summarize_recording(path, Budget(64 * 1024, 10.0))


def test_a_chunk_that_decompresses_to_more_than_it_declares_is_refused(tmp_path: Path) -> None:
    records = bombs.schema() + bombs.channel() + bombs.message() * 50
    path = tmp_path / "liar.mcap"
    path.write_bytes(bombs.MAGIC + bombs.header() + bombs.chunk(records, declared=100) + bombs.footer())
    with pytest.raises(NotARecording, match="decompresses to more than the 100 bytes it declares"):
        list(decoded_messages(path))


def test_schema_problem_reads_ros1_and_ros2_texts_of_real_types() -> None:
    """Real nested types (a Header, a relative name, a bounded string) are not mistaken for a cycle."""
    text = (
        b"std_msgs/Header header\nPoint[] points\nstring<=10 name\n"
        + b"=" * 80
        + b"\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
        + b"=" * 80
        + b"\nMSG: pkg/Point\nfloat64 x\nint32 CONSTANT=3\n"
    )
    assert schema_problem(Schema(1, "pkg/msg/Cloud", "ros2msg", text)) is None


def test_the_reader_reports_where_a_file_is_cut_off_and_keeps_what_came_before(tmp_path: Path) -> None:
    """A killed recorder's file (no summary, cut inside a chunk): what came before is summarised, and the
    summary says where it breaks off."""
    definitions = bombs.schema() + bombs.channel()
    first = bombs.chunk(definitions + b"".join(bombs.message(log_time=10**9 + i) for i in range(3)))
    second = bombs.chunk(b"".join(bombs.message(log_time=2 * 10**9 + i) for i in range(3)))
    path = tmp_path / "killed.mcap"
    path.write_bytes(bombs.MAGIC + bombs.header() + first + second[: len(second) // 2])
    summary = summarize_recording(path)
    assert summary.messages == 3
    assert "cut off" in summary.damaged


def test_the_file_reader_imports_nothing_of_ours() -> None:
    """So the simulated robot may use it (tests/safety/test_layering.py holds the rule too)."""
    package = Path(sys.modules[McapFile.__module__].__file__ or "").parent
    for module in package.glob("*.py"):
        imports = [
            ln for ln in module.read_text().splitlines() if "rosbridge_mcp_server" in ln and "import" in ln
        ]
        assert all("rosbridge_mcp_server.mcapfile" in ln for ln in imports), (module.name, imports)


def test_an_abandoned_budget_stops_the_reading_thread_at_its_next_check(tmp_path: Path) -> None:
    """A cancelled read_recording marks its budget abandoned: the thread reading the file stops there."""
    path = bombs.tiny_messages(tmp_path, 40_000)
    budget = read_budget()
    reading = decoded_messages(path, budget=budget)
    budget.abandoned = True
    with pytest.raises(NotARecording, match="the call was cancelled, so reading stopped"):
        list(reading)


def test_chunk_indexes_naming_overlapping_message_indexes_are_refused(tmp_path: Path) -> None:
    """The fan-out shifted: chunk indexes pointing a few bytes apart into one message index (each would read
    the rest of it again) are refused before any is read."""
    path = bombs.fanout(tmp_path, chunks=1, entries=200)
    data = path.read_bytes()
    at = data.rindex(b"\x08", 0, data.rindex(b"\x0b"))  # the one chunk index record
    length = struct.unpack_from("<Q", data, at + 1)[0]
    one = data[at : at + 9 + length]
    offset_at = 9 + 32 + 4 + 2  # the message index offset in the record
    (index_at,) = struct.unpack_from("<Q", one, offset_at)
    shifted = bytearray(one)
    struct.pack_into("<Q", shifted, offset_at, index_at + 16)
    path.write_bytes(data[:at] + one + bytes(shifted) + data[at + len(one) :])
    with pytest.raises(NotARecording, match="name the same message index"):
        summarize_recording(path)


def test_a_message_too_large_to_decode_within_the_budget_is_refused_unread(tmp_path: Path) -> None:
    """A 20 MB JSON message (a few kB compressed) would take ~320 MB as objects: refused before it is read."""
    body = bombs.schema(name="", text=b"", enc="") + bombs.channel(sid=0, enc="json")
    big = bombs.message(data=b"[" + b" " * (20 * 1024 * 1024) + b"]")
    path = tmp_path / "big.mcap"
    path.write_bytes(bombs.MAGIC + bombs.header() + bombs.chunk(body + big) + bombs.footer())
    assert summarize_recording(path).messages == 1
    with pytest.raises(NotARecording, match=r"declares 20971522 bytes; decoding it would take about 320 MiB"):
        list(decoded_messages(path))


def test_a_summary_over_the_budget_falls_back_to_the_files_statistics(tmp_path: Path) -> None:
    """An index too large to time every message (here: a small budget) still gives counts and mean rates,
    saying what is not known."""
    path = bombs.fanout(tmp_path, chunks=1, entries=4000)
    summary = summarize_recording(path, Budget(256 * 1024, 10.0))
    assert summary.topics[0].timing.count == 0  # the writer's statistics declare no per-channel count
    assert summary.messages == 4000
    assert "gaps are not known" in summary.note
    assert "over this server's budget of 256 KiB" in summary.note


def test_a_rosbag2_mcap_written_by_rosbags_is_read(tmp_path: Path) -> None:
    """A foreign writer's file (rosbags' rosbag2 MCAP, nested ROS 2 types) is read whole: the bounded reader
    and the schema check take real files as they are."""
    import numpy
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    odometry, tf = store.types["nav_msgs/msg/Odometry"], store.types["tf2_msgs/msg/TFMessage"]
    header = store.types["std_msgs/msg/Header"](
        stamp=store.types["builtin_interfaces/msg/Time"](1, 2), frame_id="odom"
    )
    point = store.types["geometry_msgs/msg/Point"](x=1.5, y=2.5, z=0.0)
    quat = store.types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
    pose = store.types["geometry_msgs/msg/Pose"](position=point, orientation=quat)
    vector = store.types["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
    twist = store.types["geometry_msgs/msg/Twist"](linear=vector, angular=vector)
    covariance = numpy.zeros(36)
    odom = odometry(
        header=header,
        child_frame_id="base_link",
        pose=store.types["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=covariance),
        twist=store.types["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=covariance),
    )
    folder = tmp_path / "bag"
    with Writer(folder, version=8, storage_plugin=StoragePlugin.MCAP) as writer:
        odom_link = writer.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=store)
        tf_link = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=store)
        for index in range(20):
            writer.write(odom_link, 10**9 + index * 10**8, store.serialize_cdr(odom, "nav_msgs/msg/Odometry"))
            writer.write(
                tf_link, 10**9 + index * 10**8, store.serialize_cdr(tf(transforms=[]), tf.__msgtype__)
            )
    [path] = folder.glob("*.mcap")
    summary = summarize_recording(path)
    assert {t.topic: t.timing.count for t in summary.topics} == {"/odom": 20, "/tf": 20}
    decoded = [m for topic, _, m in decoded_messages(path, ["/odom"])]
    assert len(decoded) == 20
    assert decoded[0]["pose"]["pose"]["position"] == {"x": 1.5, "y": 2.5, "z": 0.0}


@pytest.mark.timeout(30)
@pytest.mark.parametrize(
    ("write", "words"),
    [
        (bombs.empty_elements, "an array of pkg/Nothing, a type that takes no bytes"),
        (lambda d: bombs.empty_elements(d, "ros2"), "an array of pkg/Nothing, a type that takes no bytes"),
        (bombs.free_objects, "objects from 0 bytes"),
    ],
)
def test_a_schema_making_objects_from_no_bytes_is_refused_before_decoding(
    write: Callable[[Path], Path], words: str, tmp_path: Path
) -> None:
    """A few bytes that a decoder believing the schema turns into billions of objects (2.7 GB and 25 s before
    a 3 GB limit stopped it): the schema is named, nothing decoded."""
    path = write(tmp_path)
    assert summarize_recording(path).topics[0].topic == "/data"
    with pytest.raises(NotARecording, match="cannot be read") as caught:
        list(decoded_messages(path))
    assert words in str(caught.value)


def test_a_message_whose_schema_decodes_it_into_many_objects_is_held_to_the_budget(tmp_path: Path) -> None:
    """256 K one-byte elements, each decoded into two objects, under a 16 MiB budget: refused by what its
    schema makes of them, unread; the same bytes as ``uint8[]`` (one object) are read."""
    text = b"pkg/Flag[] flags\n" + bombs.NOTHING.replace(b"Nothing", b"Flag") + b"bool on\n"
    count = 256 * 1024
    data = struct.pack("<I", count) + bytes(count)
    for name, typed in (("flags", text), ("bytes", b"uint8[] flags\n")):
        body = bombs.schema(name="pkg/Flags", text=typed, enc="ros1msg") + bombs.channel(enc="ros1")
        bombs._file(tmp_path, f"{name}.mcap", body + bombs.message(data=data) + bombs.footer())
    with pytest.raises(NotARecording, match="decoded by its schema") as caught:
        list(decoded_messages(tmp_path / "flags.mcap", budget=Budget(16 * 1024 * 1024, 30)))
    assert "over this server's budget of 16 MiB" in str(caught.value)
    [(_, _, message)] = list(decoded_messages(tmp_path / "bytes.mcap", budget=Budget(16 * 1024 * 1024, 30)))
    assert len(message["flags"]) > count
