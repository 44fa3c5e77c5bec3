"""Running, observing and cancelling action goals on ROS 2 (action ops) and ROS 1 (actionlib topics).

ROS 2 goals use the client's ``send_action_goal`` (a lane of their own, so a Humble bridge that
runs a goal inside its connection thread still hears the cancel on the main connection). ROS 1
rosbridge has no action ops, so goals go through the five actionlib topics under the action's
namespace: publish ``<ns>/goal`` and ``<ns>/cancel``, listen on ``<ns>/status``, ``<ns>/feedback``
and ``<ns>/result``, matching our goal by ``goal_id.id``.

Status numbers are kept as the dialect sends them (ROS 2 0..6, ROS 1 0..9); the words differ too
(a canceled ROS 1 goal ends "preempted" or "recalled").
"""

from __future__ import annotations

import asyncio
import base64
import binascii
import contextlib
import logging
import time
import weakref
from collections import deque
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any, Final, Literal

from rosbridge_mcp_server.client import RosbridgeClient, Subscription
from rosbridge_mcp_server.errors import (
    ActionError,
    ConnectionLostError,
    GoalTimeoutError,
    NotConnectedError,
    RequestTimeoutError,
    RosbridgeError,
    ServiceError,
)
from rosbridge_mcp_server.wire.dialect import (
    action_type_names,
    goal_status_name,
    is_success_status,
    is_terminal_status,
)

__all__ = [
    "ACTIONLIB_SERVER_WAIT",
    "UNCONFIRMED_STATUS",
    "CancelReport",
    "CanceledBy",
    "GoalOutcome",
    "RunningGoal",
    "cancel_goals",
    "run_goal",
    "running_goals",
]

logger = logging.getLogger("rosbridge_mcp_server.actions")

CanceledBy = Literal["timeout", "request_cancelled", "cancel_action"]
#: ``GoalOutcome.status`` of a goal that timed out and whose end the server never confirmed after the cancel.
UNCONFIRMED_STATUS: Final = "timed out"

#: How long a ROS 1 goal waits for a first message on ``<ns>/status`` (actionlib servers publish it
#: periodically; roslibpy waits 3 s too).
ACTIONLIB_SERVER_WAIT: Final = 3.0
#: After a timeout's cancel, how long we wait for the goal's final result.
CANCEL_GRACE: Final = 2.0
#: A ROS 1 goal whose status says it finished, but whose result never came, ends after this long.
RESULT_AFTER_STATUS_GRACE: Final = 1.0
_LAST_FEEDBACK: Final = 5

_ZERO_UUID: Final = [0] * 16


@dataclass
class GoalOutcome:
    """How a goal ended."""

    goal_id: str
    action: str
    action_type: str
    """As the bridge was given it (the dialect's spelling)."""
    status_code: int
    status: str
    succeeded: bool
    result: dict[str, Any] | None
    feedback_count: int
    last_feedback: list[dict[str, Any]]
    canceled_by: CanceledBy | None
    dialect: int


@dataclass
class RunningGoal:
    """A goal started by :func:`run_goal` that has not ended yet."""

    goal_id: str
    action: str
    action_type: str
    dialect: int
    started: float = field(default_factory=time.monotonic)
    feedback_count: int = 0
    cancel_requested: bool = False


@dataclass
class CancelReport:
    """What :func:`cancel_goals` did."""

    action: str
    dialect: int
    goal_id: str | None
    """The goal asked for, or None for every goal of the action."""
    canceled_ours: list[str]
    """Ids of our running goals a cancel was sent for."""
    unknown_goal_id: bool
    """A goal id was given that is not one of our running goals (a cancel was still sent for it)."""
    goals_canceling: list[str] | None = None
    """ROS 2, cancel-all: goal UUIDs (hex) the action server said it is canceling, ours or not."""
    note: str | None = None


_registry: weakref.WeakKeyDictionary[RosbridgeClient, dict[str, RunningGoal]] = weakref.WeakKeyDictionary()


def _goals_of(client: RosbridgeClient) -> dict[str, RunningGoal]:
    goals = _registry.get(client)
    if goals is None:
        goals = {}
        _registry[client] = goals
    return goals


def running_goals(client: RosbridgeClient, action: str | None = None) -> list[RunningGoal]:
    """Goals started through :func:`run_goal` on *client* that are still running."""
    return [g for g in _goals_of(client).values() if action is None or g.action == action]


