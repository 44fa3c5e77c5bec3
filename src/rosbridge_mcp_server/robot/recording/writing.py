"""An MCAP file written on a thread of its own, so the event loop only hands messages over.

Each message is encoded (:mod:`.encoding`) and added on the writer thread. The file ends cleanly — its summary
and index written, readable by any MCAP reader — when the recording ends for any reason: its time is up, the
size cap is reached, the disk is nearly full, a write fails, or it is stopped.

The disk is one budget for every recording on it (:class:`DiskBudget`, one per filesystem in this process):
before each message is written, the free space less what every running recording may still write without
asking (its chunk not yet on disk, its index and summary: :meth:`DiskBudget.allows`) must stay above
:data:`DISK_RESERVE`. Sixteen recordings at once stop together above the floor instead of each checking
the disk on its own, every half second, while the others fill it.
"""

from __future__ import annotations

import contextlib
import logging
import os
import queue
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from rosbridge_mcp_server.robot.recording.encoding import MessageCodec

__all__ = ["DISK_RESERVE", "DiskBudget", "McapFileWriter", "WriterState", "shared_disk"]

_log = logging.getLogger(__name__)

#: Recording stops while this many bytes are still free on the disk (the summary and index need room).
DISK_RESERVE = 32 * 1024 * 1024
#: Room kept under the size cap for the last chunk, the summary and the index.
SUMMARY_RESERVE = 256 * 1024
#: Messages handed over but not yet written, at most (beyond that the oldest are refused and counted).
MAX_PENDING = 2000
#: MCAP chunk size: the unit of compression and of the index.
CHUNK_SIZE = 1024 * 1024

FreeBytes = Callable[[], int]


class DiskBudget:
    """The free space of one filesystem, shared by every recording written on it (thread-safe: each writer
    asks from its own thread)."""

    def __init__(self, free_bytes: FreeBytes, floor: int = DISK_RESERVE) -> None:
        self.free_bytes, self.floor = free_bytes, floor
        self._lock = threading.Lock()
        #: What each running writer may still put on the disk without asking: its open chunk (a chunk and a
        #: message at least), the chunk's message index, and the summary at the end.
        self._held: dict[int, int] = {}

    def join(self, writer: int) -> None:
        with self._lock:
            self._held[writer] = 2 * CHUNK_SIZE + SUMMARY_RESERVE

    def leave(self, writer: int) -> bool:
        """The writer has finished its file; whether any writer is left."""
        with self._lock:
            self._held.pop(writer, None)
            return bool(self._held)

    def allows(self, writer: int, size: int) -> bool:
        """Whether ``writer`` may add a message of ``size`` bytes with every recording's pending writes still
        above the floor."""
        with self._lock:
            held = max(self._held.get(writer, 0), 2 * CHUNK_SIZE + SUMMARY_RESERVE + 2 * size)
            self._held[writer] = held
            try:
                free = self.free_bytes()
            except OSError:
                return True  # the disk cannot be asked: the write itself will say
            return free - sum(self._held.values()) - size >= self.floor


_DISKS: dict[int, DiskBudget] = {}
_DISKS_LOCK = threading.Lock()


def shared_disk(fd: int, free_bytes: FreeBytes) -> DiskBudget:
    """The budget of the filesystem ``fd`` is on, shared by every recording on it in this process (the disk
    is the process's, whichever robot or session records)."""
    device = os.fstat(fd).st_dev
    with _DISKS_LOCK:
        budget = _DISKS.get(device)
        if budget is None:
            budget = _DISKS[device] = DiskBudget(free_bytes)
        return budget


def _leave_disk(fd_device: int, budget: DiskBudget, writer: int) -> None:
    with _DISKS_LOCK:
        if not budget.leave(writer) and _DISKS.get(fd_device) is budget:
            del _DISKS[fd_device]  # no recording on it: the next one asks afresh


@dataclass
class WriterState:
    """What the writer thread did, read by the event loop (plain ints and strings: no lock needed)."""

    written: dict[str, int] = field(default_factory=dict)
    times: dict[str, list[int]] = field(default_factory=dict)
    bytes_in: int = 0
    refused: int = 0
    failed: dict[str, str] = field(default_factory=dict)
    #: Why the writer stopped taking messages ("size", "disk", "error: ..."), or None while it takes them.
    stopped: str | None = None


