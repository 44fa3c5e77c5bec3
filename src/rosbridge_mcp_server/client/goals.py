"""The client's goals: a :class:`GoalHandle` per goal it sends, every goal cancel it sends, and the goals a
drop cut off.

A goal keeps running on the robot when our connection drops: ROS 2 goals outlive the WebSocket that sent them
(the bridge's goal table is process-wide) and ROS 1 actionlib goals live in the action server. Nobody
supervises them any more, so each is cancelled once as soon as a connection is back. This is not a replay: a
cancel only stops motion, and nothing else asked for during the outage is sent.

Every cancel the client sends goes through this module, in four functions: :meth:`GoalHandle.cancel` (our
goal, on every connection the bridge may need), :meth:`ClientGoals.cancel` (another client's goal, or every
goal of an action), :meth:`ClientGoals._sweep` (the goals a drop cut off, once a connection is back) and
:meth:`ClientGoals._send_cancel` (the one place a cancel is written). What a goal means (its timeout, its
record, the registry the stops read) is ``robot/goals``'.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final

from rosbridge_mcp_server.client.actionlib import CANCEL_TYPE, ActionlibGoal, GoalsHost, cancel_message
from rosbridge_mcp_server.client.cut_off import ORPHAN_LIMIT, CutOff, not_to_cancel
from rosbridge_mcp_server.client.goal_lane import GoalLane, GoalLanes
from rosbridge_mcp_server.client.session import BridgeSession, send_quietly
from rosbridge_mcp_server.errors import ActionError, ConnectionLostError, NotConnectedError
from rosbridge_mcp_server.wire import protocol
from rosbridge_mcp_server.wire.goals import GoalEnded, GoalEvent, GoalNeverRan

__all__ = [
    "CANCEL_CONFIRM_SECONDS",
    "ROS1_CANCEL_REPEAT_SECONDS",
    "ClientGoals",
    "GoalCancel",
    "GoalHandle",
    "OthersCancel",
]

logger = logging.getLogger("rosbridge_mcp_server.client")

#: ROS 1: a cancel on a new publisher is published again this long after: a message published right after a
#: rospy publisher is (re)created is often lost before the action server's subscriber connects to it.
ROS1_CANCEL_REPEAT_SECONDS: Final = 1.0
#: How long a cancel sent after a drop waits for the connection to prove it is read.
CANCEL_CONFIRM_SECONDS: Final = 1.0
#: How long the main connection takes a refusal of our own goal's cancel as expected (not logged).
_REFUSAL_SECONDS: Final = 5.0
_ZERO_UUID: Final = [0] * 16


@dataclass(frozen=True, slots=True)
class GoalCancel:
    """Where a goal's cancel went: on the main connection, on the goal's own lane, and whether one of them
    surely reaches the goal on this bridge (else the goal is cancelled again once a connection is back)."""

    on_main: bool
    on_lane: bool
    reaches: bool

    @property
    def sent(self) -> bool:
        """The cancel went out on at least one connection."""
        return self.on_main or self.on_lane


@dataclass(frozen=True, slots=True)
class OthersCancel:
    """What the bridge or the action server answered a cancel of goals not ours (ROS 2): the bridge's refusal
    of a cancel by rosbridge id, or ``<action>/_action/cancel_goal``'s answer (``goals_canceling`` as the
    server sent them, its ``return_code``)."""

    refused: str | None = None
    goals_canceling: list[Any] | None = None
    return_code: int | None = None


class GoalHandle:
    """One goal this client sent (ROS 2: on a lane of its own; ROS 1: over actionlib's topics): what the
    bridge says of it as typed events (:meth:`next`), its cancel (:meth:`cancel`), :meth:`aclose` after."""

    def __init__(self, goals: ClientGoals, action: str, goal_id: str, version: int) -> None:
        self._goals = goals
        self.action = action
        self.goal_id = goal_id
        #: The ROS version of the bridge the goal went to.
        self.version = version
        self.lane: GoalLane | None = None
        self.topics: ActionlibGoal | None = None
        #: The goal's own connection dropped (ROS 2) or the subscriptions did (ROS 1).
        self.dropped = False

    @property
    def last_status(self) -> int:
        """ROS 1: the goal's last status on ``<ns>/status`` (0 pending); ROS 2: 0."""
        return self.topics.progress.code if self.topics is not None else 0

    async def next(self) -> GoalEvent:
        """The next thing the bridge said of the goal: feedback, its end, a goal that never ran, a refusal.

        :class:`ConnectionLostError` when the goal's connection drops (the goal keeps running on the robot).
        """
        source = self.lane or self.topics
        if source is None:
            raise RuntimeError("the goal was not started")
        try:
            event = await source.next()
        except ConnectionLostError:
            self.dropped = True
            raise
        if isinstance(event, GoalEnded | GoalNeverRan):
            self._goals.ended(self.goal_id)
        return event

    async def cancel(self) -> GoalCancel:
        """Cancel the goal on every connection the bridge may need it on; what reached it.

        ROS 2, the main connection first: on a bridge whose goals hold their connection up (2.1.0's and
        Humble's defaults) the goal's own lane reads its copy only after the goal ended. The lane's copy is
        for a bridge that lets only the starting connection cancel (rosbridge-server-rs, which refuses the
        main connection's copy with an error ``status``: expected here, so not logged). Once the lane dropped,
        the main connection's copy counts only when a ping on it is answered (the whole bridge may be going).
        A cancel that surely reaches nothing is kept: it is sent again as soon as a connection is back.
        """
        goals, host = self._goals, self._goals.host
        session = host.session
        lane = self.lane
        if self.version == 1:
            sent = await goals._send_cancel(session, self.action, self.goal_id, 1)
            outcome = GoalCancel(sent, False, sent)
        elif self.dropped:
            on_main = session is not None and await goals._send_cancel(session, self.action, self.goal_id, 2)
            confirm = min(CANCEL_CONFIRM_SECONDS, host.request_timeout)
            reached = session is not None and on_main and await session.confirm(confirm)
            outcome = GoalCancel(on_main, False, reached)
        else:
            if session is not None and session.capabilities.status_replies:
                conn = session.connection
                conn.expect(self.goal_id, f"the refusal of goal {self.goal_id}'s cancel", _REFUSAL_SECONDS)
                asyncio.get_running_loop().call_later(_REFUSAL_SECONDS, conn.forget, self.goal_id)
            on_main = session is not None and await goals._send_cancel(session, self.action, self.goal_id, 2)
            on_lane = lane is not None and await goals._send_cancel(
                None, self.action, self.goal_id, 2, on=lane
            )
            caps = lane.capabilities if lane else session.capabilities if session else None
            reaches = caps is not None and (
                (on_main and not caps.cancel_by_owner_only) or (on_lane and not caps.goals_hold_connection)
            )
            outcome = GoalCancel(on_main, on_lane, reaches)
        if not outcome.reaches:
            # After a drop (ROS 2) the session the cancel went on may be the dying one: not swept on it.
            stale = session if self.dropped and self.version == 2 else None
            goals.remember(self.action, self.goal_id, self.version, stale=stale)
        return outcome

    async def aclose(self) -> None:
        """Stop listening to the goal; its connection (ROS 2) or subscriptions (ROS 1) close."""
        self._goals.forget(self)
        if self.lane is not None:
            self.lane.close()
        if self.topics is not None:
            await self.topics.aclose()


class ClientGoals:
    """The goals of one client: those open now (by goal id), and the ledger of goals a drop cut off."""

    def __init__(self, host: GoalsHost, lanes: GoalLanes) -> None:
        self.host = host
        self.lanes = lanes
        self._open: dict[str, GoalHandle] = {}
        self._cut_off: dict[str, CutOff] = {}

    # --- goals open now ------------------------------------------------------------------------------

    async def start(
        self,
        action: str,
        action_type: str,
        goal: dict[str, Any],
        *,
        goal_id: str | None = None,
        timeout: float,
        check: Callable[[], None] | None = None,
    ) -> GoalHandle:
        """Send *goal* to *action* (*action_type* as the bridge spells it) and return its handle, open until
        ``aclose()``; see :meth:`RosbridgeClient.start_goal`."""
        session = self.host.require_session()
        version = session.info.version
        gid = goal_id if goal_id is not None else self.host.new_goal_id(action)
        if version == 2 and not session.capabilities.action_ops:
            raise ActionError(action, "this bridge has no action ops")
        handle = GoalHandle(self, action, gid, version)
        # Open before anything is sent: a cancel meanwhile reaches it.
        self._open[gid] = handle
        try:
            if version == 1:
                handle.topics = ActionlibGoal(self.host, action, action_type, gid)
                await handle.topics.open(timeout)
                await handle.topics.send(goal, check)
            else:
                what = f"action goal {gid} on {action}"
                handle.lane = await self.lanes.open(action, gid, what, session.capabilities, timeout)
                if check is not None:
                    check()
                await handle.lane.send_goal(action_type, goal)
        except BaseException:
            await asyncio.shield(handle.aclose())
            raise
        return handle

    def handle(self, goal_id: str) -> GoalHandle | None:
        """The open goal *goal_id* of this client, if any."""
        return self._open.get(goal_id)

    def forget(self, handle: GoalHandle) -> None:
        """*handle* is closed."""
        if self._open.get(handle.goal_id) is handle:
            del self._open[handle.goal_id]

    def prepare_cancel(self, action: str) -> None:
        """ROS 1: advertise ``<action>/cancel`` now, in the background, so that a later cancel goes out on a
        publisher the action server already hears (the first message of a new one is often lost)."""

        async def advertise() -> None:
            with contextlib.suppress(Exception):
                await self.host.advertise(f"{action}/cancel", CANCEL_TYPE)

        self.host.run_in_background(advertise(), f"advertise {action}/cancel")

    async def cancel(self, action: str, goal_id: str | None, *, timeout: float) -> OthersCancel:
        """Cancel a goal not ours (by id), or every goal of *action* (``None``).

        ROS 1: an ``actionlib_msgs/GoalID`` on ``<action>/cancel`` (an empty id cancels every goal), once more
        a moment later on a new publisher. ROS 2: a goal UUID (32 hex digits), or every goal, through the
        action server's own ``<action>/_action/cancel_goal`` (:class:`ServiceError` as it comes); a rosbridge
        id on the main connection, with the bridge's refusal if it comes before the answer to a call sent
        after it (within *timeout*; rosbridge_suite cancels silently, rosbridge-server-rs refuses another
        connection's goal, which is then learnt: ``cancel_by_owner_only``). :class:`NotConnectedError` when
        the cancel could not be sent.
        """
        session = self.host.require_session()
        if session.info.version == 1:
            fresh = f"{action}/cancel" not in session.connection.advertised
            if not await self._send_cancel(session, action, goal_id or "", 1, repeat=fresh):
                raise NotConnectedError(self.host.url, f"could not publish on {action}/cancel")
            return OthersCancel()
        uuid = _uuid_bytes(goal_id) if goal_id is not None else _ZERO_UUID
        if uuid is not None:
            stamp = {"sec": 0, "nanosec": 0}
            values = await self.host.call_service(
                f"{action}/_action/cancel_goal", {"goal_info": {"goal_id": {"uuid": uuid}, "stamp": stamp}}
            )
            canceling = values.get("goals_canceling") if isinstance(values, dict) else None
            code = values.get("return_code") if isinstance(values, dict) else None
            return OthersCancel(
                goals_canceling=canceling if isinstance(canceling, list) else None,
                return_code=code if isinstance(code, int) else None,
            )
        assert goal_id is not None
        conn = session.connection
        heard = conn.expect(goal_id, f"a refusal of the cancel of goal {goal_id}", timeout)
        try:
            if not await self._send_cancel(session, action, goal_id, 2):
                raise NotConnectedError(self.host.url, f"could not send the cancel of goal {goal_id}")
            if not heard.done():
                await session.handled(timeout)
            if not heard.done() or heard.cancelled() or heard.exception() is not None:
                return OthersCancel()
            frame = heard.result()
        finally:
            conn.forget(goal_id)
        session.learn_cancel_by_owner_only()
        return OthersCancel(refused=str(frame.get("msg") or "the bridge refused the cancel"))

    async def _send_cancel(
        self,
        session: BridgeSession | None,
        action: str,
        goal_id: str,
        version: int,
        *,
        on: GoalLane | None = None,
        after: float = 0.0,
        repeat: bool = False,
    ) -> bool:
        """Write one cancel: ROS 2 ``cancel_action_goal`` on *session*'s connection or the goal's lane *on*,
        ROS 1 a ``GoalID`` on ``<action>/cancel`` (on the current session when *session* is None); False when
        it could not be sent. *after*: first wait this long, and send only if *session* is still the one up.
        *repeat* (ROS 1): send it once more :data:`ROS1_CANCEL_REPEAT_SECONDS` later, in the background."""
        host = self.host
        if after:
            with contextlib.suppress(TimeoutError):
                await host.wait_disconnected(after)
            if session is None or host.session is not session:
                return False  # the connection went: the ledger's cancels after a drop take over
        if version == 2:
            conn = on.connection if on is not None else session.connection if session is not None else None
            sent = await send_quietly(conn, protocol.cancel_action_goal(action, id=goal_id))
            if sent and on is None:
                host.unhandled_acts = True
            return sent
        try:
            await host.publish(f"{action}/cancel", CANCEL_TYPE, cancel_message(goal_id), session=session)
        except Exception as exc:
            logger.debug("Could not send a cancel for goal %r on %s: %s", goal_id, action, exc)
            return False
        if repeat:
            again = self._send_cancel(
                session or host.session, action, goal_id, 1, after=ROS1_CANCEL_REPEAT_SECONDS
            )
            host.run_in_background(again, f"repeat the cancel on {action}")
        return True

    # --- the ledger of goals cut off by a drop -----------------------------------------------------------

    @property
    def cut_off(self) -> list[str]:
        """The ids of the goals waiting for a connection to be cancelled on (diagnostics and tests)."""
        return list(self._cut_off)

    def ended(self, goal_id: str) -> None:
        """The bridge said goal *goal_id* ended: nothing is left to cancel when the connection is back."""
        self._cut_off.pop(goal_id, None)

    def remember(
        self, action: str, goal_id: str, version: int, *, stale: BridgeSession | None = None
    ) -> None:
        """Remember a goal that may still be running but could not be cancelled: the connection is down.

        It is cancelled once as soon as a connection to the bridge is up again (at once if one already
        is, other than *stale*, a session known to be dying), then forgotten. At most :data:`ORPHAN_LIMIT`
        are kept; one older than :data:`ORPHAN_MAX_AGE_SECONDS` is never cancelled.
        """
        host = self.host
        if host.closed:
            return
        self._cut_off.pop(goal_id, None)
        self._cut_off[goal_id] = CutOff(action, goal_id, version, stale)
        logger.warning(
            "Goal %s on %s may still be running on the robot; it will be cancelled as soon as the "
            "connection to %s is back",
            goal_id,
            action,
            host.url,
        )
        while len(self._cut_off) > ORPHAN_LIMIT:
            oldest = self._cut_off.pop(next(iter(self._cut_off)))
            logger.warning(
                "More than %d goals are waiting to be cancelled; forgetting goal %s on %s without a cancel",
                ORPHAN_LIMIT,
                oldest.goal_id,
                oldest.action,
            )
        # The reconnect may already have happened (its own sweep ran before this goal was remembered).
        session = host.session
        if session is not None and session is not stale:
            self.session_started(session)

    def session_started(self, session: BridgeSession) -> None:
        """A connection is up: cancel the goals a drop cut off, in the background."""
        if self._cut_off:
            self.host.run_in_background(self._sweep(session), "cancel goals cut off by a drop")

    async def closing(self) -> None:
        """The client is closing: cancel the goals open now while the connection is there; log those a drop
        cut off (no connection is left to cancel them on)."""
        for handle in list(self._open.values()):
            await handle.cancel()
        for entry in self._cut_off.values():
            logger.warning(
                "The client is closing; goal %s on %s, left running by a drop, was not cancelled",
                entry.goal_id,
                entry.action,
            )
        self._cut_off.clear()

    async def _sweep(self, session: BridgeSession) -> None:
        """Cancel, once, every remembered goal *session* may reach; forget them once the bridge read it."""
        now, version = time.monotonic(), session.info.version
        sent: list[CutOff] = []
        for entry in list(self._cut_off.values()):
            if entry.stale is session or self._cut_off.get(entry.goal_id) is not entry:
                continue
            # Taken out before any await, so a second sweep running at the same time never sends it again.
            del self._cut_off[entry.goal_id]
            if (why := not_to_cancel(entry, now, version, self.host.url)) is not None:
                logger.warning("Not cancelling goal %s on %s: %s", entry.goal_id, entry.action, why)
                continue
            if not await self._send_cancel(session, entry.action, entry.goal_id, entry.version):
                # The connection went again: the next one tries.
                self._keep([entry, *sent], session)
                return
            sent.append(entry)
        # A cancel written into a socket the bridge is closing is lost: only a pong proves it was read.
        if sent and not await session.confirm(min(CANCEL_CONFIRM_SECONDS, self.host.request_timeout)):
            self._keep(sent, session)
            return
        for entry in sent:
            logger.warning(
                "Sent a cancel for goal %s on %s, left running on the robot when the connection dropped "
                "%.1f s ago (nothing else asked for during the outage is sent)",
                entry.goal_id,
                entry.action,
                time.monotonic() - entry.since,
            )
            if entry.version == 1:
                # The publisher on <ns>/cancel is new on this connection: once more, while it lasts.
                again = self._send_cancel(
                    session, entry.action, entry.goal_id, 1, after=ROS1_CANCEL_REPEAT_SECONDS
                )
                self.host.run_in_background(again, f"repeat the cancel on {entry.action}")

    def _keep(self, entries: list[CutOff], session: BridgeSession) -> None:
        for entry in entries:
            if entry.goal_id not in self._cut_off:
                entry.stale = session
                self._cut_off[entry.goal_id] = entry


def _uuid_bytes(goal_id: str) -> list[int] | None:
    """The 16 bytes of a goal UUID written as 32 hex digits (dashes allowed), else None (a rosbridge id)."""
    digits = goal_id.strip().replace("-", "")
    if len(digits) != 32:
        return None
    try:
        return list(bytes.fromhex(digits))
    except ValueError:
        return None
