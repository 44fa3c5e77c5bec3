"""An MCAP file read within a budget: whoever wrote it, whatever it declares.

A recording is a file anyone may put in the recordings folder (or a hostile robot may have filled), and MCAP
records carry their own lengths, counts and sizes: a 61 kB file can declare a 2 GB chunk, one message index
can be named by 600 chunk indexes, an 8.9 kB chunk can decompress to millions of tiny records. The ``mcap``
package believes what a file declares; this module does not. It reads the records itself and holds every
declared size, count and offset to the file's real size and to a :class:`Budget` (the memory one call may
hold, the same as a picture's, and the seconds it may take) before it reads, allocates or decompresses:

* each record's length fits in what is left of the file (or of its chunk): a cut-off file is named as such;
* a chunk declares at most the memory budget uncompressed, is decompressed as a stream (never held whole)
  and may not yield more than it declared, nor more records than :data:`RECORDS_PER_COMPRESSED_BYTE` per
  byte of compressed data (beyond :data:`RECORDS_FLOOR`): the work a chunk costs stays in proportion to the
  file;
* every chunk index points inside the file, and no two at the same message index (the fan-out); the
  message times kept at once fit in the memory budget;
* a message's data, a schema's text and a metadata string are capped before they are read;
* a ``ros2msg``/``ros1msg`` schema names no type that contains itself and nests at most :data:`MAX_NESTING`
  levels (:func:`schema_problem`), so no decoder recurses without end.

Every refusal is a :class:`RecordingProblem` whose text names what is wrong and where. Pure file reading: it
imports nothing of ours, so the simulated robot's ``--play`` holds files to the same rules.
"""

from __future__ import annotations

import io
import re
import struct
import time
from array import array
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import IO, Any

