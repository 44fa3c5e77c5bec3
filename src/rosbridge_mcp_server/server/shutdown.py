"""Stopping the server stops the robots first: :func:`stop_robots`, run before any robot's client closes.

However the server stops — SIGINT or SIGTERM (any number of them), stdin closing (stdio), the HTTP server
shutting down — what it set going on each robot is stopped the way ``stop_robot`` stops it
(:func:`~rosbridge_mcp_server.safety.emergency_stop`, pressed by ``"shutdown"``): every stream ended, a zero
command on every velocity topic it used, every running goal cancelled, each step audited. It is bounded
(:data:`STOP_SECONDS`, a frozen bridge must not keep the process alive) and runs to its end whatever cancels
its caller meanwhile: a second Ctrl-C must not cut the stop short.

A robot on which nothing of this server runs (no goal, no stream) is left alone: nothing is sent to it (a
one-off command published earlier is not followed by a zero).
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING

import anyio

from rosbridge_mcp_server.robot.approval import Act
from rosbridge_mcp_server.safety import Presser, emergency_stop

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.session import RobotSession

__all__ = ["STOP_SECONDS", "stop_robots"]

_log = logging.getLogger("rosbridge_mcp_server.server")

#: Longest the stop at shutdown may take on all robots together (the emergency stop's own waits: 0.5 s for
#: the streams, 2 s for the bridge to confirm, plus a round trip or two).
STOP_SECONDS = 5.0
_PRESSER: Presser = "shutdown"


async def stop_robots(sessions: Sequence[RobotSession]) -> None:
    """Stop what runs on each of *sessions*, within :data:`STOP_SECONDS`, shielded from cancellation."""
    moved = [session for session in sessions if _set_going(session)]
    if not moved:
        return
    stopping = asyncio.ensure_future(asyncio.gather(*(_stop(session) for session in moved)))
    deadline = time.monotonic() + STOP_SECONDS
    cancel: asyncio.CancelledError | None = None
    while not stopping.done() and (left := deadline - time.monotonic()) > 0:
        try:
            # Shielded from anyio's cancel scopes (which cancel every await again) and, by the loop, from a
            # plain task cancel: the stop goes on to its end or its deadline.
            with anyio.CancelScope(shield=True):
                await asyncio.wait({stopping}, timeout=left)
        except asyncio.CancelledError as exc:
            cancel = cancel or exc
    if not stopping.done():
        _log.error("the stop at shutdown did not end within %g s; check the robot", STOP_SECONDS)
        stopping.cancel()
    if cancel is not None:
        raise cancel


def _set_going(session: RobotSession) -> bool:
    """Whether something this server started still runs on the robot: a goal or a stream."""
    return bool(session.goals.running() or session.activity.streams)


async def _stop(session: RobotSession) -> None:
    try:
        report = await emergency_stop(session, by=_PRESSER)
    except Exception:
        _log.exception("the stop at shutdown failed on %s; check the robot", session.client.url)
        return
    guard = session.guard
    for topic, type_name, message in report.zero_messages:
        guard.record(Act(_PRESSER, "topic", topic, type_name, message), "e-stop")
    for action, goal_id in report.goals:
        guard.record(Act(_PRESSER, "action", action, "", {"cancel": goal_id}), "e-stop")
    _log.info(
        "shutting down: %d stream(s) ended, %d velocity topic(s) zeroed, %d goal(s) cancelled on %s%s",
        len(report.streams_stopped),
        len(report.zeroed_topics),
        len(report.goals_cancelled),
        session.client.url,
        f"; {'; '.join(report.failures)}" if report.failures else "",
    )
