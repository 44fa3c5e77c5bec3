"""One registry of goals per robot session: the goals running now, and those a publish or a service call
started, which the stops read.

What a drop leaves running on the robot is the client's to cancel once a connection is back
(``client.goals``): this registry only says what the goals are.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator
from typing import TYPE_CHECKING, Final

from rosbridge_mcp_server.errors import ActionError
from rosbridge_mcp_server.robot.goals.caused import CausedGoal
from rosbridge_mcp_server.robot.goals.record import Goal

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient

__all__ = ["CAUSED_LIMIT", "GoalRegistry"]

logger = logging.getLogger("rosbridge_mcp_server.robot.goals")

#: At most this many goals started by a publish or a service call are remembered for the stops (the oldest
#: are forgotten).
CAUSED_LIMIT: Final = 100


class GoalRegistry:
    """The goals sent through one client: running ones, and those a publish or a service call started (see
    :mod:`.caused`). Made once per client, by its
    :class:`~rosbridge_mcp_server.robot.session.RobotSession`."""

    def __init__(self, client: RosbridgeClient) -> None:
        self.client = client
        self._running: dict[str, Goal] = {}
        self._caused: dict[tuple[str, str | None], CausedGoal] = {}

    # --- running goals ----------------------------------------------------------------------------------

    @contextlib.contextmanager
    def tracking(self, goal: Goal) -> Iterator[Goal]:
        """*goal* is running for the duration; :class:`ActionError` if its id is already in use."""
        if goal.goal_id in self._running:
            raise ActionError(goal.action, f"goal id {goal.goal_id!r} is already in use by a running goal")
        self._running[goal.goal_id] = goal
        try:
            yield goal
        finally:
            if self._running.get(goal.goal_id) is goal:
                del self._running[goal.goal_id]

    def running(self, action: str | None = None) -> list[Goal]:
        """Goals running now (all, or those of *action*)."""
        return [g for g in self._running.values() if action is None or g.action == action]

    # --- goals a publish or a service call started ------------------------------------------------------

    def caused(self, goal: CausedGoal | None) -> None:
        """Remember *goal*, started by a publish or a service call, until a stop cancels it (``None``: the act
        started no goal). At most :data:`CAUSED_LIMIT` are kept, the newest."""
        if goal is None:
            return
        self._caused.pop(goal.key, None)
        self._caused[goal.key] = goal
        while len(self._caused) > CAUSED_LIMIT:
            oldest = self._caused.pop(next(iter(self._caused)))
            logger.warning(
                "More than %d goals sent by publish or service call; forgetting %s for the stops",
                CAUSED_LIMIT,
                oldest.describe(),
            )
        if goal.dialect == 1:
            # A message published right after a rospy publisher is created is often lost: the cancel topic is
            # advertised now, so that a stop's cancel goes out on a publisher the action server already hears.
            self.client.goals.prepare_cancel(goal.action)

    def caused_goals(self) -> list[CausedGoal]:
        """The goals publishes and service calls started that no stop has cancelled yet, oldest first."""
        return list(self._caused.values())

    def forget_caused(self, goal: CausedGoal | None) -> None:
        """A stop cancelled *goal*, or it never started (the bridge refused the call)."""
        if goal is not None and self._caused.get(goal.key) is goal:
            del self._caused[goal.key]