def _namespace(action: str) -> str:
    ns = action.strip().rstrip("/")
    return ns if ns.startswith("/") else f"/{ns}"


async def run_goal(
    client: RosbridgeClient,
    action: str,
    action_type: str,
    goal: dict[str, Any],
    *,
    timeout: float,
    on_feedback: Callable[[int, dict[str, Any]], Awaitable[None] | None] | None = None,
    goal_id: str | None = None,
) -> GoalOutcome:
    """Send a goal and wait (up to *timeout* seconds) for it to end.

    On timeout the goal is cancelled and the outcome says ``canceled_by="timeout"``; if the task
    running this is cancelled, the goal is cancelled before the cancellation propagates. Raises
    :class:`ActionError` when the goal cannot be sent (no action server, refused by the bridge), and
    :class:`ConnectionLostError` when the connection drops: the goal keeps running on the robot, so the
    client cancels it as soon as a connection is back (``goal_cancel`` says whether that already happened).
    """
    info = await client.ros_info()
    action = _namespace(action)
    gid = goal_id if goal_id is not None else client.new_goal_id(action)
    goals = _goals_of(client)
    if gid in goals:
        raise ActionError(action, f"goal id {gid!r} is already in use by a running goal")
    entry = RunningGoal(gid, action, action_type, info.version)
    goals[gid] = entry
    try:
        if info.version == 2:
            return await _run_ros2(client, entry, goal, timeout, on_feedback)
        return await _run_ros1(client, entry, goal, timeout, on_feedback)
    finally:
        goals.pop(gid, None)


class _FeedbackLog:
    def __init__(
        self, entry: RunningGoal, on_feedback: Callable[[int, dict[str, Any]], Awaitable[None] | None] | None
    ):
        self.entry = entry
        self.last: deque[dict[str, Any]] = deque(maxlen=_LAST_FEEDBACK)
        self.on_feedback = on_feedback

    async def __call__(self, values: dict[str, Any]) -> None:
        self.entry.feedback_count += 1
        self.last.append(values)
        if self.on_feedback is not None:
            maybe = self.on_feedback(self.entry.feedback_count, values)
            if maybe is not None:
                await maybe


def _outcome(
    entry: RunningGoal,
    code: int,
    result: Any,
    log: _FeedbackLog,
    *,
    timed_out: bool = False,
    finished: bool = True,
) -> GoalOutcome:
    version = entry.dialect
    succeeded = finished and is_success_status(code, version)
    canceled_by: CanceledBy | None = None
    if not succeeded:
        if timed_out:
            canceled_by = "timeout"
        elif entry.cancel_requested:
            canceled_by = "cancel_action"
    return GoalOutcome(
        goal_id=entry.goal_id,
        action=entry.action,
        action_type=action_type_names(entry.action_type).for_version(version),
        status_code=code,
        status=goal_status_name(code, version) if finished else UNCONFIRMED_STATUS,
        succeeded=succeeded,
        result=result if isinstance(result, dict) else None,
        feedback_count=entry.feedback_count,
        last_feedback=list(log.last),
        canceled_by=canceled_by,
        dialect=version,
    )


async def _run_ros2(
    client: RosbridgeClient,
    entry: RunningGoal,
    goal: dict[str, Any],
    timeout: float,
    on_feedback: Callable[[int, dict[str, Any]], Awaitable[None] | None] | None,
) -> GoalOutcome:
    log = _FeedbackLog(entry, on_feedback)
    try:
        result = await client.send_action_goal(
            entry.action, entry.action_type, goal, on_feedback=log, timeout=timeout, goal_id=entry.goal_id
        )
    except GoalTimeoutError as exc:
        if exc.status is None:
            return _outcome(entry, 0, None, log, timed_out=True, finished=False)
        return _outcome(entry, exc.status, exc.result, log, timed_out=True)
    return _outcome(entry, result.status, result.values, log)


async def _pump(kind: str, sub: Subscription, queue: asyncio.Queue[tuple[str, Any]]) -> None:
    try:
        while True:
            queue.put_nowait((kind, await sub.get()))
    except RosbridgeError as exc:
        queue.put_nowait(("error", exc))


def _goal_id_of(status: Any) -> str | None:
    if isinstance(status, dict):
        goal_id = status.get("goal_id")
        if isinstance(goal_id, dict):
            gid = goal_id.get("id")
            return gid if isinstance(gid, str) else None
    return None


