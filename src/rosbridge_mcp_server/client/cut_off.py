"""A goal a drop cut off, as the client's ledger keeps it (:mod:`.goals` sends its cancel): since when, which
session was dying then, and when it is too late, or pointless, to cancel it."""

from __future__ import annotations

import time
from typing import Final

from rosbridge_mcp_server.client.session import BridgeSession

__all__ = ["ORPHAN_LIMIT", "ORPHAN_MAX_AGE_SECONDS", "CutOff", "not_to_cancel"]

#: At most this many goals cut off by a drop are remembered for a cancel (the oldest are forgotten).
ORPHAN_LIMIT: Final = 100
#: A goal cut off by a drop longer ago than this is not cancelled when the connection comes back: a
#: surprise cancel of something that old would stop whatever the robot is doing now.
ORPHAN_MAX_AGE_SECONDS = 300.0


class CutOff:
    """A goal in the ledger: since when, and the session that was open when it was cut off (maybe dying)."""

    __slots__ = ("action", "goal_id", "since", "stale", "version")

    def __init__(self, action: str, goal_id: str, version: int, stale: BridgeSession | None) -> None:
        self.action, self.goal_id, self.version = action, goal_id, version
        self.since = time.monotonic()
        self.stale = stale


def not_to_cancel(entry: CutOff, now: float, version: int, url: str) -> str | None:
    """Why a goal a drop cut off is not cancelled on a connection of ROS *version*, or None."""
    age = now - entry.since
    if age > ORPHAN_MAX_AGE_SECONDS:
        return f"it was left running by a drop {age:.0f} s ago, too long ago for a surprise cancel"
    if entry.version != version:
        return (
            f"it was sent to a ROS {entry.version} bridge and {url} came back as ROS {version}, so the goal "
            "is gone"
        )
    return None
