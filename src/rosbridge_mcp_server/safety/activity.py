"""What this server session set going on the robot, so that ``stop_robot`` can stop exactly that.

Two things are remembered here: the topics on which a velocity command (Twist / TwistStamped) was published,
with their type, and the publish streams still running. Goals are remembered by the goal registry, which
already knows which goals this session started and which still run.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from rosbridge_mcp_server.safety.velocity import is_velocity_type, stamped

__all__ = ["SessionActivity", "Stream", "VelocityTopic"]

_log = logging.getLogger("rosbridge_mcp_server.safety")


@dataclass
class VelocityTopic:
    """A topic this session sent velocity commands on, and how (type as sent, the last frame id)."""

    topic: str
    type: str
    frame_id: str = ""


@dataclass
class Stream:
    """A running publish stream: the task that runs it, and what it publishes."""

    topic: str
    type: str
    task: asyncio.Task[Any]
    stopped_by_estop: bool = field(default=False)


class SessionActivity:
    """The velocity topics published to and the streams running, for one server session."""

    def __init__(self) -> None:
        self._velocity: dict[str, VelocityTopic] = {}
        self._streams: dict[asyncio.Task[Any], Stream] = {}
        self._estopped: set[asyncio.Task[Any]] = set()

    def published(self, topic: str, type_name: str, message: Any) -> None:
        """Note a message that reached the bridge; only velocity commands are remembered."""
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

    @contextlib.contextmanager
    def stream(self, topic: str, type_name: str, task: asyncio.Task[Any] | None = None) -> Iterator[Stream]:
        """Register a running stream for the ``with`` block; ``task`` (default: the current one) is what
        ``stop_robot`` cancels."""
        runner = task if task is not None else asyncio.current_task()
        if runner is None:
            raise RuntimeError("a stream must run in an asyncio task")
        entry = Stream(topic, type_name, runner)
        self._streams[runner] = entry
        try:
            yield entry
        finally:
            self._streams.pop(runner, None)

    @property
    def streams(self) -> list[Stream]:
        return list(self._streams.values())

    def stopped_by_estop(self, task: asyncio.Task[Any] | None = None) -> bool:
        """Whether ``stop_robot`` cancelled ``task`` (default: the current task): it ended on purpose."""
        runner = task if task is not None else asyncio.current_task()
        return runner in self._estopped

    async def stop_streams(self, timeout: float) -> tuple[list[Stream], list[Stream]]:
        """Cancel every stream, wait up to ``timeout`` s for them to end; returns (ended, still running)."""
        streams = self.streams
        for entry in streams:
            entry.stopped_by_estop = True
            self._estopped.add(entry.task)
            entry.task.cancel()
        tasks = [entry.task for entry in streams]
        if tasks:
            await asyncio.wait(tasks, timeout=timeout)
        ended = [entry for entry in streams if entry.task.done()]
        running = [entry for entry in streams if not entry.task.done()]
        for entry in ended:
            self._estopped.discard(entry.task)
        return ended, running