async def _run_ros1(
    client: RosbridgeClient,
    entry: RunningGoal,
    goal: dict[str, Any],
    timeout: float,
    on_feedback: Callable[[int, dict[str, Any]], Awaitable[None] | None] | None,
) -> GoalOutcome:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    ns = entry.action
    types = action_type_names(entry.action_type).ros1
    log = _FeedbackLog(entry, on_feedback)
    gid = entry.goal_id
    # Advertised before we wait for the server, so the bridge's publishers have time to connect to
    # the action server: a message published right after a ROS 1 advertise is often lost.
    await client.advertise(f"{ns}/goal", types.goal)
    await client.advertise(f"{ns}/cancel", types.goal_id)
    queue: asyncio.Queue[tuple[str, Any]] = asyncio.Queue()
    sent = False
    finished = False
    async with (
        client.subscribe(f"{ns}/status", types.status_array, max_queue=10) as status_sub,
        client.subscribe(f"{ns}/feedback", types.feedback, max_queue=100) as feedback_sub,
        client.subscribe(f"{ns}/result", types.result, max_queue=10) as result_sub,
    ):
        wait = max(min(ACTIONLIB_SERVER_WAIT, deadline - loop.time()), 0.0)
        try:
            first_status = await status_sub.get(wait)
        except RequestTimeoutError:
            raise ActionError(
                ns,
                f"no action server at {ns}: no status messages on {ns}/status within {round(wait, 1):g} s "
                f"(is the action server running, and is the type {types.action} right?)",
            ) from None
        pumps = [
            asyncio.create_task(_pump("status", status_sub, queue)),
            asyncio.create_task(_pump("feedback", feedback_sub, queue)),
            asyncio.create_task(_pump("result", result_sub, queue)),
        ]
        queue.put_nowait(("status", first_status))
        seen = _Ros1Progress()
        try:
            await client.publish(
                f"{ns}/goal",
                types.goal,
                {"header": {}, "goal_id": {"stamp": {"secs": 0, "nsecs": 0}, "id": gid}, "goal": goal},
            )
            sent = True
            try:
                async with asyncio.timeout_at(deadline):
                    code, result = await _follow_ros1(queue, gid, log, seen)
                finished = True
                return _outcome(entry, code, result, log)
            except TimeoutError:
                pass
            except ConnectionLostError:
                # The action server keeps running the goal after our connection dropped.
                finished = True  # the cancel is taken care of here, not in `finally`
                reached = await asyncio.shield(_cancel_ros1(client, ns, gid, remember=True))
                raise ConnectionLostError(
                    client.url, f"action goal {gid} on {ns}", goal_cancel="sent" if reached else "pending"
                ) from None
            await asyncio.shield(_cancel_ros1(client, ns, gid))
            try:
                async with asyncio.timeout(CANCEL_GRACE):
                    code, result = await _follow_ros1(queue, gid, log, seen)
                finished = True
                return _outcome(entry, code, result, log, timed_out=True)
            except (TimeoutError, ConnectionLostError):
                finished = True
                return _outcome(entry, seen.code, None, log, timed_out=True, finished=False)
        finally:
            for pump in pumps:
                pump.cancel()
            if sent and not finished:
                await asyncio.shield(_cancel_ros1(client, ns, gid, remember=True))


class _Ros1Progress:
    """What the status topic has told us about our goal (kept across timeouts)."""

    __slots__ = ("code", "ended_at")

    def __init__(self) -> None:
        self.code = 0  # pending
        self.ended_at: float | None = None


async def _follow_ros1(
    queue: asyncio.Queue[tuple[str, Any]], gid: str, log: _FeedbackLog, seen: _Ros1Progress
) -> tuple[int, Any]:
    """Wait for our goal's result; returns (status, result)."""
    loop = asyncio.get_running_loop()
    while True:
        if seen.ended_at is None:
            kind, msg = await queue.get()
        else:
            try:
                async with asyncio.timeout_at(seen.ended_at + RESULT_AFTER_STATUS_GRACE):
                    kind, msg = await queue.get()
            except TimeoutError:
                # The status array says the goal ended but its result never came (published
                # before our subscription was set up, or lost): end with what we know.
                return seen.code, None
        if kind == "error":
            raise msg
        if not isinstance(msg, dict):
            continue
        if kind == "result":
            status = msg.get("status")
            if _goal_id_of(status) == gid:
                code = status.get("status") if isinstance(status, dict) else None
                seen.code = code if isinstance(code, int) else seen.code
                return seen.code, msg.get("result")
        elif kind == "feedback":
            if _goal_id_of(msg.get("status")) == gid:
                values = msg.get("feedback")
                await log(values if isinstance(values, dict) else {})
        elif kind == "status":
            for status in msg.get("status_list") or []:
                if _goal_id_of(status) == gid and isinstance(status.get("status"), int):
                    seen.code = status["status"]
                    if is_terminal_status(seen.code, 1) and seen.ended_at is None:
                        seen.ended_at = loop.time()


