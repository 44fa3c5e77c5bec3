"""What this server session set going on the robot, so that ``stop_robot`` can stop exactly that.

Three things are remembered here: the topics on which a velocity command (Twist / TwistStamped) was
published, with their type, the publish streams still running, and the closing zeros a drop kept from the
robot (owed until the connection is back). Goals are remembered by the goal registry, which
knows which goals this session started and which still run, whatever carried them (a goal topic, a goal pose,
a ``send_goal`` call: ``robot/goals/caused.py``).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Awaitable, Iterator
from dataclasses import dataclass, field
from typing import Any

from rosbridge_mcp_server.robot.arm_stop import TrajectorySent, trajectory_sent
from rosbridge_mcp_server.robot.velocity import is_velocity_type, stamped

__all__ = ["OwedZero", "SessionActivity", "Stream", "VelocityTopic"]

_log = logging.getLogger(__name__)


@dataclass
class VelocityTopic:
    """A topic this session sent velocity commands on, and how (type as sent, the last frame id)."""

    topic: str
    type: str
    frame_id: str = ""


#: An owed zero older than this is forgotten (the robot's own timeout, or a person, has long acted by then).
OWED_MAX_AGE_SECONDS = 300.0


@dataclass(frozen=True)
class OwedZero:
    """A zero velocity command that could not be sent (the connection was down: a stream's closing zero, a
    stop's): it goes out once the connection is back (``robot/owed_zeros.py``), stamped then, unless a later
    message on the topic replaced it."""

    topic: str
    type: str
    frame_id: str
    since: float


@dataclass
class Stream:
    """A running publish stream: what it publishes, the task that runs it, and stop_robot's request to end.

    A stream loop waits with :meth:`pause` instead of ``asyncio.sleep``: it returns early, with ``True``, once
    stop_robot asks the stream to stop; the loop then ends as it would at its planned end (a velocity stream
    sends its closing zero) and the tool answers normally, saying it was stopped.
    """

    topic: str
    type: str
    task: asyncio.Task[Any]
    stop_requested: asyncio.Event = field(default_factory=asyncio.Event)
    ended: asyncio.Event = field(default_factory=asyncio.Event)
    #: Who asked it to stop, for its answer ("stop_robot", or "E-STOP on the operator console").
    stopped_by: str = ""

    async def unless_stopped(self, step: Awaitable[Any]) -> bool:
        """Run *step* unless stop_robot asks this stream to stop first (then *step* is cancelled); ``True``
        when it was asked."""
        if self.stop_requested.is_set():
            if asyncio.iscoroutine(step):
                step.close()
            return True
        work = asyncio.ensure_future(step)
        asked = asyncio.ensure_future(self.stop_requested.wait())
        try:
            await asyncio.wait({work, asked}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            asked.cancel()
            if not work.done():
                work.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await work
        if work.cancelled():
            return True
        work.result()  # what the step raised, if anything
        return False

    async def pause(self, seconds: float) -> bool:
        """Wait up to ``seconds``; ``True`` (at once) when stop_robot asked this stream to stop."""
        if self.stop_requested.is_set():
            return True
        if seconds <= 0:
            return False
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(seconds):
                await self.stop_requested.wait()
        return self.stop_requested.is_set()


class SessionActivity:
    """The velocity topics published to and the streams running, for one server session."""

    def __init__(self) -> None:
        self._velocity: dict[str, VelocityTopic] = {}
        self._streams: list[Stream] = []
        self._trajectories: dict[str, TrajectorySent] = {}
        self._owed: dict[str, OwedZero] = {}
        self._sent: dict[str, int] = {}

    def owe_zero(self, topic: str, type_name: str, frame_id: str = "") -> None:
        """A zero command of *type_name* on *topic* could not be sent: owe it."""
        self._owed[topic] = OwedZero(topic, type_name, frame_id, time.monotonic())

    def owed_zeros(self) -> list[OwedZero]:
        """The zeros still owed (those owed too long ago are forgotten)."""
        now = time.monotonic()
        for topic in [t for t, owed in self._owed.items() if now - owed.since > OWED_MAX_AGE_SECONDS]:
            del self._owed[topic]
        return list(self._owed.values())

    def zero_paid(self, owed: OwedZero) -> None:
        """*owed* was sent (or replaced by a later message on its topic)."""
        if self._owed.get(owed.topic) is owed:
            del self._owed[owed.topic]

    def sent_on(self, topic: str) -> int:
        """How many messages this session has sent on *topic* (that :meth:`published` was told of)."""
        return self._sent.get(topic, 0)

    def published(self, topic: str, type_name: str, message: Any) -> None:
        """Note a message that reached the bridge; only velocity commands and joint trajectories (on a
        controller's topic: ``robot/arm_stop.py``) are remembered."""
        self._sent[topic] = self._sent.get(topic, 0) + 1
        sent = trajectory_sent(topic, type_name, message, time.monotonic())
        if sent is not None:
            self._trajectories[topic] = sent
        self._owed.pop(topic, None)  # a later message on the topic replaces the zero owed there
        if not is_velocity_type(type_name):
            return
        frame_id = ""
        if stamped(type_name) and isinstance(message, dict):
            header = message.get("header")
            if isinstance(header, dict) and isinstance(header.get("frame_id"), str):
                frame_id = header["frame_id"]
        self._velocity[topic] = VelocityTopic(topic, type_name, frame_id)

    @property
    def velocity_topics(self) -> list[VelocityTopic]:
        return list(self._velocity.values())

    @property
    def trajectories(self) -> list[TrajectorySent]:
        """The last joint trajectory published on each topic (a stop holds those still running)."""
        return list(self._trajectories.values())

    def forget_trajectory(self, topic: str) -> None:
        """*topic*'s trajectory was stopped (a later stop need not hold it again)."""
        self._trajectories.pop(topic, None)

    @contextlib.contextmanager
    def stream(self, topic: str, type_name: str, task: asyncio.Task[Any] | None = None) -> Iterator[Stream]:
        """Register a running stream for the ``with`` block (``task``, default the current one, is what
        stop_robot cancels if the stream does not end when asked)."""
        runner = task if task is not None else asyncio.current_task()
        if runner is None:
            raise RuntimeError("a stream must run in an asyncio task")
        entry = Stream(topic, type_name, runner)
        self._streams.append(entry)
        try:
            yield entry
        finally:
            self._streams.remove(entry)
            entry.ended.set()

    @property
    def streams(self) -> list[Stream]:
        return list(self._streams)

    async def stop_streams(self, timeout: float, by: str) -> tuple[list[Stream], list[Stream]]:
        """Ask every stream to stop (``by`` is who asks) and wait up to ``timeout`` s; returns (ended, still
        running).

        A stream that has not ended when asked is cancelled halfway through the wait: stopping must not
        depend on the stream's loop looking at the request.
        """
        streams = self.streams
        for entry in streams:
            entry.stopped_by = by
            entry.stop_requested.set()
        if streams:
            await self._wait_ended(streams, timeout / 2)
            for entry in streams:
                if not entry.ended.is_set():
                    entry.task.cancel()
            await self._wait_ended(streams, timeout / 2)
        ended = [entry for entry in streams if entry.ended.is_set()]
        running = [entry for entry in streams if not entry.ended.is_set()]
        return ended, running

    @staticmethod
    async def _wait_ended(streams: list[Stream], timeout: float) -> None:
        waiters = [asyncio.ensure_future(entry.ended.wait()) for entry in streams if not entry.ended.is_set()]
        if not waiters:
            return
        try:
            await asyncio.wait(waiters, timeout=timeout)
        finally:
            for waiter in waiters:
                waiter.cancel()
