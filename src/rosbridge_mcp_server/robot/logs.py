"""The robot's log as this server keeps it: a bounded ring of ``/rosout`` lines, filters, and folding.

rosbridge keeps no history, so a model that asks "what went wrong?" sees nothing logged before it asked.
:class:`LogRing` keeps the lines from the moment the server connects, bounded by count
(:data:`RING_LINES`) and by age (:data:`RING_SECONDS`): the oldest go first. Beside it, a small tally of
every warning and error since the server connected (:class:`Tally`, at most :data:`TALLY_GROUPS` groups),
so ``diagnose`` still counts what the ring has already let go.

Both dialects' log messages are read into one :class:`LogLine`: ROS 2 ``rcl_interfaces/msg/Log`` (levels 10
… 50, a logger name such as ``global_costmap.global_costmap``) and ROS 1 ``rosgraph_msgs/Log`` (levels 1 …
16, a node name such as ``/amcl``). Repeats fold: lines of one node and level whose text differs only in its
numbers are one :class:`Fold` ("×37 in 12 s, last 0.4 s ago").
"""

from __future__ import annotations

import fnmatch
import re
import time
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Final

from rosbridge_mcp_server.robot.text import NAME_CHARS, shown

__all__ = [
    "LEVELS",
    "RING_LINES",
    "RING_SECONDS",
    "TALLY_GROUPS",
    "Fold",
    "LogLine",
    "LogRing",
    "Tally",
    "fold",
    "level_rank",
    "line_of",
    "node_matcher",
]

#: The most lines the ring keeps.
RING_LINES: Final = 5_000
#: The oldest line the ring keeps, in seconds.
RING_SECONDS: Final = 600.0
#: The most (node, level, text) groups the tally of warnings and errors keeps.
TALLY_GROUPS: Final = 200

#: Level names, lowest first.
LEVELS: Final = ("debug", "info", "warn", "error", "fatal")
_ROS2_LEVELS: Final = {10: "debug", 20: "info", 30: "warn", 40: "error", 50: "fatal"}
_ROS1_LEVELS: Final = {1: "debug", 2: "info", 4: "warn", 8: "error", 16: "fatal"}
_MAX_TEXT: Final = 500
_NUMBER = re.compile(r"\d+(?:\.\d+)?")


def level_rank(level: str) -> int:
    """0 for debug … 4 for fatal."""
    return LEVELS.index(level)


def _level(value: Any) -> str:
    if isinstance(value, str):
        # ROS 1 bridges may send a byte as a one-character string.
        value = ord(value[0]) if len(value) == 1 else int(value) if value.isdigit() else 0
    if not isinstance(value, int) or isinstance(value, bool):
        return "info"
    if value in _ROS2_LEVELS:
        return _ROS2_LEVELS[value]
    if value in _ROS1_LEVELS:
        return _ROS1_LEVELS[value]
    return "fatal" if value > 50 else "info"


def _node(name: Any) -> str:
    """A node name from a logger name: ``local_costmap.local_costmap`` → ``/local_costmap/local_costmap``."""
    text = shown(name or "?", NAME_CHARS)
    if not text.startswith("/"):
        text = "/" + text.replace(".", "/")
    return text


def _stamp(msg: Mapping[str, Any]) -> float | None:
    stamp = msg.get("stamp")
    if stamp is None and isinstance(msg.get("header"), Mapping):
        stamp = msg["header"].get("stamp")
    if not isinstance(stamp, Mapping):
        return None
    sec = stamp.get("sec", stamp.get("secs"))
    nsec = stamp.get("nanosec", stamp.get("nsecs", 0))
    if not isinstance(sec, int | float) or not isinstance(nsec, int | float):
        return None
    return float(sec) + float(nsec) / 1e9


@dataclass(frozen=True, slots=True)
class LogLine:
    """One log line: when it arrived (``time.time()``), the robot's stamp, level, node and text."""

    received: float
    stamp: float | None
    level: str
    node: str
    text: str
    where: str  #: ``file:line (function)``, or ""


def line_of(msg: Mapping[str, Any], received: float) -> LogLine:
    """A :class:`LogLine` from a log message of either dialect (lenient: a bad field reads as empty).

    Every field is robot text, kept as it will be shown (:func:`~rosbridge_mcp_server.robot.text.shown`:
    escaped, and capped with the cut said), so a line cannot start a line of ours nor hold megabytes in the
    ring.
    """
    text = shown(msg.get("msg", ""), _MAX_TEXT)
    file = msg.get("file") or ""
    where = ""
    if file:
        function = shown(msg.get("function", ""), NAME_CHARS)
        where = f"{shown(file, NAME_CHARS)}:{shown(msg.get('line', ''), 20)} ({function})"
    return LogLine(received, _stamp(msg), _level(msg.get("level")), _node(msg.get("name")), text, where)


