"""Every recording together keeps the disk above the floor: sixteen writers at once on a fake disk (its free
space is a fixed capacity less what the folder holds) stop above :data:`DISK_RESERVE`, each file finished.

The disk is faked by its free-space function, the one thing a writer asks of it; the files are real.
"""

from __future__ import annotations

import os
import threading
from pathlib import Path

from rosbridge_mcp_server.robot.messages import TypeDef
from rosbridge_mcp_server.robot.recording.encoding import MessageCodec
from rosbridge_mcp_server.robot.recording.files import MCAP_MAGIC, create_recording
from rosbridge_mcp_server.robot.recording.reading import summarize_recording
from rosbridge_mcp_server.robot.recording.writing import DISK_RESERVE, DiskBudget, McapFileWriter

MIB = 1024 * 1024
BLOB = {"pkg/Blob": TypeDef("pkg/Blob", ("data",), ("uint8[]",), (0,))}


class FakeDisk:
    """A disk of ``DISK_RESERVE + headroom`` bytes free before the folder's files: what they hold is used."""

    def __init__(self, folder: Path, headroom: int) -> None:
        self.folder, self.capacity = folder, DISK_RESERVE + headroom
        self.lowest = self.capacity

    def free(self) -> int:
        used = sum(path.stat().st_size for path in self.folder.glob("*.mcap"))
        free = self.capacity - used
        self.lowest = min(self.lowest, free)
        return free


def _writers(folder: Path, disk: FakeDisk, count: int) -> list[tuple[Path, McapFileWriter]]:
    made = []
    for index in range(count):
        path, fd = create_recording(folder, f"rec{index}")
        codec = MessageCodec("pkg/Blob", BLOB, 2)
        made.append(
            (
                path,
                McapFileWriter(fd, {"/blob": codec}, ros_version=2, max_bytes=10**12, free_bytes=disk.free),
            )
        )
    return made


def test_sixteen_recordings_at_once_stop_above_the_floor(tmp_path: Path) -> None:
    """16 writers, each handed 6.4 MB of incompressible data at once, on a disk with 48 MiB above the floor:
    all of them end with the disk's free space above the floor, and every file is finished and readable."""
    disk = FakeDisk(tmp_path, headroom=48 * MIB)
    writers = _writers(tmp_path, disk, 16)

    def feed(writer: McapFileWriter) -> None:
        for index in range(200):
            writer.put("/blob", 10**9 + index, {"data": os.urandom(32 * 1024)})

    feeders = [threading.Thread(target=feed, args=(writer,)) for _, writer in writers]
    for feeder in feeders:
        feeder.start()
    for feeder in feeders:
        feeder.join()
    problems = [writer.close() for _, writer in writers]
    assert problems == [None] * 16
    assert disk.free() >= DISK_RESERVE, f"{(DISK_RESERVE - disk.free()) / MIB:.1f} MiB below the floor"
    assert disk.lowest >= DISK_RESERVE
    assert any(writer.state.stopped == "disk" for _, writer in writers)
    for path, writer in writers:
        assert path.read_bytes().endswith(MCAP_MAGIC)  # finished: footer and closing magic written
        assert summarize_recording(path).messages == writer.state.written["/blob"]


def test_the_budget_counts_what_every_running_writer_may_still_write() -> None:
    """Three writers on one budget: the others' pending chunks and summaries count against a message; when
    they have finished, the same message fits."""
    free = 100 * MIB
    budget = DiskBudget(lambda: free, floor=10 * MIB)
    for writer in (1, 2, 3):
        budget.join(writer)
    assert budget.allows(1, MIB)
    free = 18 * MIB  # 8 MiB above the floor; the three hold 4.25 + 2.25 + 2.25 MiB, the message 1 MiB
    assert not budget.allows(1, MIB)
    assert budget.leave(2)
    assert budget.leave(3)
    assert budget.allows(1, MIB)
    assert not budget.leave(1)