async def _cancel_ros1(client: RosbridgeClient, ns: str, goal_id: str, *, remember: bool = False) -> bool:
    """Publish a cancel on ``<ns>/cancel`` (empty id = every goal); False if it could not be sent.

    With *remember*, a goal whose cancel could not be sent is left to the client, which cancels it as
    soon as the connection is back.
    """
    try:
        await client.publish(
            f"{ns}/cancel", "actionlib_msgs/GoalID", {"stamp": {"secs": 0, "nsecs": 0}, "id": goal_id}
        )
    except RosbridgeError as exc:
        if remember and goal_id:
            # Right after the failed send, with no await between: the client sees the same connection state.
            client.remember_orphaned_goal(ns, goal_id, 1)
        else:
            logger.warning("Could not send a cancel for goal %r on %s: %s", goal_id, ns, exc)
        return False
    return True


def _uuid_hex(goal_info: Any) -> str | None:
    if not isinstance(goal_info, dict):
        return None
    goal_id = goal_info.get("goal_id")
    uuid = goal_id.get("uuid") if isinstance(goal_id, dict) else None
    # uint8[16] arrives base64-encoded from rosbridge's JSON mode; accept a list of ints too.
    if isinstance(uuid, str):
        with contextlib.suppress(binascii.Error, ValueError):
            return base64.b64decode(uuid, validate=True).hex()
        return uuid
    if isinstance(uuid, list) and all(isinstance(b, int) and 0 <= b < 256 for b in uuid):
        return bytes(uuid).hex()
    return None


async def cancel_goals(client: RosbridgeClient, action: str, goal_id: str | None = None) -> CancelReport:
    """Cancel one goal (by our id) or every goal of *action* (ours and others').

    ROS 2: ``cancel_action_goal`` for our goals (on the main connection, so it reaches a goal
    running on its own lane), plus, to cancel every goal, the action's hidden
    ``<action>/_action/cancel_goal`` service with a zero goal id and zero stamp. ROS 1: a
    ``actionlib_msgs/GoalID`` on ``<ns>/cancel`` (empty id and zero stamp cancels every goal).
    """
    info = await client.ros_info()
    ns = _namespace(action)
    ours = [g for g in running_goals(client, ns) if goal_id is None or g.goal_id == goal_id]
    for entry in ours:
        entry.cancel_requested = True
    canceled_ours = [g.goal_id for g in ours]
    unknown = goal_id is not None and not ours
    if info.version == 1:
        if not await _cancel_ros1(client, ns, goal_id or ""):
            raise NotConnectedError(client.url, f"could not publish on {ns}/cancel")
        return CancelReport(ns, 1, goal_id, canceled_ours, unknown)
    if goal_id is not None:
        await client.cancel_action_goal(ns, goal_id)
        return CancelReport(ns, 2, goal_id, canceled_ours, unknown)
    for entry in ours:
        await client.cancel_action_goal(ns, entry.goal_id)
    report = CancelReport(ns, 2, None, canceled_ours, False)
    try:
        values = await client.call_service(
            f"{ns}/_action/cancel_goal",
            {"goal_info": {"goal_id": {"uuid": _ZERO_UUID}, "stamp": {"sec": 0, "nanosec": 0}}},
        )
    except ServiceError as exc:
        report.note = f"cancelling goals of other clients failed: {exc.message}"
        return report
    canceling = values.get("goals_canceling") if isinstance(values, dict) else None
    if isinstance(canceling, list):
        report.goals_canceling = [h for h in (_uuid_hex(info_) for info_ in canceling) if h is not None]
    return_code = values.get("return_code") if isinstance(values, dict) else None
    if return_code not in (None, 0):
        # action_msgs/srv/CancelGoal: 1 rejected, 2 unknown goal id, 3 goal terminated.
        report.note = f"the action server answered the cancel with return_code {return_code}"
    return report
