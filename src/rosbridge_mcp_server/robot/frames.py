"""Listening to ``/tf`` and ``/tf_static`` until a transform between two frames can be answered.

``/tf_static`` is latched (ROS 1) / transient-local (ROS 2), so its links arrive as soon as we subscribe;
``/tf`` links arrive at the publishers' rates. Both subscriptions are closed afterwards.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rosbridge_mcp_server.errors import RequestTimeoutError
from rosbridge_mcp_server.robot.transforms import FrameTree, Lookup, TransformError

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["TF_TOPICS", "FoundTransform", "look_up_transform"]

TF_TOPICS = ("/tf", "/tf_static")


@dataclass(frozen=True)
class FoundTransform:
    """A look-up and how old its newest moving link was when answered (``None``: static links only)."""

    lookup: Lookup
    age: float | None
    waited: float


async def look_up_transform(
    client: RosbridgeClient, graph: RosGraph, target: str, source: str, *, timeout: float
) -> FoundTransform:
    """``target ← source`` from the links heard within ``timeout``; else :class:`TransformError`."""
    types = {topic: await graph.topic_type(topic) for topic in TF_TOPICS}
    present = {topic: msg_type for topic, msg_type in types.items() if msg_type}
    if not present:
        raise TransformError("Neither /tf nor /tf_static is in the ROS graph: nothing publishes transforms.")
    tree = FrameTree()
    start = time.monotonic()
    changed = asyncio.Event()
    last_error: TransformError | None = None

    async def pump(topic: str, msg_type: str) -> None:
        async with client.subscribe(topic, msg_type, max_queue=100) as sub:
            while True:
                message = await sub.get()
                if tree.add_message(message, static=topic == "/tf_static", received=time.monotonic()):
                    changed.set()

    tasks = [asyncio.create_task(pump(topic, msg_type)) for topic, msg_type in present.items()]
    try:
        deadline = start + timeout
        while True:
            try:
                found = tree.lookup(target, source)
            except TransformError as exc:
                last_error = exc
            else:
                now = time.monotonic()
                age = None if found.newest_received is None else now - found.newest_received
                return FoundTransform(found, age, now - start)
            left = deadline - time.monotonic()
            if left <= 0:
                break
            changed.clear()
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(left):
                    await _first_of(changed, tasks)
    finally:
        for task in tasks:
            task.cancel()
        # Shielded unsubscribes run in each task's own `async with` exit.
        await asyncio.gather(*tasks, return_exceptions=True)
    assert last_error is not None
    raise TransformError(f"Within {timeout:g} s: {last_error}") from None


async def _first_of(changed: asyncio.Event, tasks: list[asyncio.Task[None]]) -> None:
    """Wait for a new link, or for a listener that failed (its error is raised)."""
    waiter = asyncio.create_task(changed.wait())
    try:
        done, _ = await asyncio.wait([waiter, *tasks], return_when=asyncio.FIRST_COMPLETED)
    finally:
        waiter.cancel()
    for task in done:
        if task is not waiter and task.exception() is not None:
            error = task.exception()
            if isinstance(error, RequestTimeoutError):
                continue
            assert error is not None
            raise error
