"""What an MCAP file holds, as this reader keeps it, and what one call may spend reading it. Pure."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

__all__ = [
    "INDEX_ENTRY_COST",
    "MAGIC",
    "MAX_NESTING",
    "MAX_SCHEMA",
    "MAX_STRING",
    "RECORDS_FLOOR",
    "RECORDS_PER_COMPRESSED_BYTE",
    "RECORD_COST",
    "Budget",
    "Channel",
    "ChunkIndex",
    "CutOff",
    "OverBudget",
    "RecordingProblem",
    "Schema",
    "Statistics",
    "Summary",
    "byte_size",
]

MAGIC = b"\x89MCAP0\r\n"
#: A chunk may yield this many records per byte of its compressed data (beyond RECORDS_FLOOR). A recorder's
#: records differ in time and sequence at least, so real data stays far below it; a bomb does not.
RECORDS_PER_COMPRESSED_BYTE = 8
RECORDS_FLOOR = 50_000
#: The longest schema text, and the longest string of a header, channel or metadata record, read.
MAX_SCHEMA = 1024 * 1024
MAX_STRING = 4096
#: How deep a message type may nest (a real ROS type nests a handful of levels).
MAX_NESTING = 64
#: Bytes of a message index entry in memory (its log time) while a summary is made.
INDEX_ENTRY_COST = 96
#: Bytes a schema, channel or chunk index costs in memory besides its data (Python objects).
RECORD_COST = 512


class RecordingProblem(ValueError):
    """The file cannot be read within the budget, or is malformed; ``str()`` says what and where."""


class CutOff(RecordingProblem):
    """The file ends inside a record (a recorder killed while writing, or a file cut short)."""


class OverBudget(RecordingProblem):
    """Reading it would hold more memory than one call's budget (the file may be fine, only large)."""


def byte_size(count: int) -> str:
    """``256 MiB``, ``1.9 GiB``: a byte count for a person."""
    size = float(count)
    for unit in ("bytes", "KiB", "MiB", "GiB"):
        if size < 1024:
            return f"{count} bytes" if unit == "bytes" else f"{size:.3g} {unit}"
        size /= 1024
    return f"{size:.3g} TiB"


@dataclass
class Budget:
    """What one call may spend reading a recording: bytes held at once and seconds."""

    memory: int
    seconds: float
    started: float = field(default_factory=time.monotonic)
    #: Set when the call was cancelled: the reading (on a thread of its own) stops at its next check.
    abandoned: bool = False

    def check_time(self) -> None:
        if self.abandoned:
            raise RecordingProblem("the call was cancelled, so reading stopped")
        if time.monotonic() - self.started > self.seconds:
            raise RecordingProblem(
                f"reading it took over {self.seconds:g} s, this server's time budget for one call; it was "
                "stopped there (ask for fewer topics, a shorter window, or a smaller file)"
            )

    def check_bytes(self, what: str, needed: int) -> None:
        if needed > self.memory:
            raise OverBudget(
                f"{what} about {byte_size(needed)}, over this server's budget of "
                f"{byte_size(self.memory)} for one call, so it was not read"
            )


@dataclass(frozen=True)
class Schema:
    id: int
    name: str
    encoding: str
    data: bytes


@dataclass(frozen=True)
class Channel:
    id: int
    schema_id: int
    topic: str
    message_encoding: str


@dataclass(frozen=True)
class ChunkIndex:
    start: int
    end: int
    offset: int
    length: int
    index_offsets: dict[int, int]
    index_length: int


@dataclass(frozen=True)
class Statistics:
    message_count: int
    start: int
    end: int
    #: Messages per channel id, as the file declares them.
    channel_counts: dict[int, int] = field(default_factory=dict)


@dataclass
class Summary:
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    chunk_indexes: list[ChunkIndex] = field(default_factory=list)
    statistics: Statistics | None = None
