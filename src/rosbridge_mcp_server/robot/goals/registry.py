"""One registry of goals per robot session: the goals running now, and the ledger of goals a drop cut off.

A goal keeps running on the robot when our connection drops: ROS 2 goals outlive the WebSocket that sent them
(the bridge's goal table is process-wide) and ROS 1 actionlib goals live in the action server. Nobody
supervises them any more, so each is cancelled once as soon as a connection is back. This is not a replay: a
cancel only stops motion, and nothing else asked for during the outage is sent.
"""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING, Final

from rosbridge_mcp_server.errors import ActionError
from rosbridge_mcp_server.robot.goals.actionlib import CANCEL_TYPE, publish_cancel
from rosbridge_mcp_server.robot.goals.caused import CausedGoal
from rosbridge_mcp_server.robot.goals.record import Goal

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient, Session

__all__ = [
    "CANCEL_CONFIRM_SECONDS",
    "CAUSED_LIMIT",
    "ORPHAN_LIMIT",
    "ORPHAN_MAX_AGE_SECONDS",
    "ROS1_CANCEL_REPEAT_SECONDS",
    "GoalRegistry",
]

logger = logging.getLogger("rosbridge_mcp_server.robot.goals")

#: At most this many goals cut off by a drop are remembered for a cancel (the oldest are forgotten).
ORPHAN_LIMIT: Final = 100
#: A goal cut off by a drop longer ago than this is not cancelled when the connection comes back: a
#: surprise cancel of something that old would stop whatever the robot is doing now.
ORPHAN_MAX_AGE_SECONDS = 300.0
#: ROS 1: the cancels are published again this long after the first time. A message published right
#: after a rospy publisher is (re)created is often lost before the action server's subscriber connects to it.
ROS1_CANCEL_REPEAT_SECONDS: Final = 1.0
#: At most this many goals started by a publish or a service call are remembered for the stops (the oldest
#: are forgotten).
CAUSED_LIMIT: Final = 100
#: How long a cancel sent after a drop waits for the connection to prove it is read.
CANCEL_CONFIRM_SECONDS: Final = 1.0


class _CutOff:
    """A goal in the ledger: since when, and the session that was open when it was cut off (maybe dying)."""

    __slots__ = ("goal", "since", "stale")

    def __init__(self, goal: Goal, since: float, stale: Session | None) -> None:
        self.goal = goal
        self.since = since
        self.stale = stale