class McapFileWriter:
    """One MCAP file being written: channels registered up front, messages handed over with :meth:`put`."""

    def __init__(
        self,
        fd: int,
        codecs: dict[str, MessageCodec],
        *,
        ros_version: int,
        max_bytes: int,
        free_bytes: FreeBytes,
        on_stop: Callable[[], None] | None = None,
        compression: str = "zstd",
    ) -> None:
        from mcap.writer import CompressionType, Writer  # lazy: only recording needs mcap  # noqa: PLC0415

        self._device = os.fstat(fd).st_dev
        self._disk = shared_disk(fd, free_bytes)
        self._disk.join(id(self))
        self._file = os.fdopen(fd, "wb")
        kind = CompressionType.ZSTD if compression == "zstd" else CompressionType.NONE
        self._writer = Writer(self._file, chunk_size=CHUNK_SIZE, compression=kind)
        self._writer.start(profile="ros2" if ros_version == 2 else "ros1", library="rosbridge-mcp-server")
        self._codecs = codecs
        self._channels: dict[str, int] = {}
        for topic, codec in codecs.items():
            schema = self._writer.register_schema(
                codec.schema_name, codec.schema_encoding, codec.schema_text.encode()
            )
            metadata = {"offered_qos_profiles": ""} if ros_version == 2 else {}
            self._channels[topic] = self._writer.register_channel(
                topic, codec.message_encoding, schema, metadata
            )
        self.state = WriterState(written=dict.fromkeys(codecs, 0), times={t: [] for t in codecs})
        self._max_bytes = max_bytes
        self._on_stop = on_stop
        self._queue: queue.Queue[tuple[str, int, Any] | None] = queue.Queue()
        self._thread = threading.Thread(target=self._run, name="mcap-writer", daemon=True)
        self._sequence = 0
        self._thread.start()

    # --- the event loop's side ------------------------------------------------------------------------------

    def put(self, topic: str, log_time_ns: int, message: Any) -> bool:
        """Hand one message over; False when the writer has stopped or is too far behind (counted)."""
        if self.state.stopped is not None:
            return False
        if self._queue.qsize() >= MAX_PENDING:
            self.state.refused += 1
            return False
        self._queue.put((topic, log_time_ns, message))
        return True

    def close(self) -> str | None:
        """Write what is left, the summary and the index; blocking (call it in a thread).

        Returns an error text when the file could not be finished."""
        self._queue.put(None)
        self._thread.join()
        try:
            self._writer.finish()  # type: ignore[no-untyped-call]
            self._file.close()
        except OSError as exc:
            _log.warning("recording could not be finished: %s", exc)
            with contextlib.suppress(OSError):
                self._file.close()
            return exc.strerror or str(exc)
        finally:
            _leave_disk(self._device, self._disk, id(self))
        return None

    # --- the writer thread --------------------------------------------------------------------------------

    def _stop(self, reason: str) -> None:
        if self.state.stopped is None:
            self.state.stopped = reason
            if self._on_stop is not None:
                self._on_stop()

    def _run(self) -> None:
        while True:
            item = self._queue.get()
            if item is None:
                return
            if self.state.stopped is not None:
                continue
            topic, log_time, message = item
            codec = self._codecs[topic]
            try:
                data = codec.encode(message)
            except (ValueError, TypeError, OverflowError, Exception) as exc:  # a message that does not fit
                self.state.failed.setdefault(topic, f"{type(exc).__name__}: {exc}")
                continue
            if self.state.bytes_in + len(data) + SUMMARY_RESERVE > self._max_bytes:
                self._stop("size")
                continue
            if not self._disk.allows(id(self), len(data)):
                self._stop("disk")
                continue
            self._sequence += 1
            try:
                self._writer.add_message(
                    self._channels[topic],
                    log_time=log_time,
                    data=data,
                    publish_time=_stamp_ns(message, log_time),
                    sequence=self._sequence,
                )
            except OSError as exc:
                self._stop(f"error: {exc.strerror or exc}")
                continue
            except Exception as exc:  # the mcap writer refused: stop, the file is still finished
                self._stop(f"error: {exc}")
                continue
            self.state.bytes_in += len(data)
            self.state.written[topic] += 1
            self.state.times[topic].append(log_time)


def _stamp_ns(message: Any, default: int) -> int:
    """The header stamp of a message, in ns (its publish time), or ``default``."""
    header = message.get("header") if isinstance(message, dict) else None
    stamp = header.get("stamp") if isinstance(header, dict) else None
    if not isinstance(stamp, dict):
        return default
    secs = stamp.get("sec", stamp.get("secs"))
    nsecs = stamp.get("nanosec", stamp.get("nsecs"))
    if not isinstance(secs, int) or not isinstance(nsecs, int) or secs <= 0:
        return default
    return secs * 1_000_000_000 + nsecs
