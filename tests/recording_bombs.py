"""Hostile MCAP files, written record by record (the ``mcap`` writer would refuse to lie): each class of bomb
issue 36 found, small on disk and costly to a reader that believes what the file declares.

Used by ``tests/robot/test_recording_budget.py``, the MCP tests and ``scripts/benchmarks/recording_bombs.py``.
Every writer takes the folder and returns the file's path; counts are parameters so tests stay fast while the
benchmark writes the issue's sizes.
"""

from __future__ import annotations

import json
import struct
from collections.abc import Callable
from pathlib import Path

import zstandard

__all__ = ["BOMBS", "chunk_declaring", "deep_json", "deep_schema", "empty_records", "fanout", "huge_length"]

MAGIC = b"\x89MCAP0\r\n"
SCHEMA_TEXT = b"float64 data\n"


def _string(text: str) -> bytes:
    data = text.encode()
    return struct.pack("<I", len(data)) + data


def record(opcode: int, body: bytes) -> bytes:
    return struct.pack("<BQ", opcode, len(body)) + body


def header() -> bytes:
    return record(0x01, _string("ros2") + _string("bomb"))


def schema(
    sid: int = 1, name: str = "std_msgs/msg/Float64", text: bytes = SCHEMA_TEXT, enc: str = "ros2msg"
) -> bytes:
    return record(
        0x03, struct.pack("<H", sid) + _string(name) + _string(enc) + struct.pack("<I", len(text)) + text
    )


def channel(cid: int = 1, sid: int = 1, topic: str = "/data", enc: str = "cdr") -> bytes:
    return record(0x04, struct.pack("<HH", cid, sid) + _string(topic) + _string(enc) + struct.pack("<I", 0))


def message(cid: int = 1, log_time: int = 1_000_000_000, data: bytes = b"\0\1\0\0" + bytes(8)) -> bytes:
    return record(0x05, struct.pack("<HIQQ", cid, 0, log_time, log_time) + data)


def chunk(records: bytes, declared: int | None = None, start: int = 0, end: int = 2**40) -> bytes:
    data = zstandard.ZstdCompressor().compress(records)
    size = len(records) if declared is None else declared
    body = struct.pack("<QQQI", start, end, size, 0) + _string("zstd") + struct.pack("<Q", len(data)) + data
    return record(0x06, body)


