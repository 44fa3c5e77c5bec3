"""The simulated robot's world state: what tests assert on and what the world's nodes change.

Everything here is mutated from the robot's event loop only. Every change calls :meth:`World.notify`,
which wakes :meth:`World.wait_for`, so tests wait on a condition instead of sleeping.
"""

from __future__ import annotations

import asyncio
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

__all__ = [
    "PUBLISHED_HISTORY",
    "TURTLE_HOME",
    "GoalRecord",
    "PublishedMessage",
    "Turtle",
    "World",
]

#: How many client-published messages are kept per topic in :attr:`World.published`.
PUBLISHED_HISTORY = 1000

#: turtlesim spawns its first turtle in the middle of an 11.09 m square.
TURTLE_HOME = 5.544444561004639
#: turtlesim's window edge, in metres.
TURTLE_ARENA = 11.088889122009277


@dataclass
class Turtle:
    """The turtle of ``/turtle1``: pose in metres / radians, current command in m/s and rad/s."""

    x: float = TURTLE_HOME
    y: float = TURTLE_HOME
    theta: float = 0.0
    linear: float = 0.0
    angular: float = 0.0
    #: ``time.monotonic()`` of the last accepted velocity command; the command holds for one second.
    command_time: float = 0.0
    #: Every velocity command the turtle accepted.
    commands: int = 0

    def reset(self) -> None:
        """Put the turtle back where turtlesim spawns it, standing still."""
        self.x = self.y = TURTLE_HOME
        self.theta = self.linear = self.angular = 0.0
        self.command_time = 0.0

    def step(self, dt: float) -> None:
        """Integrate the current command over ``dt`` seconds, like turtlesim: forward speed and turn rate."""
        self.theta = math.atan2(
            math.sin(self.theta + self.angular * dt), math.cos(self.theta + self.angular * dt)
        )
        self.x = min(max(self.x + math.cos(self.theta) * self.linear * dt, 0.0), TURTLE_ARENA)
        self.y = min(max(self.y + math.sin(self.theta) * self.linear * dt, 0.0), TURTLE_ARENA)


@dataclass(frozen=True)
class PublishedMessage:
    """One message a client published, as the world received it."""

    topic: str
    type: str
    #: The message after rosbridge-style conversion (defaults filled in).
    msg: dict[str, Any]
    #: ``time.monotonic()`` when it arrived.
    received_at: float
    #: Which client connection sent it (1, 2, ... in connection order).
    connection_id: int


@dataclass
class GoalRecord:
    """One goal of the ``/fibonacci`` action, whichever way it arrived."""

    goal_id: str
    order: int
    #: Status in the dialect's own codes (``action_msgs/GoalStatus`` or ``actionlib_msgs/GoalStatus``).
    status: int
    sequence: list[int] = field(default_factory=list)
    feedback_count: int = 0
    cancel_requested: bool = False
    accepted_at: float = field(default_factory=time.time)
    finished: bool = False


@dataclass
class World:
    """State of the simulated world, for assertions in tests."""

    dialect: str
    turtle: Turtle = field(default_factory=Turtle)
    #: Whether ``/set_enabled`` last enabled the robot; when false the turtle ignores ``cmd_vel``.
    enabled: bool = True
    #: Parameters in the dialect's naming: ROS 2 ``/node:param``, ROS 1 ``/global/name``.
    params: dict[str, Any] = field(default_factory=dict)
    #: Client-published messages per topic, newest last (bounded).
    published: dict[str, deque[PublishedMessage]] = field(default_factory=dict)
    #: Goals of ``/fibonacci`` by goal id (ROS 2: the rosbridge ``id``, else the UUID in hex; ROS 1:
    #: ``goal_id.id``).
    goals: dict[str, GoalRecord] = field(default_factory=dict)
    #: How many times each service was called (by name).
    service_calls: dict[str, int] = field(default_factory=dict)
    #: Calls refused before reaching the service because the request did not fit its type (by name); a real
    #: bridge logs an error line for each.
    refused_calls: dict[str, int] = field(default_factory=dict)
    #: Counters of the periodic publishers.
    chatter_count: int = 0
    fast_count: int = 0
    camera_frames: int = 0
    depth_frames: int = 0
    scans: int = 0
    _changed: asyncio.Event = field(default_factory=asyncio.Event, repr=False)

    def notify(self) -> None:
        """Wake every :meth:`wait_for`; call after each change."""
        self._changed.set()
        self._changed = asyncio.Event()

    def record_published(self, message: PublishedMessage) -> None:
        """Remember a message a client published (oldest dropped beyond :data:`PUBLISHED_HISTORY`)."""
        history = self.published.get(message.topic)
        if history is None:
            history = self.published[message.topic] = deque(maxlen=PUBLISHED_HISTORY)
        history.append(message)
        self.notify()

    def count_call(self, service: str) -> None:
        """Count one call of ``service``."""
        self.service_calls[service] = self.service_calls.get(service, 0) + 1
        self.notify()

    def count_refused(self, service: str) -> None:
        """Count one call of ``service`` refused for a request that does not fit its type."""
        self.refused_calls[service] = self.refused_calls.get(service, 0) + 1

    async def wait_for(
        self,
        predicate: Callable[[World], object],
        timeout: float = 5.0,
    ) -> None:
        """Return once ``predicate(world)`` is true; raise :class:`TimeoutError` after ``timeout`` seconds."""
        async with asyncio.timeout(timeout):
            while not predicate(self):
                await self._changed.wait()
