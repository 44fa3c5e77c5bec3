"""Whether a published message reached anyone: the topic's subscribers, looked up beside the publish.

rosbridge takes a publish on any topic, subscribed or not, and answers nothing, so a misspelt topic
(``/turtle1/cmd_vell``) would read as plain success. A topic this connection saw subscribed within
:data:`FRESH` seconds is taken as still subscribed (a teleop loop asks once, not per message); otherwise the
look-up (rosapi ``subscribers``) runs while the message is checked and sent, so the publish waits for no
round trip of its own. When the look-up has not answered :data:`LATE` after the publish, or fails, the
answer says nothing about who heard it.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator
from dataclasses import dataclass, field
from typing import Final

from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.names import absolute_name, did_you_mean
from rosbridge_mcp_server.tools.base import ToolContext

__all__ = ["FRESH", "LATE", "Audience", "audience"]

#: Longest wait for the subscribers once the message is sent, seconds.
LATE: Final = 1.0
#: How long subscribers seen on a topic are taken as still there, seconds.
FRESH: Final = 5.0


@dataclass
class Audience:
    """The topic's subscribers as they were while the message went out (``None``: not known)."""

    lookup: asyncio.Task[tuple[str, ...]] | None = None
    subscribers: tuple[str, ...] | None = field(default=None)

    @property
    def count(self) -> int | None:
        return None if self.subscribers is None else len(self.subscribers)

    async def nobody_text(self, ctx: ToolContext, topic: str) -> str:
        """``But nothing subscribes to /x: no node received it. Did you mean /y?``, when none does."""
        if self.subscribers != ():
            return ""
        known = ctx.graph.recent_topics(60.0)
        if known is None:
            with contextlib.suppress(RosbridgeError):
                known = await ctx.graph.topics()
        near = did_you_mean(topic, [entry.name for entry in known or () if entry.name != topic])
        return f"But nothing subscribes to {topic}: no node received it.{near}"


@contextlib.asynccontextmanager
async def audience(ctx: ToolContext, topic: str) -> AsyncIterator[Audience]:
    """Look up *topic*'s subscribers while the body publishes; the result is known when the block ends."""
    heard = Audience()
    try:
        name = absolute_name(topic, "topic")
    except RosbridgeError:
        yield heard  # the publish names what is wrong with the name
        return
    if (recent := ctx.graph.recent_subscribers(name, FRESH)) is not None:
        heard.subscribers = recent
        yield heard
        return
    heard.lookup = asyncio.create_task(ctx.graph.subscribers(name))
    try:
        yield heard
    except BaseException:
        heard.lookup.cancel()
        heard.lookup.add_done_callback(lambda task: task.cancelled() or task.exception())
        raise
    with contextlib.suppress(RosbridgeError, TimeoutError):
        heard.subscribers = await asyncio.wait_for(heard.lookup, LATE)