def streamed_chunk(unit: bytes, count: int) -> bytes:
    """A zstd chunk of ``count`` copies of ``unit``, compressed as a stream (never held whole)."""
    compressor = zstandard.ZstdCompressor().compressobj()
    block = unit * max(1, (1 << 20) // len(unit))
    per_block = (1 << 20) // len(unit) or 1
    parts, left = [], count
    while left > 0:
        take = min(left, per_block)
        parts.append(compressor.compress(block if take == per_block else unit * take))
        left -= take
    parts.append(compressor.flush())
    data = b"".join(parts)
    size = len(unit) * count
    body = struct.pack("<QQQI", 0, 2**40, size, 0) + _string("zstd") + struct.pack("<Q", len(data)) + data
    return record(0x06, body)


def footer(summary_start: int = 0) -> bytes:
    return record(0x02, struct.pack("<QQI", summary_start, 0, 0)) + MAGIC


def _file(folder: Path, name: str, body: bytes) -> Path:
    path = folder / name
    path.write_bytes(MAGIC + header() + body)
    return path


def chunk_declaring(folder: Path, declared: int | None = 2 * 10**9) -> Path:
    """A small zstd chunk that declares ``declared`` bytes uncompressed."""
    records = schema() + channel() + b"".join(message(log_time=10**9 + i) for i in range(2000))
    return _file(folder, "declared.mcap", chunk(records, declared) + record(0x0F, bytes(4)) + footer())


def fanout(
    folder: Path,
    chunks: int = 601,
    entries: int = 60_000,
    index_length: int | None = None,
    name: str = "fanout.mcap",
) -> Path:
    """One chunk and one large message index, named by ``chunks`` chunk indexes in the summary."""
    head = MAGIC + header() + schema() + channel()
    body = chunk(b"".join(message(log_time=10**9 + i) for i in range(8)))
    chunk_at = len(head)
    index_at = chunk_at + len(body)
    pairs = b"".join(struct.pack("<QQ", 10**9 + i, 0) for i in range(entries))
    index = record(0x07, struct.pack("<HI", 1, len(pairs)) + pairs)
    data = head + body + index + record(0x0F, bytes(4))
    summary_at = len(data)
    offsets = struct.pack("<HQ", 1, index_at)
    one = record(
        0x08,
        struct.pack("<QQQQ", 10**9, 10**9 + entries, chunk_at, len(body))
        + struct.pack("<I", len(offsets))
        + offsets
        + struct.pack("<Q", len(index) if index_length is None else index_length)
        + _string("zstd")
        + struct.pack("<QQ", len(body), 8 * 31),
    )
    stats = record(0x0B, struct.pack("<QHIIIIQQI", entries, 1, 1, 0, 0, chunks, 10**9, 10**9 + entries, 0))
    summary = schema() + channel() + one * chunks + stats
    path = folder / name
    path.write_bytes(data + summary + footer(summary_at))
    return path


def tiny_messages(folder: Path, count: int = 3_000_000) -> Path:
    """One chunk of ``count`` tiny messages (empty data), a few kilobytes compressed."""
    unit = message(data=b"")
    return _file(folder, "tiny.mcap", schema() + channel() + streamed_chunk(unit, count) + footer())


def empty_records(folder: Path, count: int = 33_000_000) -> Path:
    """One chunk of ``count`` empty records of an unknown opcode."""
    return _file(
        folder, "empty.mcap", schema() + channel() + streamed_chunk(record(0x80, b""), count) + footer()
    )


def huge_length(folder: Path) -> Path:
    """A record declaring 2**62 bytes."""
    return _file(folder, "huge.mcap", schema() + channel() + struct.pack("<BQ", 0x05, 2**62) + bytes(64))


def huge_index(folder: Path) -> Path:
    """A summary whose chunk index names a message index of 2**60 bytes."""
    return fanout(folder, chunks=1, entries=4, index_length=2**60, name="huge-index.mcap")


def truncated(folder: Path) -> Path:
    """A good file cut off in the middle of its chunk."""
    records = schema() + channel() + b"".join(message(log_time=10**9 + i) for i in range(2000))
    full = MAGIC + header() + chunk(records) + record(0x0F, bytes(4)) + footer()
    path = folder / "truncated.mcap"
    path.write_bytes(full[: len(full) // 2])
    return path


def recursive_schema(folder: Path) -> Path:
    """A schema whose type contains itself."""
    text = b"float64 data\npkg/Loop next\n" + b"=" * 80 + b"\nMSG: pkg/Loop\npkg/Loop next\nfloat64 x\n"
    body = schema(name="pkg/msg/Loop", text=text) + channel() + message()
    return _file(folder, "recursive.mcap", body + footer())


def deep_schema(folder: Path, levels: int = 100_000) -> Path:
    """A schema nesting ``levels`` types, each holding the next."""
    parts = [b"pkg/T1 next\n"]
    for level in range(1, levels):
        parts.append(b"=" * 80 + f"\nMSG: pkg/T{level}\npkg/T{level + 1} next\n".encode())
    parts.append(b"=" * 80 + f"\nMSG: pkg/T{levels}\nfloat64 x\n".encode())
    body = schema(name="pkg/msg/T0", text=b"".join(parts)) + channel() + message()
    return _file(folder, "deep.mcap", body + footer())


def deep_json(folder: Path, levels: int = 100_000) -> Path:
    """A JSON message nesting ``levels`` arrays."""
    data = ("[" * levels + "]" * levels).encode()
    body = schema(name="", text=b"", enc="") + channel(sid=0, enc="json") + message(data=data)
    return _file(folder, "deep-json.mcap", body + footer())


def good_json(folder: Path) -> Path:
    """A well-formed recording: one JSON topic, a few messages (the control)."""
    body = schema(name="", text=b"", enc="") + channel(sid=0, enc="json")
    body += b"".join(
        message(log_time=10**9 + i * 10**8, data=json.dumps({"x": i}).encode()) for i in range(5)
    )
    return _file(folder, "good.mcap", body + footer())


def many_schemas(folder: Path, count: int = 200) -> Path:
    """One chunk of ``count`` distinct 1 MiB schemas of zeros (a few kB compressed, 200 MiB held)."""
    compressor = zstandard.ZstdCompressor().compressobj()
    text = bytes(1024 * 1024 - 64)
    parts = [compressor.compress(schema(sid=index + 1, text=text)) for index in range(count)]
    parts.append(compressor.flush())
    data = b"".join(parts)
    size = len(schema(text=text)) * count
    body = struct.pack("<QQQI", 0, 2**40, size, 0) + _string("zstd") + struct.pack("<Q", len(data)) + data
    return _file(folder, "schemas.mcap", record(0x06, body) + footer())


#: A type that takes no bytes on the wire (ROS 1 writes nothing for an empty message).
NOTHING = b"=" * 80 + b"\nMSG: pkg/Nothing\n"


def empty_elements(folder: Path, dialect: str = "ros1", name: str = "pkg/msg/Bomb") -> Path:
    """One message of four bytes: an array of ``2**32 - 16`` elements of a type that takes no bytes (ROS 1's
    empty message; on ROS 2 a type holding only ``uint8[0]``): a decoder believing it makes billions.
    ``name``: the type it claims to be (a known one gets it played by the simulator)."""
    if dialect == "ros1":
        text, data, enc = b"pkg/Nothing[] items\n" + NOTHING, struct.pack("<I", 2**32 - 16), "ros1"
    else:
        text, data, enc = b"pkg/Nothing[] items\n" + NOTHING + b"uint8[0] none\n", b"\0\1\0\0", "cdr"
        data += struct.pack("<I", 2**32 - 16)
    body = schema(name=name, text=text, enc=f"{dialect}msg") + channel(enc=enc) + message(data=data)
    return _file(folder, f"elements-{dialect}.mcap", body + footer())


def free_objects(folder: Path, per_level: int = 1000, levels: int = 3, name: str = "pkg/L0") -> Path:
    """A ROS 1 message of no bytes whose type holds ``per_level`` of the next, ``levels`` deep, down to an
    empty type: ``per_level ** levels`` objects decoded from nothing. ``name``: the type it claims to be."""
    parts = [f"pkg/L1[{per_level}] next\n".encode()]
    for level in range(1, levels):
        parts.append(b"=" * 80 + f"\nMSG: pkg/L{level}\npkg/L{level + 1}[{per_level}] next\n".encode())
    parts.append(b"=" * 80 + f"\nMSG: pkg/L{levels}\n".encode())
    body = (
        schema(name="pkg/L0", text=b"".join(parts), enc="ros1msg") + channel(enc="ros1") + message(data=b"")
    )
    return _file(folder, "free-objects.mcap", body + footer())


#: Every class, by name: the writer and what the refusal names.
BOMBS: dict[str, tuple[Callable[[Path], Path], str]] = {
    "declared 2 GB chunk": (chunk_declaring, "uncompressed"),
    "601 chunk indexes, one message index": (fanout, "same message index"),
    "3 M tiny messages": (tiny_messages, "compression bomb"),
    "33 M empty records": (empty_records, "uncompressed"),
    "huge record length": (huge_length, "declares"),
    "huge index length": (huge_index, "index"),
    "truncated file": (truncated, "cut off"),
    "self-recursive schema": (recursive_schema, "contains itself"),
    "100,000 nesting levels": (deep_schema, "declares"),
    "100,000 nested JSON arrays": (deep_json, "nest"),
    "200 schemas of 1 MiB": (many_schemas, "schemas, channels and chunk indexes would take"),
    "4-byte array of 4 G empty elements": (empty_elements, "takes no bytes"),
    "a billion objects from no bytes": (free_objects, "objects from no bytes"),
}