def node_matcher(pattern: str | None) -> Callable[[str], bool]:
    """A node-name test: a glob (``*costmap*``), or a name with or without its slash (``amcl``)."""
    if not pattern:
        return lambda _node: True
    wanted = pattern.strip()
    if not wanted.startswith(("/", "*")):
        wanted = "/" + wanted
    if any(char in wanted for char in "*?["):
        return lambda node: fnmatch.fnmatchcase(node, wanted)
    return lambda node: node == wanted


class LogRing:
    """The log lines since the server connected, bounded by count and age (the oldest go first)."""

    def __init__(self, max_lines: int = RING_LINES, max_age: float = RING_SECONDS) -> None:
        self.max_lines = max_lines
        self.max_age = max_age
        self._lines: deque[LogLine] = deque()
        #: Lines received, and lines let go by the bounds.
        self.received = 0
        self.dropped = 0
        self.tally = Tally()

    def add(self, line: LogLine) -> None:
        self.received += 1
        if len(self._lines) >= self.max_lines:
            self._lines.popleft()
            self.dropped += 1
        self._lines.append(line)
        if level_rank(line.level) >= level_rank("warn"):
            self.tally.add(line)

    def _expire(self, now: float) -> None:
        oldest = now - self.max_age
        while self._lines and self._lines[0].received < oldest:
            self._lines.popleft()
            self.dropped += 1

    def lines(self, now: float | None = None) -> list[LogLine]:
        """The lines kept, oldest first (those older than the age bound are let go first)."""
        self._expire(time.time() if now is None else now)
        return list(self._lines)

    def __len__(self) -> int:
        return len(self._lines)

    def select(
        self,
        *,
        level: str = "warn",
        node: str | None = None,
        text: str | None = None,
        since: float | None = None,
        now: float | None = None,
    ) -> list[LogLine]:
        """The lines at *level* or above, of nodes matching *node*, containing *text* (any case), received in
        the last *since* seconds; oldest first."""
        now = time.time() if now is None else now
        lowest = level_rank(level)
        wanted_node = node_matcher(node)
        needle = text.lower() if text else None
        after = now - since if since is not None else None
        return [
            line
            for line in self.lines(now)
            if level_rank(line.level) >= lowest
            and (after is None or line.received >= after)
            and wanted_node(line.node)
            and (needle is None or needle in line.text.lower())
        ]


def _key(line: LogLine) -> tuple[str, str, str]:
    return (line.node, line.level, _NUMBER.sub("#", line.text))


@dataclass
class Fold:
    """Lines of one node and level whose texts differ at most in their numbers: the latest text, how many,
    when the first and the last arrived."""

    node: str
    level: str
    text: str
    count: int
    first: float
    last: float
    where: str = ""

    def describe(self, now: float) -> str:
        """``[ERROR] /controller_server: Failed to make progress ×37 in 12 s, last 0.4 s ago``."""
        ago = _seconds(now - self.last)
        if self.count == 1:
            when = f"{ago} ago"
        else:
            when = f"×{self.count} in {_seconds(self.last - self.first)}, last {ago} ago"
        return f"[{self.level.upper()}] {self.node}: {self.text} ({when})"


def _seconds(value: float) -> str:
    value = max(0.0, value)
    if value < 10:
        return f"{value:.1f} s"
    if value < 120:
        return f"{value:.0f} s"
    if value < 7200:
        return f"{value / 60:.0f} min"
    return f"{value / 3600:.1f} h"


def fold(lines: Iterable[LogLine]) -> list[Fold]:
    """Repeats folded, ordered by their last line (oldest first)."""
    folds: dict[tuple[str, str, str], Fold] = {}
    for line in lines:
        key = _key(line)
        found = folds.get(key)
        if found is None:
            folds[key] = Fold(line.node, line.level, line.text, 1, line.received, line.received, line.where)
        else:
            found.count += 1
            found.last = line.received
            found.text = line.text
            found.where = line.where
    return sorted(folds.values(), key=lambda f: f.last)


@dataclass
class Tally:
    """Every warning and error since the server connected, folded, at most :data:`TALLY_GROUPS` groups (a
    new group beyond that replaces the one seen longest ago)."""

    groups: dict[tuple[str, str, str], Fold] = field(default_factory=dict)
    max_groups: int = TALLY_GROUPS

    def add(self, line: LogLine) -> None:
        key = _key(line)
        found = self.groups.get(key)
        if found is not None:
            found.count += 1
            found.last = line.received
            found.text = line.text
            return
        if len(self.groups) >= self.max_groups:
            stalest = min(self.groups, key=lambda k: self.groups[k].last)
            del self.groups[stalest]
        self.groups[key] = Fold(line.node, line.level, line.text, 1, line.received, line.received, line.where)

    def folds(self) -> list[Fold]:
        """The groups, the most severe first, then the latest."""
        return sorted(self.groups.values(), key=lambda f: (-level_rank(f.level), -f.last))
