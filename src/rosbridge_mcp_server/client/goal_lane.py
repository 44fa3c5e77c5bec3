"""A goal's own lane: a WebSocket opened for one action goal, carrying its feedback and result, closed after.

rosbridge 2.0.x (Humble) runs a goal inside the connection's one incoming thread until the goal ends, so a
goal on the shared connection would block every other tool and its own cancel; a lane of its own keeps the
main connection free. The lane hands its goal's frames on as typed events (``wire/goals.py``) to the goal's
:class:`~.goals.GoalHandle`, which sends its cancels. What a goal means (timeouts, its record) is
``robot/goals``.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from rosbridge_mcp_server.client.capabilities import BridgeCapabilities
from rosbridge_mcp_server.client.connection import Connection
from rosbridge_mcp_server.errors import NotConnectedError
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.goals import GoalEvent, goal_event

__all__ = ["GoalLane", "GoalLanes"]


class GoalLane:
    """One goal's connection: what the bridge says of goal ``goal_id`` of ``action`` arrives in :meth:`next`.

    ``capabilities`` are those of the bridge the goal went to (the session the lane was opened under).
    """

    def __init__(
        self,
        connection: Connection,
        action: str,
        goal_id: str,
        what: str,
        *,
        capabilities: BridgeCapabilities,
        on_close: Callable[[GoalLane], None],
    ) -> None:
        self.connection = connection
        self.action = action
        self.goal_id = goal_id
        self.capabilities = capabilities
        self._stream = connection.stream(goal_id, what)
        self._on_close = on_close

    async def send_goal(self, action_type: str, goal: dict[str, Any]) -> None:
        """Send the goal itself (with feedback) on the lane, under the lane's goal id."""
        await self.connection.send(
            protocol.send_action_goal(self.action, action_type, goal, id=self.goal_id, feedback=True)
        )

    async def next(self) -> GoalEvent:
        """The next thing the bridge said of the goal: feedback, its end, or a refusal (typed events).

        :class:`ConnectionLostError` when the lane drops (the goal keeps running on the robot).
        """
        item = await self._stream.queue.get()
        if isinstance(item, BaseException):
            raise item
        return goal_event(*item)

    def close(self) -> None:
        """Stop listening and close the lane in the background."""
        self.connection.forget(self.goal_id)
        self._on_close(self)


class GoalLanes:
    """The goal lanes open now: opened through *open_lane*, closed through *close* when a goal ends."""

    def __init__(
        self,
        url: str,
        open_lane: Callable[[float], Awaitable[Connection]],
        close: Callable[[Connection], None],
    ) -> None:
        self._url = url
        self._open_lane = open_lane
        self._close = close
        self._open: set[GoalLane] = set()

    async def open(
        self, action: str, goal_id: str, what: str, capabilities: BridgeCapabilities, timeout: float
    ) -> GoalLane:
        """A connection of its own for goal *goal_id* of *action*, opened within *timeout*; ``lane.close()``
        after."""
        try:
            conn = await self._open_lane(timeout)
        except NotConnectedError as exc:
            raise NotConnectedError(self._url, f"could not open a lane for the goal: {exc.reason}") from None
        lane = GoalLane(conn, action, goal_id, what, capabilities=capabilities, on_close=self._forget)
        self._open.add(lane)
        return lane

    def _forget(self, lane: GoalLane) -> None:
        self._open.discard(lane)
        self._close(lane.connection)

    def take_all(self) -> list[Connection]:
        """Every open lane's connection, for the caller to close; the lanes are forgotten."""
        connections = [lane.connection for lane in self._open]
        self._open.clear()
        return connections
