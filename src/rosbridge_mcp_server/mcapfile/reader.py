"""The MCAP reader itself: records read one by one, every declared length, size and offset held to the file
and to the call's :class:`~rosbridge_mcp_server.mcapfile.model.Budget` before it is read."""

from __future__ import annotations

import itertools
import struct
from array import array
from collections.abc import Iterator
from typing import IO, Any

from rosbridge_mcp_server.mcapfile.chunks import BLOCK, decompressed
from rosbridge_mcp_server.mcapfile.model import (
    INDEX_ENTRY_COST,
    MAGIC,
    MAX_SCHEMA,
    MAX_STRING,
    RECORD_COST,
    RECORDS_FLOOR,
    RECORDS_PER_COMPRESSED_BYTE,
    Budget,
    Channel,
    ChunkIndex,
    CutOff,
    RecordingProblem,
    Schema,
    Statistics,
    Summary,
    byte_size,
)

__all__ = ["McapFile"]

_HEADER, _FOOTER, _SCHEMA, _CHANNEL, _MESSAGE, _CHUNK, _MESSAGE_INDEX, _CHUNK_INDEX = range(1, 9)
_STATISTICS, _DATA_END = 0x0B, 0x0F
_FOOTER_SIZE = 1 + 8 + 20


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
        if size > 65536 * struct.calcsize("<" + key + value):  # more entries than a u16 key has values
            raise RecordingProblem(f"{self.what} is malformed: a map of {size} bytes, more than its keys can")
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
        self._held = 0  # bytes the schemas, channels and chunk indexes kept take (see _hold)

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
            self._hold(RECORD_COST + 16 * len(found.chunk_indexes[-1].index_offsets))
        elif opcode == _STATISTICS:
            count = body.number("Q")
            body.take(2 + 4 + 4 + 4 + 4)
            start, end = body.number("Q"), body.number("Q")
            found.statistics = Statistics(count, start, end, body.pairs("H", "Q"))

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
        """Each channel's message log times from the message indexes, read without decompressing a chunk.
        Each chunk's indexes are read once: regions that coincide or overlap (one index named by many chunk
        indexes, the fan-out) are refused before any is read."""
        times: dict[int, array[int]] = {cid: array("Q") for cid in summary.channels}
        entries = 0
        for begin, end in self._index_regions(summary):
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
                pairs = array("Q")
                pairs.frombytes(data[: len(data) // 16 * 16])
                times.setdefault(channel, array("Q")).extend(pairs[0::2])
            self.budget.check_time()
        return times

    def _index_regions(self, summary: Summary) -> list[tuple[int, int]]:
        regions: list[tuple[int, int, int]] = []
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
            regions.append((begin, end, chunk.offset))
        regions.sort()
        for (begin, end, first), (later, _, other) in itertools.pairwise(regions):
            if later < end or later == begin:
                raise RecordingProblem(
                    f"{self.name}: the chunk indexes of the chunks at bytes {first} and {other} name the "
                    f"same message index (bytes {begin}-{end} and from {later}); each chunk has its own, so "
                    "the index is malformed"
                )
        return [(begin, end) for begin, end, _ in regions]

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
            block = self.handle.read(min(BLOCK, left))
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
        # Decoded, a message takes several times its bytes (Python numbers, lists; JSON's objects more).
        needed = (length - 22) * (16 if channel.message_encoding == "json" else 8)
        if needed > self.budget.memory:
            self.budget.check_bytes(
                f"the message on {channel.topic[:100]} at byte {where} declares {length - 22} bytes; "
                "decoding it would take",
                needed,
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
        self.budget.check_bytes(f"{self.name}: {what} declares {size} bytes uncompressed, which is", size)
        held = f"{self.name}: {what} holds {data_length} compressed bytes; reading them would take"
        self.budget.check_bytes(held, data_length * 2)
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
        inner = _Source(decompressed(compressed, compression, size, f"{self.name}: {what}"), size)
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
            schema = Schema(sid, name, encoding, body.take(body.number("I")))
            old = self.schemas.get(sid)
            self._hold(len(schema.data) - (len(old.data) if old else -RECORD_COST))
            self.schemas[sid] = schema
        else:
            cid, sid = body.number("H"), body.number("H")
            channel = Channel(cid, sid, body.string(), body.string())
            old_channel = self.channels.get(cid)
            self._hold(_cost(channel) - (_cost(old_channel) if old_channel else 0))
            self.channels[cid] = channel

    def _hold(self, size: int) -> None:
        """Count what the schemas, channels and chunk indexes kept take, held to an eighth of the budget (a
        real recording's take a few hundred kilobytes)."""
        self._held += size
        if self._held > self.budget.memory // 8:
            raise RecordingProblem(
                f"{self.name}: its schemas, channels and chunk indexes would take over "
                f"{byte_size(self.budget.memory // 8)} (an eighth of this server's budget for one call)"
            )


def _cost(channel: Channel) -> int:
    return RECORD_COST + len(channel.topic) + len(channel.message_encoding)


def _skip(src: _Source, length: int, where: int) -> None:
    left = length
    while left > 0:
        step = min(left, BLOCK)
        src.read(step, f"the record at byte {where}")
        left -= step


def _not_mcap(head: bytes, name: str) -> str:
    what = "an empty file" if not head else f"a file starting with {head[:8]!r}"
    if head.startswith(b"#ROSBAG"):
        what = "a ROS 1 bag (.bag), not MCAP; convert it with `mcap convert`"
    elif head.startswith(b"SQLite format"):
        what = "a SQLite file (a ROS 2 .db3 bag?), not MCAP"
    return f"{name} is not an MCAP recording: it is {what} (MCAP starts with \\x89MCAP0)"
