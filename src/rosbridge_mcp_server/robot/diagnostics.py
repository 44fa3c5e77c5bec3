"""``/diagnostics`` as a board: the latest ``diagnostic_msgs/DiagnosticStatus`` per name and hardware id.

Each driver publishes its own ``DiagnosticArray`` (diagnostic_updater: about once a second); an aggregator
republishes them on ``/diagnostics_agg``. :class:`StatusBoard` keeps the latest status of each (name,
hardware id), at most :data:`BOARD_STATUSES` of them. The level is a ``byte``: an integer from ROS 1 and the
simulated robot, and on some ROS 2 bridges a base64 string (``"Ag=="`` for ERROR) or a one-character string;
all are read.
"""

from __future__ import annotations

import base64
import binascii
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Final

from rosbridge_mcp_server.robot.text import NAME_CHARS, shown

__all__ = ["BOARD_STATUSES", "LEVEL_NAMES", "StatusBoard", "StatusRecord", "status_level"]

#: The most (name, hardware id) pairs the board keeps.
BOARD_STATUSES: Final = 500
LEVEL_NAMES: Final = {0: "OK", 1: "WARN", 2: "ERROR", 3: "STALE"}
_MAX_VALUES: Final = 6


def status_level(value: Any) -> int | None:
    """A status's level as 0-3 from any of the forms bridges send, or ``None`` when unreadable."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int):
        return value if value in LEVEL_NAMES else None
    if isinstance(value, list) and len(value) == 1:
        return status_level(value[0])
    if isinstance(value, str):
        if len(value) == 1:
            if value.isdigit():
                return status_level(int(value))
            return status_level(ord(value))
        try:
            raw = base64.b64decode(value, validate=True)
        except (binascii.Error, ValueError):
            return int(value) if value.isdigit() and int(value) in LEVEL_NAMES else None
        return raw[0] if len(raw) == 1 and raw[0] in LEVEL_NAMES else None
    return None


@dataclass(frozen=True)
class StatusRecord:
    """One status as last seen: level 0-3, name, message, hardware id, the first key values, the topic it
    came on and when (``time.time()``)."""

    level: int
    name: str
    message: str
    hardware_id: str
    values: tuple[tuple[str, str], ...]
    topic: str
    received: float

    @property
    def level_name(self) -> str:
        return LEVEL_NAMES.get(self.level, str(self.level))


class StatusBoard:
    """The latest status per (name, hardware id)."""

    def __init__(self, max_statuses: int = BOARD_STATUSES) -> None:
        self.max_statuses = max_statuses
        self._statuses: dict[tuple[str, str], StatusRecord] = {}
        self.messages = 0

    def add_message(self, msg: Mapping[str, Any], topic: str, received: float) -> None:
        """Every status of a ``DiagnosticArray``."""
        self.messages += 1
        statuses = msg.get("status")
        if not isinstance(statuses, list):
            return
        for status in statuses:
            if not isinstance(status, Mapping):
                continue
            level = status_level(status.get("level"))
            if level is None:
                continue
            values = status.get("values")
            # Every field is robot text: kept escaped and capped (robot/text.py), as it will be shown.
            pairs = tuple(
                (shown(v.get("key", ""), 60), shown(v.get("value", ""), 120))
                for v in (values if isinstance(values, list) else [])[:_MAX_VALUES]
                if isinstance(v, Mapping)
            )
            key = (
                shown(status.get("name", ""), NAME_CHARS),
                shown(status.get("hardware_id", ""), NAME_CHARS),
            )
            if key not in self._statuses and len(self._statuses) >= self.max_statuses:
                continue
            self._statuses[key] = StatusRecord(
                level, key[0], shown(status.get("message", ""), 300), key[1], pairs, topic, received
            )

    def statuses(self) -> list[StatusRecord]:
        """Every status, the worst first, then by name."""
        return sorted(self._statuses.values(), key=lambda s: (-s.level, s.name))

    def __len__(self) -> int:
        return len(self._statuses)
