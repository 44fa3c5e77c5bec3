"""Recordings: topics written to MCAP files as ``ros2 bag`` / ``rosbag`` would, and read back.

``encoding.py`` (schemas and CDR / ROS 1 bytes from rosapi's TypeDefs), ``writing.py`` (the MCAP file on a
writer thread, its caps), ``recorder.py`` (choosing topics, subscribing, recording), ``reading.py`` (summary
from the index, decoded messages, fields over time), ``files.py`` (the recording directory and the paths held
inside it), ``timing.py`` (rates and gaps). The ``mcap`` packages are imported only when a recording
is made or read.
"""

from __future__ import annotations

import asyncio

__all__ = ["RunningRecordings"]


class RunningRecordings:
    """The recordings running on one robot session, by file name, so a later call can stop them."""

    def __init__(self) -> None:
        self._running: dict[str, asyncio.Event] = {}

    def add(self, name: str) -> asyncio.Event:
        event = asyncio.Event()
        self._running[name] = event
        return event

    def remove(self, name: str) -> None:
        self._running.pop(name, None)

    def names(self) -> list[str]:
        return sorted(self._running)

    def stop(self, name: str | None = None) -> list[str]:
        """Stop the recording named ``name`` (every one when ``None``); the names stopped."""
        stopped = []
        for key, event in self._running.items():
            if name is None or key in (name, f"{name}.mcap"):
                event.set()
                stopped.append(key)
        return stopped
