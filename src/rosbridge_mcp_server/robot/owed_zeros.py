"""The zero commands a drop kept from the robot, sent once the connection is back.

A velocity stream ends with an all-zero command, also when it is cancelled or fails (``robot/acting/
streams.py``), and a stop sends one on every velocity topic used (``safety/estop.py``); when the connection
is down at that moment the zero cannot be sent, and the robot's last command is still a moving one. It is
owed instead (``SessionActivity.owe_zero``); this session watcher sends every zero still owed after each
reconnect, stamped then, before anything else of this server on the topic (a later message there replaces
it), as the client cancels the goals a drop cut off. On ROS 1 each goes once more
:data:`ROS1_REPEAT_SECONDS` later, unless this server sent something else on the topic meanwhile: rospy often
loses a message published right after its publisher is created, and the publisher is new on this connection
(the client's cancels of cut-off goals go twice for the same reason). Owed zeros older than
:data:`~rosbridge_mcp_server.robot.activity.OWED_MAX_AGE_SECONDS` are forgotten.
"""

from __future__ import annotations

import asyncio
import logging
import time
from typing import TYPE_CHECKING

from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.velocity import zero_command

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient, SessionFacts
    from rosbridge_mcp_server.robot.activity import OwedZero, SessionActivity

__all__ = ["ROS1_REPEAT_SECONDS", "OwedZeros"]

_log = logging.getLogger(__name__)

#: How long the sending waits for the new connection to be the current one.
_CONNECTED_WAIT = 5.0
#: ROS 1: an owed zero goes once more this long after (a new rospy publisher's first message is often lost).
ROS1_REPEAT_SECONDS = 1.0


class OwedZeros:
    """A session watcher that sends the zeros owed when a connection starts."""

    def __init__(self, client: RosbridgeClient, activity: SessionActivity) -> None:
        self._client = client
        self._activity = activity
        self._task: asyncio.Task[None] | None = None

    def session_started(self, session: SessionFacts) -> None:
        """Send what is owed on the new connection (nothing to do on most)."""
        if self._activity.owed_zeros():
            repeat = session.dialect.version == 1
            self._task = self._client.run_in_background(
                self._pay(session.number, repeat=repeat), "send owed zeros"
            )

    async def client_closing(self, session: SessionFacts | None) -> None:
        """Stop sending: the client is closing."""
        if self._task is not None:
            self._task.cancel()

    async def _pay(self, number: int, *, repeat: bool) -> None:
        try:
            await self._client.wait_connected(_CONNECTED_WAIT)
            paid = []
            for owed in self._activity.owed_zeros():
                await self._send(owed)
                paid.append((owed, self._activity.sent_on(owed.topic)))
                self._activity.zero_paid(owed)
                _log.warning("sent the zero command on %s that a drop kept from the robot", owed.topic)
            if not repeat or not paid:
                return
            await asyncio.sleep(ROS1_REPEAT_SECONDS)
            for owed, count in paid:
                if self._activity.sent_on(owed.topic) == count:  # nothing of ours there since: once more
                    await self._send(owed)
        except RosbridgeError as exc:  # down again: still owed, sent on the next connection
            _log.info("the zeros owed could not be sent on connection %d yet: %s", number, exc)

    async def _send(self, owed: OwedZero) -> None:
        await self._client.publish(owed.topic, owed.type, zero_command(owed.type, time.time(), owed.frame_id))
