"""What every action server of the simulated robot shares: the host it lives in, status codes, the
Fibonacci execution loop, stamps.

Both Fibonacci servers follow the example servers: the sequence starts ``[0, 1]``; each step appends the
next number, publishes one feedback and waits ``action_step`` seconds; the result is the whole sequence. A
cancel ends the goal at its next step with the partial sequence (ROS 2 CANCELED, ROS 1 PREEMPTED), as the
rclcpp minimal action server does.

Goals we refuse (our documented choice; the example servers differ on this): ``order < 0`` is rejected,
and so is ``order > 9000`` (the rclcpp example's own limit). A goal whose next number no longer fits an
``int32`` is aborted with the sequence so far (that happens from ``order = 47`` on).
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
from collections.abc import Callable
from typing import Any, Protocol

from rosbridge_mcp_server.sim.graph import Graph
from rosbridge_mcp_server.sim.interfaces import InterfaceRegistry
from rosbridge_mcp_server.sim.world import GoalRecord, World

__all__ = [
    "ACCEPTED_TEXT",
    "CANCELED_BEFORE_STAMP",
    "FIBONACCI_NODE",
    "KEEP_FINISHED",
    "REPLACED_BY_ANOTHER_GOAL",
    "ROS1_STATUS",
    "ROS2_STATUS",
    "ActionHost",
    "FibonacciRun",
    "order_ok",
    "stamp_seconds",
    "time_msg",
    "uuid_bytes",
]

FIBONACCI_NODE = "/fibonacci_server"
INT32_MAX = 2**31 - 1
MAX_ORDER = 9000

#: ``action_msgs/msg/GoalStatus``
ROS2_STATUS = {
    "UNKNOWN": 0,
    "ACCEPTED": 1,
    "EXECUTING": 2,
    "CANCELING": 3,
    "SUCCEEDED": 4,
    "CANCELED": 5,
    "ABORTED": 6,
}
#: ``actionlib_msgs/GoalStatus`` — the numbers differ from ROS 2.
ROS1_STATUS = {
    "PENDING": 0,
    "ACTIVE": 1,
    "PREEMPTED": 2,
    "SUCCEEDED": 3,
    "ABORTED": 4,
    "REJECTED": 5,
    "PREEMPTING": 6,
    "RECALLING": 7,
    "RECALLED": 8,
    "LOST": 9,
}
#: How many finished goals stay in the status list.
KEEP_FINISHED = 20


class ActionHost(Protocol):
    """What an action server needs from the rosbridge process it lives in, and nothing more."""

    @property
    def graph(self) -> Graph: ...

    @property
    def world(self) -> World: ...

    @property
    def registry(self) -> InterfaceRegistry: ...

    def publish_json(self, topic: str, msg_type: str, partial: dict[str, Any]) -> None:
        """Publish a message given in JSON form (missing fields take defaults)."""

    def has_subscribers(self, topic: str) -> bool:
        """Whether anyone listens to ``topic``."""

    def send_to_client(self, client: int, message: dict[str, Any]) -> bool:
        """Send a frame to one client; ``False`` if it has gone."""


def order_ok(order: int) -> bool:
    return 0 <= order <= MAX_ORDER


def uuid_bytes(value: Any) -> bytes:
    """A UUID field in whatever form the converter gives it (bytes, list of ints, base64 text)."""
    if isinstance(value, str):
        return base64.b64decode(value)
    return bytes(value)


#: SimpleActionServer's texts (actionlib 1.x).
ACCEPTED_TEXT = "This goal has been accepted by the simple action server"
REPLACED_BY_ANOTHER_GOAL = (
    "This goal was canceled because another goal was received by the simple action server"
)
CANCELED_BEFORE_STAMP = (
    "This goal handle was canceled by the action server because its timestamp is before the timestamp of the "
    "last cancel request"
)


def stamp_seconds(stamp: Any) -> float:
    if not isinstance(stamp, dict):
        return 0.0
    sec = stamp.get("sec", stamp.get("secs", 0)) or 0
    nsec = stamp.get("nanosec", stamp.get("nsecs", 0)) or 0
    return float(sec) + float(nsec) / 1e9


def time_msg(seconds: float, dialect: str) -> dict[str, int]:
    sec = int(seconds)
    nsec = round((seconds - sec) * 1e9)
    return {"sec": sec, "nanosec": nsec} if dialect == "ros2" else {"secs": sec, "nsecs": nsec}


class FibonacciRun:
    """The execution loop shared by both dialects."""

    def __init__(
        self, record: GoalRecord, step: float, notify: Callable[[], None], cancel: asyncio.Event | None = None
    ) -> None:
        self.record = record
        self.step = step
        self.notify = notify
        self.cancel = cancel or asyncio.Event()

    async def execute(self, on_feedback: Callable[[list[int]], None]) -> str:
        """Run to the end; returns ``succeeded``, ``canceled`` or ``aborted``."""
        sequence = [0, 1]
        self.record.sequence = list(sequence)
        for i in range(1, self.record.order):
            if self.cancel.is_set():
                return "canceled"
            following = sequence[i] + sequence[i - 1]
            if following > INT32_MAX:
                return "aborted"
            sequence.append(following)
            self.record.sequence = list(sequence)
            on_feedback(list(sequence))
            self.notify()
            # Wakes early on a cancel so it takes effect at the next step without waiting it out.
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self.cancel.wait(), self.step)
        return "succeeded"