__all__ = [
    "INDEX_ENTRY_COST",
    "MAGIC",
    "MAX_NESTING",
    "Budget",
    "Channel",
    "ChunkIndex",
    "CutOff",
    "McapFile",
    "RecordingProblem",
    "Schema",
    "Statistics",
    "Summary",
    "byte_size",
    "schema_problem",
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
INDEX_ENTRY_COST = 64
_BLOCK = 1024 * 1024
_HEADER, _FOOTER, _SCHEMA, _CHANNEL, _MESSAGE, _CHUNK, _MESSAGE_INDEX, _CHUNK_INDEX = range(1, 9)
_STATISTICS, _DATA_END = 0x0B, 0x0F
_FOOTER_SIZE = 1 + 8 + 20


class RecordingProblem(ValueError):
    """The file cannot be read within the budget, or is malformed; ``str()`` says what and where."""


class CutOff(RecordingProblem):
    """The file ends inside a record (a recorder killed while writing, or a file cut short)."""


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

    def check_time(self) -> None:
        if time.monotonic() - self.started > self.seconds:
            raise RecordingProblem(
                f"reading it took over {self.seconds:g} s, this server's time budget for one call; it was "
                "stopped there (ask for fewer topics, a shorter window, or a smaller file)"
            )

    def check_bytes(self, what: str, needed: int) -> None:
        if needed > self.memory:
            raise RecordingProblem(
                f"{what}: about {byte_size(needed)}, over this server's budget of "
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


@dataclass
class Summary:
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    chunk_indexes: list[ChunkIndex] = field(default_factory=list)
    statistics: Statistics | None = None


class _Body:
    """One record's body, read field by field; running past its end is a malformed record."""

    def __init__(self, data: bytes, what: str) -> None:
        self.data, self.pos, self.what = data, 0, what

    def take(self, size: int) -> bytes:
        if size < 0 or self.pos + size > len(self.data):
            raise RecordingProblem(f"{self.what} is malformed: a field runs past the record's end")
        out = self.data[self.pos : self.pos + size]
        self.pos += size
        return out

    def number(self, fmt: str) -> int:
        (value,) = struct.unpack("<" + fmt, self.take(struct.calcsize(fmt)))
        return int(value)

    def string(self, limit: int = MAX_STRING) -> str:
        size = self.number("I")
        if size > limit:
            raise RecordingProblem(f"{self.what} holds a string of {size} bytes, over the {limit} read")
        return self.take(size).decode("utf-8", "replace")

    def pairs(self, key: str, value: str) -> dict[int, int]:
        size = self.number("I")
        end = self.pos + size
        if end > len(self.data):
            raise RecordingProblem(f"{self.what} is malformed: a map runs past the record's end")
        out: dict[int, int] = {}
        while self.pos < end:
            name = self.number(key)  # read before the value: an assignment evaluates its right side first
            out[name] = self.number(value)
        return out


class _Source:
    """Bytes read in order from a file region or a decompressed chunk, with a position and an end."""

    def __init__(self, blocks: Iterator[bytes], end: int, base: int = 0) -> None:
        self._blocks, self._buffer, self._at, self.pos, self.end = blocks, b"", 0, base, end

    def read(self, size: int, what: str) -> bytes:
        at = self._at
        if at + size <= len(self._buffer):  # the common case: within the block at hand
            self._at = at + size
            self.pos += size
            return self._buffer[at : at + size]
        out = bytearray()
        while len(out) < size:
            if self._at >= len(self._buffer):
                self._buffer, self._at = next(self._blocks, b""), 0
                if not self._buffer:
                    raise CutOff(f"{what} is cut off: the data ends inside it")
            piece = self._buffer[self._at : self._at + size - len(out)]
            self._at += len(piece)
            out += piece
        self.pos += size
        return bytes(out)


class McapFile:
    """One open MCAP file: its header, summary and records, read within ``budget``."""

    def __init__(self, handle: IO[bytes], size: int, budget: Budget, name: str = "the file") -> None:
        self.handle, self.size, self.budget, self.name = handle, size, budget, name
        #: Schemas and channels met while reading the data section (a file without a summary has only these).
        self.schemas: dict[int, Schema] = {}
        self.channels: dict[int, Channel] = {}
        handle.seek(0)
        head = handle.read(len(MAGIC))
        if head != MAGIC:
            raise RecordingProblem(_not_mcap(head, name))
        self.profile = self.library = ""

    # --- the summary ------------------------------------------------------------------------------------

    def summary(self) -> Summary | None:
        """The summary section, or ``None`` when the file has none (or its footer is cut off)."""
        if self.size < len(MAGIC) * 2 + _FOOTER_SIZE:
            return None
        self.handle.seek(self.size - len(MAGIC) - _FOOTER_SIZE)
        tail = self.handle.read(_FOOTER_SIZE + len(MAGIC))
        if tail[-len(MAGIC) :] != MAGIC or tail[0] != _FOOTER:
            return None
        start = struct.unpack_from("<Q", tail, 9)[0]
        footer_at = self.size - len(MAGIC) - _FOOTER_SIZE
        if start == 0:
            return None
        if not len(MAGIC) <= start <= footer_at:
            raise RecordingProblem(
                f"{self.name}'s footer puts its summary at byte {start}, outside the file ({self.size} bytes)"
            )
        found = Summary()
        kinds = frozenset({_SCHEMA, _CHANNEL, _CHUNK_INDEX, _STATISTICS})
        for opcode, body, where in self._records(start, footer_at, "the summary section", kinds):
            self._summary_record(found, opcode, body, where)
        return found

    def _summary_record(self, found: Summary, opcode: int, body: _Body | None, where: int) -> None:
        if body is None:
            return
        if opcode in (_SCHEMA, _CHANNEL):
            self._definition(opcode, body)
            found.schemas.update(self.schemas)
            found.channels.update(self.channels)
        elif opcode == _CHUNK_INDEX:
            found.chunk_indexes.append(self._chunk_index(body, where))
        elif opcode == _STATISTICS:
            count = body.number("Q")
            body.take(2 + 4 + 4 + 4 + 4)
            found.statistics = Statistics(count, body.number("Q"), body.number("Q"))

    def _chunk_index(self, body: _Body, where: int) -> ChunkIndex:
        start, end, offset, length = body.number("Q"), body.number("Q"), body.number("Q"), body.number("Q")
        offsets = body.pairs("H", "Q")
        index = ChunkIndex(start, end, offset, length, offsets, body.number("Q"))
        first = min(offsets.values(), default=0)
        if offset + length > self.size or (offsets and first + index.index_length > self.size):
            raise RecordingProblem(
                f"{self.name}: the chunk index at byte {where} points past the end of the file "
                f"({self.size} bytes); the file is damaged or cut off"
            )
        return index

    def message_times(self, summary: Summary) -> dict[int, array[int]]:
        """Each channel's message log times from the message indexes, read without decompressing a chunk."""
        times: dict[int, array[int]] = {cid: array("q") for cid in summary.channels}
        seen: dict[int, int] = {}
        entries = 0
        for chunk in summary.chunk_indexes:
            if not chunk.index_offsets:
                continue
            begin = min(chunk.index_offsets.values())
            end = begin + chunk.index_length
            if begin < chunk.offset + chunk.length or end > self.size:
                raise RecordingProblem(
                    f"{self.name}: a chunk index puts its message index at bytes {begin}-{end}, not after "
                    f"its chunk and inside the file ({self.size} bytes); the index is malformed"
                )
            if begin in seen:
                raise RecordingProblem(
                    f"{self.name}: the chunk indexes at bytes {seen[begin]} and {chunk.offset} name the same "
                    f"message index (byte {begin}); each chunk has its own, so the index is malformed"
                )
            seen[begin] = chunk.offset
            for opcode, body, _ in self._records(begin, end, "a message index", frozenset({_MESSAGE_INDEX})):
                if opcode != _MESSAGE_INDEX or body is None:
                    continue
                channel = body.number("H")
                data = body.take(body.number("I"))
                entries += len(data) // 16
                self.budget.check_bytes(
                    f"{self.name}'s indexes list over {entries} messages; their times would take",
                    entries * INDEX_ENTRY_COST,
                )
                pairs = array("q")
                pairs.frombytes(data[: len(data) // 16 * 16])
                times.setdefault(channel, array("q")).extend(pairs[0::2])
            self.budget.check_time()
        return times

    # --- the data section -------------------------------------------------------------------------------

    def header(self) -> tuple[str, str]:
        """The header's profile and library (``ros2``, ``rosbag2 ...``), or empty ones."""
        for opcode, body, _ in self._records(len(MAGIC), self.size, "the header", frozenset({_HEADER})):
            if opcode == _HEADER and body is not None:
                self.profile, self.library = body.string(), body.string()
            break
        return self.profile, self.library

    def messages(
        self,
        wanted: set[int] | None = None,
        start: int | None = None,
        end: int | None = None,
        summary: Summary | None = None,
    ) -> Iterator[tuple[Channel, int, bytes | None]]:
        """(channel, log time, data) of every message in file order; ``data`` is ``None`` for a channel not
        ``wanted`` or a time outside [start, end) (its bytes are not read). With the file's ``summary``, a
        chunk wholly outside the time is not decompressed."""
        if summary is not None:
            self.schemas.update(summary.schemas)
            self.channels.update(summary.channels)
        window = (start, end) if summary is not None else (None, None)
        kinds = frozenset({_HEADER, _SCHEMA, _CHANNEL, _MESSAGE, _CHUNK})
        for opcode, body, where in self._records(len(MAGIC), self.size, "the data section", kinds):
            if opcode in (_FOOTER, _DATA_END):
                return
            if opcode == _CHUNK:
                yield from self._chunk(body, where, wanted, (start, end), window)
            elif opcode == _MESSAGE:
                yield self._message(body, where, wanted, start, end)
            elif opcode == _HEADER and body is not None:
                self.profile, self.library = body.string(), body.string()
            elif opcode in (_SCHEMA, _CHANNEL) and body is not None:
                self._definition(opcode, body)

    # --- records ----------------------------------------------------------------------------------------

    def _file_blocks(self, begin: int, end: int) -> Iterator[bytes]:
        self.handle.seek(begin)
        left = end - begin
        while left > 0:
            block = self.handle.read(min(_BLOCK, left))
            if not block:
                return
            left -= len(block)
            yield block

    def _records(
        self,
        begin: int,
        end: int,
        region: str,
        bodies: frozenset[int],
        source: _Source | None = None,
    ) -> Iterator[tuple[int, Any, int]]:
        """(opcode, body, offset) of each record in [begin, end). A body is read only for the opcodes in
        ``bodies``; a message's is left to the caller (``_message``) as (source, length), a chunk's is the
        source and length of its records (read by ``_chunk``); every other record is skipped unread."""
        src = source or _Source(self._file_blocks(begin, end), end, begin)
        count = 0
        while src.pos < src.end:
            where = src.pos
            if src.end - where < 9:
                raise CutOff(
                    f"{self.name}: {region} is cut off at byte {where} (a record's header does not fit)"
                )
            opcode, length = struct.unpack("<BQ", src.read(9, f"the record at byte {where}"))
            if length > src.end - src.pos:
                raise CutOff(
                    f"{self.name}: the record at byte {where} of {region} declares {length} bytes, but only "
                    f"{src.end - src.pos} are left; the file is cut off or damaged"
                )
            count += 1
            if count % 4096 == 0:
                self.budget.check_time()
            if opcode not in bodies:
                _skip(src, length, where)
                yield opcode, None, where
            elif opcode in (_MESSAGE, _CHUNK):
                yield opcode, (src, length), where
            else:
                limit = MAX_SCHEMA + 64 if opcode == _SCHEMA else self.budget.memory // 4
                if length > limit:
                    raise RecordingProblem(
                        f"{self.name}: the record at byte {where} declares {byte_size(length)}, more than "
                        f"any real one ({byte_size(limit)} are read at most)"
                    )
                what = f"{self.name}: the record at byte {where}"
                yield opcode, _Body(src.read(length, what), what), where

    def _message(
        self, body: Any, where: int, wanted: set[int] | None, start: int | None, stop: int | None
    ) -> tuple[Channel, int, bytes | None]:
        src, length = body
        if length < 22:
            raise RecordingProblem(
                f"{self.name}: the message at byte {where} is shorter than a message record"
            )
        channel_id, _, log_time, _ = struct.unpack("<HIQQ", src.read(22, f"the message at byte {where}"))
        channel = self.channels.get(channel_id) or Channel(channel_id, 0, f"(channel {channel_id})", "")
        keep = (wanted is None or channel_id in wanted) and (start is None or log_time >= start)
        keep = keep and (stop is None or log_time < stop)
        if not keep:
            _skip(src, length - 22, where)
            return channel, log_time, None
        if (length - 22) * 4 > self.budget.memory:
            self.budget.check_bytes(
                f"the message on {channel.topic[:100]} at byte {where} declares {length - 22} bytes; "
                "decoding it would take",
                (length - 22) * 4,
            )
        return channel, log_time, src.read(length - 22, f"the message at byte {where}")

    def _chunk(
        self,
        body: tuple[_Source, int],
        where: int,
        wanted: set[int] | None,
        times: tuple[int | None, int | None],
        window: tuple[int | None, int | None],
    ) -> Iterator[tuple[Channel, int, bytes | None]]:
        src, length = body
        what = f"the chunk at byte {where}"
        head = _Body(src.read(min(length, 8 * 3 + 4 + 4 + 64 + 8), what), f"{self.name}: {what}")
        first, last, size = head.number("Q"), head.number("Q"), head.number("Q")
        head.number("I")
        compression = head.string(64)
        data_length = head.number("Q")
        left_over = head.data[head.pos :]
        if data_length != length - head.pos:
            raise RecordingProblem(
                f"{self.name}: {what} declares {data_length} bytes of records in a {length}-byte record; "
                "the file is damaged"
            )
        self.budget.check_bytes(f"{self.name}: {what} declares {size} bytes uncompressed", size)
        self.budget.check_bytes(f"{self.name}: {what} holds {data_length} compressed bytes", data_length * 2)
        if (window[0] is not None and last < window[0]) or (window[1] is not None and first >= window[1]):
            _skip(src, data_length - len(left_over), where)
            return
        compressed = left_over + src.read(data_length - len(left_over), what)
        yield from self._chunk_messages(
            compressed, compression=compression, size=size, what=what, wanted=wanted, times=times
        )

    def _chunk_messages(
        self,
        compressed: bytes,
        *,
        compression: str,
        size: int,
        what: str,
        wanted: set[int] | None,
        times: tuple[int | None, int | None],
    ) -> Iterator[tuple[Channel, int, bytes | None]]:
        limit = max(RECORDS_FLOOR, len(compressed) * RECORDS_PER_COMPRESSED_BYTE)
        inner = _Source(_decompressed(compressed, compression, size, f"{self.name}: {what}"), size)
        kinds = frozenset({_SCHEMA, _CHANNEL, _MESSAGE})
        for count, (opcode, body, offset) in enumerate(self._records(0, size, what, kinds, inner), 1):
            if count > limit:
                raise RecordingProblem(
                    f"{self.name}: {what} unpacks {len(compressed)} compressed bytes into over {limit} "
                    "records, far more than any recorder writes (a compression bomb); it was not read further"
                )
            if opcode == _MESSAGE:
                yield self._message(body, offset, wanted, *times)
            elif opcode in (_SCHEMA, _CHANNEL) and body is not None:
                self._definition(opcode, body)

    def _definition(self, opcode: int, body: _Body) -> None:
        if opcode == _SCHEMA:
            sid = body.number("H")
            name, encoding = body.string(), body.string()
            self.schemas[sid] = Schema(sid, name, encoding, body.take(body.number("I")))
        else:
            cid, sid = body.number("H"), body.number("H")
            self.channels[cid] = Channel(cid, sid, body.string(), body.string())


def _skip(src: _Source, length: int, where: int) -> None:
    left = length
    while left > 0:
        step = min(left, _BLOCK)
        src.read(step, f"the record at byte {where}")
        left -= step


def _decompressed(data: bytes, compression: str, size: int, what: str) -> Iterator[bytes]:
    """The chunk's records, a block at a time, never more than ``size`` (what the chunk declares)."""
    produced = 0
    if compression == "":
        blocks: Iterator[bytes] = iter([data[i : i + _BLOCK] for i in range(0, len(data), _BLOCK)])
    elif compression == "zstd":
        blocks = _zstd_blocks(data, what)
    elif compression == "lz4":
        blocks = _lz4_blocks(data, what)
    else:
        raise RecordingProblem(
            f"{what} is compressed with {compression[:20]!r}, which this reader cannot read"
        )
    for block in blocks:
        produced += len(block)
        if produced > size:
            raise RecordingProblem(f"{what} decompresses to more than the {size} bytes it declares")
        yield block


def _zstd_blocks(data: bytes, what: str) -> Iterator[bytes]:
    import zstandard  # noqa: PLC0415

    reader = zstandard.ZstdDecompressor().stream_reader(io.BytesIO(data), read_across_frames=True)
    while True:
        try:
            block = reader.read(_BLOCK)
        except zstandard.ZstdError as exc:
            raise RecordingProblem(f"{what} is not valid zstd data ({exc})") from None
        if not block:
            return
        yield block


def _lz4_blocks(data: bytes, what: str) -> Iterator[bytes]:
    import lz4.frame  # type: ignore[import-untyped]  # noqa: PLC0415

    decompressor = lz4.frame.LZ4FrameDecompressor()
    pending = data
    while True:
        try:
            block = decompressor.decompress(pending, max_length=_BLOCK)
        except RuntimeError as exc:
            raise RecordingProblem(f"{what} is not valid lz4 data ({exc})") from None
        pending = b""
        if block:
            yield block
        if decompressor.eof or (not block and decompressor.needs_input):
            return


def _not_mcap(head: bytes, name: str) -> str:
    what = "an empty file" if not head else f"a file starting with {head[:8]!r}"
    if head.startswith(b"#ROSBAG"):
        what = "a ROS 1 bag (.bag), not MCAP; convert it with `mcap convert`"
    elif head.startswith(b"SQLite format"):
        what = "a SQLite file (a ROS 2 .db3 bag?), not MCAP"
    return f"{name} is not an MCAP recording: it is {what} (MCAP starts with \\x89MCAP0)"


# --- schemas ----------------------------------------------------------------------------------------------

_SECTION = re.compile(r"^={10,}\s*$", re.MULTILINE)
_PRIMITIVES = frozenset(
    {"bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"}
    | {"float32", "float64", "string", "wstring", "time", "duration"}
)


def schema_problem(schema: Schema) -> str | None:
    """Why a ``ros2msg``/``ros1msg`` schema cannot be decoded safely (a type containing itself, nesting over
    :data:`MAX_NESTING`), or ``None``."""
    if schema.encoding not in ("ros2msg", "ros1msg"):
        return None
    text = schema.data.decode("utf-8", "replace")
    sections = _SECTION.split(text)
    root = schema.name.replace("/msg/", "/")
    fields: dict[str, list[str]] = {}
    for index, section in enumerate(sections):
        lines = [ln.split("#", 1)[0].strip() for ln in section.splitlines()]
        lines = [ln for ln in lines if ln]
        name = root
        if index:
            if not lines or not lines[0].startswith("MSG:"):
                continue
            name = lines.pop(0)[4:].strip().replace("/msg/", "/")
        fields[name] = [_base(ln.split()[0], name) for ln in lines if len(ln.split()) >= 2 and "=" not in ln]
    return _nesting(fields, root, schema.name)


def _base(spelled: str, owner: str) -> str:
    base = spelled.split("[", 1)[0].split("<=", 1)[0].replace("/msg/", "/")
    if base in _PRIMITIVES or "/" in base:
        return base
    if base == "Header":
        return "std_msgs/Header"
    return f"{owner.split('/', maxsplit=1)[0]}/{base}"


def _nesting(fields: dict[str, list[str]], root: str, shown: str) -> str | None:
    """Depth-first without recursion: a type met again while it is open is a cycle; the open path is the
    nesting."""
    state: dict[str, bool] = {root: False}  # False: open, True: done
    stack = [(root, iter(fields.get(root, [])))]
    while stack:
        child = next(stack[-1][1], None)
        if child is None:
            state[stack.pop()[0]] = True
            continue
        if child not in fields or state.get(child) is True:
            continue
        if child in state:
            return (
                f"its schema {shown[:100]} has a type that contains itself ({child[:100]}); "
                "it was not decoded"
            )
        if len(stack) >= MAX_NESTING:
            return f"its schema {shown[:100]} nests types over {MAX_NESTING} levels deep; it was not decoded"
        state[child] = False
        stack.append((child, iter(fields[child])))
    return None