class GoalRegistry:
    """The goals sent through one client: running ones, those a publish or a service call started (see
    :mod:`.caused`), and those a drop cut off (to be cancelled once it is back). Made once per client, by its
    :class:`~rosbridge_mcp_server.robot.session.RobotSession`: it watches the client's sessions, so a second
    registry on the same client would cancel the same goals again."""

    def __init__(self, client: RosbridgeClient) -> None:
        self.client = client
        self._running: dict[str, Goal] = {}
        self._cut_off: dict[str, _CutOff] = {}
        self._caused: dict[tuple[str, str | None], CausedGoal] = {}
        client.watch(self)

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
            self.client.run_in_background(
                self._advertise_cancel(goal.action), f"advertise {goal.action}/cancel"
            )

    def caused_goals(self) -> list[CausedGoal]:
        """The goals publishes and service calls started that no stop has cancelled yet, oldest first."""
        return list(self._caused.values())

    def forget_caused(self, goal: CausedGoal | None) -> None:
        """A stop cancelled *goal*, or it never started (the bridge refused the call)."""
        if goal is not None and self._caused.get(goal.key) is goal:
            del self._caused[goal.key]

    async def _advertise_cancel(self, action: str) -> None:
        with contextlib.suppress(Exception):
            await self.client.advertise(f"{action}/cancel", CANCEL_TYPE)

    # --- the ledger of goals cut off by a drop -----------------------------------------------------------

    def ended(self, goal_id: str) -> None:
        """The bridge said goal *goal_id* ended: nothing is left to cancel when the connection is back."""
        self._cut_off.pop(goal_id, None)

    def remember_cut_off(
        self, action: str, goal_id: str, dialect: int, *, stale: Session | None = None
    ) -> None:
        """Remember a goal that may still be running but could not be cancelled: the connection is down.

        It is cancelled once as soon as a connection to the bridge is up again (at once if one already
        is, other than *stale*, a session known to be dying), then forgotten. At most :data:`ORPHAN_LIMIT`
        are kept; one older than :data:`ORPHAN_MAX_AGE_SECONDS` is never cancelled.
        """
        if self.client.closed:
            return
        self._cut_off.pop(goal_id, None)
        self._cut_off[goal_id] = _CutOff(Goal(goal_id, action, "", dialect), time.monotonic(), stale)
        logger.warning(
            "Goal %s on %s may still be running on the robot; it will be cancelled as soon as the "
            "connection to %s is back",
            goal_id,
            action,
            self.client.url,
        )
        while len(self._cut_off) > ORPHAN_LIMIT:
            oldest = next(iter(self._cut_off.values())).goal
            del self._cut_off[oldest.goal_id]
            logger.warning(
                "More than %d goals are waiting to be cancelled; forgetting goal %s on %s without a cancel",
                ORPHAN_LIMIT,
                oldest.goal_id,
                oldest.action,
            )
        # The reconnect may already have happened (its own sweep ran before this goal was remembered).
        session = self.client.session
        if session is not None and session is not stale:
            self._sweep_in_background(session)

    def session_started(self, session: Session) -> None:
        """A connection is back: cancel the goals a drop cut off."""
        if self._cut_off:
            self._sweep_in_background(session)

    async def client_closing(self, session: Session | None) -> None:
        """Cancel our running ROS 2 goals while the connection is there; log the cut-off goals left."""
        for goal in self.running():
            if goal.dialect != 2:
                continue
            # On the main connection and on the goal's own lane: the client knows which the bridge acts on.
            await self.client.cancel_goal(goal.action, goal.goal_id, goal.lane)
        for entry in self._cut_off.values():
            logger.warning(
                "The client is closing; goal %s on %s, left running by a drop, was not cancelled",
                entry.goal.goal_id,
                entry.goal.action,
            )
        self._cut_off.clear()

    def _sweep_in_background(self, session: Session) -> None:
        self.client.run_in_background(self._sweep(session), "cancel goals cut off by a drop")

    async def _sweep(self, session: Session) -> None:
        """Cancel, once, every remembered goal *session* may reach; forget them once the bridge read it."""
        now = time.monotonic()
        version = session.info.version
        sent: list[_CutOff] = []
        for entry in list(self._cut_off.values()):
            goal = entry.goal
            if entry.stale is session or self._cut_off.get(goal.goal_id) is not entry:
                continue
            # Taken out before any await, so a second sweep running at the same time never sends it again.
            del self._cut_off[goal.goal_id]
            age = now - entry.since
            if age > ORPHAN_MAX_AGE_SECONDS:
                logger.warning(
                    "Not cancelling goal %s on %s: it was left running by a drop %.0f s ago, "
                    "too long ago for a surprise cancel",
                    goal.goal_id,
                    goal.action,
                    age,
                )
                continue
            if goal.dialect != version:
                logger.warning(
                    "Not cancelling goal %s on %s: it was sent to a ROS %d bridge and %s came back "
                    "as ROS %d, so the goal is gone",
                    goal.goal_id,
                    goal.action,
                    goal.dialect,
                    self.client.url,
                    version,
                )
                continue
            try:
                await self._send_cancel(session, goal)
            except Exception as exc:
                # The connection went again: the next one tries.
                logger.debug("Could not cancel goal %s yet: %s", goal.goal_id, exc)
                self._keep([entry, *sent], session)
                return
            sent.append(entry)
        if not sent:
            return
        # A cancel written into a socket the bridge is closing is lost: only a pong proves it was read.
        if not await session.confirm(min(CANCEL_CONFIRM_SECONDS, self.client.request_timeout)):
            self._keep(sent, session)
            return
        for entry in sent:
            logger.warning(
                "Sent a cancel for goal %s on %s, left running on the robot when the connection dropped "
                "%.1f s ago (nothing else asked for during the outage is sent)",
                entry.goal.goal_id,
                entry.goal.action,
                time.monotonic() - entry.since,
            )
        ros1 = [entry.goal for entry in sent if entry.goal.dialect == 1]
        if ros1:
            # Until the disconnect (close() too) or the repeat time, whichever comes first.
            with contextlib.suppress(TimeoutError):
                await self.client.wait_disconnected(ROS1_CANCEL_REPEAT_SECONDS)
            if self.client.session is session:
                for goal in ros1:
                    with contextlib.suppress(Exception):
                        await self._send_cancel(session, goal)

    def _keep(self, entries: list[_CutOff], session: Session) -> None:
        for entry in entries:
            if entry.goal.goal_id not in self._cut_off:
                self._cut_off[entry.goal.goal_id] = _CutOff(entry.goal, entry.since, session)

    async def _send_cancel(self, session: Session, goal: Goal) -> None:
        if goal.dialect == 2:
            await session.cancel_goal(goal.action, goal.goal_id)
        else:
            await publish_cancel(self.client, goal.action, goal.goal_id, session=session)
