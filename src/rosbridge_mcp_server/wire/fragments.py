"""Messages a rosbridge server split into ``fragment`` ops, rebuilt; without I/O.

Fragment ids of id-less messages are ``"0"`` on ROS 2 and the integer ``0`` on ROS 1, so two fragmented
messages may share an id: a buffer restarts on ``num == 0`` and ``total`` is checked.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from rosbridge_mcp_server.errors import ProtocolError

__all__ = ["FragmentAssembler"]


@dataclass
class _FragmentBuffer:
    total: int
    parts: list[str]
    size: int
    updated: float


class FragmentAssembler:
    """Rebuilds messages that arrive as ``fragment`` ops.

    Servers send the fragments of one message in order, numbered from 0. A buffer restarts when
    ``num == 0`` arrives (two id-less messages share the id ``"0"``/``0``); a gap, a changed
    ``total`` or a bad field drops the buffer and raises :class:`ProtocolError`. Memory is bounded:
    at most *max_buffers* partial messages and *max_chars* characters in all, oldest dropped
    first; buffers untouched for *ttl* seconds expire.
    """

    def __init__(
        self,
        *,
        max_chars: int = 64 * 1024 * 1024,
        max_buffers: int = 32,
        ttl: float = 30.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.max_chars = max_chars
        self.max_buffers = max_buffers
        self.ttl = ttl
        self._clock = clock
        self._buffers: dict[str, _FragmentBuffer] = {}
        self._chars = 0
        #: Messages rebuilt so far (diagnostics).
        self.completed = 0

    @property
    def pending(self) -> int:
        """Number of partial messages held."""
        return len(self._buffers)

    @property
    def held_chars(self) -> int:
        """Characters held in partial messages."""
        return self._chars

    def _drop(self, key: str) -> None:
        buf = self._buffers.pop(key, None)
        if buf is not None:
            self._chars -= buf.size

    def expire(self, now: float | None = None) -> list[str]:
        """Drop buffers idle for longer than the ttl; returns their ids."""
        now = self._clock() if now is None else now
        stale = [key for key, buf in self._buffers.items() if now - buf.updated > self.ttl]
        for key in stale:
            self._drop(key)
        return stale

    def add(self, frame: dict[str, Any]) -> str | None:
        """Take one ``fragment`` op; returns the whole message text once its last part arrived."""
        fid = frame.get("id")
        data = frame.get("data")
        num = frame.get("num")
        total = frame.get("total")
        # rosbridge 0.11.17 on Python 3 (Noetic) computes ``total`` with true division, so it is a float
        # such as 5.5 for five fragments; the real count is its integer part.
        if isinstance(total, float) and math.isfinite(total):
            total = int(total)
        if (
            not isinstance(data, str)
            or isinstance(num, bool)
            or isinstance(total, bool)
            or not isinstance(num, int)
            or not isinstance(total, int)
            or fid is None
            or isinstance(fid, dict | list)
        ):
            raise ProtocolError(f"malformed fragment (id={fid!r}, num={num!r}, total={total!r})")
        key = str(fid)
        if total < 1 or not 0 <= num < total:
            self._drop(key)
            raise ProtocolError(f"fragment {key} has num={num} outside total={total}")
        now = self._clock()
        if self._buffers:
            self.expire(now)
        if num == 0:
            self._drop(key)
            if total == 1:
                self.completed += 1
                return data
            buf = _FragmentBuffer(total=total, parts=[data], size=len(data), updated=now)
            self._buffers[key] = buf
            self._chars += buf.size
        else:
            existing = self._buffers.get(key)
            if existing is None:
                raise ProtocolError(f"fragment {key} part {num} arrived without part 0; dropped")
            if existing.total != total:
                self._drop(key)
                raise ProtocolError(f"fragment {key} changed total from {existing.total} to {total}; dropped")
            if num != len(existing.parts):
                self._drop(key)
                raise ProtocolError(
                    f"fragment {key} part {num} arrived when part {len(existing.parts)} was due; dropped"
                )
            existing.parts.append(data)
            existing.size += len(data)
            existing.updated = now
            self._chars += len(data)
            if len(existing.parts) == existing.total:
                self._drop(key)
                self.completed += 1
                return "".join(existing.parts)
        self._enforce_bounds(keep=key)
        return None

    def _enforce_bounds(self, keep: str) -> None:
        # dicts keep insertion order and a restarted buffer is re-inserted, so the first key is the oldest.
        while len(self._buffers) > self.max_buffers or self._chars > self.max_chars:
            victim = next((key for key in self._buffers if key != keep), None)
            if victim is None:
                self._drop(keep)
                raise ProtocolError(f"fragmented message {keep} exceeds {self.max_chars} characters; dropped")
            self._drop(victim)
