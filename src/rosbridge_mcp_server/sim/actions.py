"""Action servers: ``/fibonacci`` for ROS 2 (``example_interfaces/action/Fibonacci``) and ROS 1 actionlib,
and the ROS 2 servers clients host through rosbridge (``advertise_action``).

Every ROS 2 server (:class:`ActionServer`) keeps its goals by UUID and offers what a real one shows in the
graph: the hidden ``_action/status`` and ``_action/feedback`` topics and ``_action/*`` services.

Both Fibonacci servers follow the example servers: the sequence starts ``[0, 1]``; each step appends the
next number, publishes one feedback and waits ``action_step`` seconds; the result is the whole sequence. A
cancel ends the goal at its next step with the partial sequence (ROS 2 CANCELED, ROS 1 PREEMPTED), as the
rclcpp minimal action server does.

Goals we refuse (our documented choice; the example servers differ on this): ``order < 0`` is rejected,
and so is ``order > 9000`` (the rclcpp example's own limit). A goal whose next number no longer fits an
``int32`` is aborted with the sequence so far (that happens from ``order = 47`` on).
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import itertools
import logging
import os
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.sim.graph import ServiceEntry
from rosbridge_mcp_server.sim.world import GoalRecord

if TYPE_CHECKING:
    from rosbridge_mcp_server.sim.bridge import Bridge

__all__ = [
    "FIBONACCI_NODE",
    "ROS1_STATUS",
    "ROS2_STATUS",
    "ActionServer",
    "ActionlibFibonacciServer",
    "FibonacciServer",
    "GoalHandle",
    "HostedActionServer",
]

log = logging.getLogger("rosbridge_mcp_server.sim")

FIBONACCI_NODE = "/fibonacci_server"
INT32_MAX = 2**31 - 1
MAX_ORDER = 9000

#: ``action_msgs/msg/GoalStatus``
ROS2_STATUS = {
    "UNKNOWN": 0,
    "ACCEPTED": 1,
    "EXECUTING": 2,
    "CANCELING": 3,
    "SUCCEEDED": 4,
    "CANCELED": 5,
    "ABORTED": 6,
}
#: ``actionlib_msgs/GoalStatus`` — the numbers differ from ROS 2.
ROS1_STATUS = {
    "PENDING": 0,
    "ACTIVE": 1,
    "PREEMPTED": 2,
    "SUCCEEDED": 3,
    "ABORTED": 4,
    "REJECTED": 5,
    "PREEMPTING": 6,
    "RECALLING": 7,
    "RECALLED": 8,
    "LOST": 9,
}
#: How many finished goals stay in the status list.
KEEP_FINISHED = 20


def _order_ok(order: int) -> bool:
    return 0 <= order <= MAX_ORDER


def _uuid_bytes(value: Any) -> bytes:
    """A UUID field in whatever form the converter gives it (bytes, list of ints, base64 text)."""
    if isinstance(value, str):
        return base64.b64decode(value)
    return bytes(value)


#: SimpleActionServer's texts (actionlib 1.x).
ACCEPTED_TEXT = "This goal has been accepted by the simple action server"
REPLACED_BY_ANOTHER_GOAL = (
    "This goal was canceled because another goal was received by the simple action server"
)
CANCELED_BEFORE_STAMP = (
    "This goal handle was canceled by the action server because its timestamp is before the timestamp of the "
    "last cancel request"
)


def _stamp_seconds(stamp: Any) -> float:
    if not isinstance(stamp, dict):
        return 0.0
    sec = stamp.get("sec", stamp.get("secs", 0)) or 0
    nsec = stamp.get("nanosec", stamp.get("nsecs", 0)) or 0
    return float(sec) + float(nsec) / 1e9


def _stamp(seconds: float, dialect: str) -> dict[str, int]:
    sec = int(seconds)
    nsec = round((seconds - sec) * 1e9)
    return {"sec": sec, "nanosec": nsec} if dialect == "ros2" else {"secs": sec, "nsecs": nsec}


class _Run:
    """The execution loop shared by both dialects."""

    def __init__(
        self, record: GoalRecord, step: float, notify: Callable[[], None], cancel: asyncio.Event | None = None
    ) -> None:
        self.record = record
        self.step = step
        self.notify = notify
        self.cancel = cancel or asyncio.Event()

    async def execute(self, on_feedback: Callable[[list[int]], None]) -> str:
        """Run to the end; returns ``succeeded``, ``canceled`` or ``aborted``."""
        sequence = [0, 1]
        self.record.sequence = list(sequence)
        for i in range(1, self.record.order):
            if self.cancel.is_set():
                return "canceled"
            following = sequence[i] + sequence[i - 1]
            if following > INT32_MAX:
                return "aborted"
            sequence.append(following)
            self.record.sequence = list(sequence)
            on_feedback(list(sequence))
            self.notify()
            # Wakes early on a cancel so it takes effect at the next step without waiting it out.
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self.cancel.wait(), self.step)
        return "succeeded"


class GoalHandle:
    """A goal of a ROS 2 action server (ours or one hosted by a client)."""

    def __init__(self, server: ActionServer, uuid: bytes, record: GoalRecord, goal: dict[str, Any]) -> None:
        self.server = server
        self.uuid = uuid
        self.record = record
        self.goal = goal
        #: The id rosbridge gave the goal when forwarding it to a client-hosted server.
        self.bridge_id: str | None = None
        self.cancel = asyncio.Event()
        self.done: asyncio.Future[tuple[int, dict[str, Any]]] = asyncio.get_running_loop().create_future()

    def request_cancel(self) -> bool:
        """Ask the goal to stop (accepted while it runs); returns whether it was accepted."""
        if self.record.finished:
            return False
        if not self.record.cancel_requested:
            self.record.cancel_requested = True
            self.record.status = ROS2_STATUS["CANCELING"]
            self.cancel.set()
            self.server.on_cancel(self)
            self.server.publish_status()
        return True

    async def outcome(self) -> tuple[int, dict[str, Any]]:
        """Terminal status and the result (JSON form)."""
        return await asyncio.shield(self.done)


FeedbackFn = Callable[[dict[str, Any]], None]


class ActionServer:
    """A ROS 2 action server in the graph: goals by UUID, the hidden status/feedback topics and services."""

    def __init__(self, bridge: Bridge, name: str, action_type: str, node: str) -> None:
        self.bridge = bridge
        self.name = name
        self.type = action_type
        self.node = node
        self.goals: dict[bytes, GoalHandle] = {}
        self._tasks: set[asyncio.Task[None]] = set()
        pkg, _, leaf = action_type.split("/")
        self.status_topic = f"{name}/_action/status"
        self.feedback_topic = f"{name}/_action/feedback"
        self.feedback_type = f"{pkg}/action/{leaf}_FeedbackMessage"
        self._services = [
            (f"{name}/_action/send_goal", f"{pkg}/action/{leaf}_SendGoal", self._send_goal_service),
            (f"{name}/_action/get_result", f"{pkg}/action/{leaf}_GetResult", self._get_result_service),
            (f"{name}/_action/cancel_goal", "action_msgs/srv/CancelGoal", self._cancel_goal_service),
        ]
        graph = bridge.graph
        graph.add_publisher(node, self.status_topic, "action_msgs/msg/GoalStatusArray")
        graph.add_publisher(node, self.feedback_topic, self.feedback_type)
        for service, service_type, handler in self._services:
            graph.add_service(ServiceEntry(service, service_type, node, handler))
        graph.actions[name] = self

    # --- what a concrete server decides --------------------------------------------------------------

    def accepts(self, goal: dict[str, Any], goal_key: str) -> bool:
        """Whether a goal is accepted (``False`` = rejected)."""
        return True

    def goal_order(self, goal: dict[str, Any]) -> int:
        """What :attr:`GoalRecord.order` records for this goal."""
        return 0

    async def run_goal(self, handle: GoalHandle, feedback: FeedbackFn) -> tuple[str, dict[str, Any]]:
        """Execute a goal; returns (``succeeded``/``canceled``/``aborted``, result in JSON form)."""
        raise NotImplementedError

    def on_cancel(self, handle: GoalHandle) -> None:
        """A cancel was accepted for ``handle`` (its ``cancel`` event is set)."""

    # --- goal life cycle -----------------------------------------------------------------------------

    def submit(
        self,
        goal: dict[str, Any],
        *,
        key: Any,
        on_feedback: FeedbackFn | None,
        uuid: bytes | None = None,
    ) -> GoalHandle | None:
        """Accept (and start) or reject a goal; ``None`` means rejected."""
        uuid = uuid or os.urandom(16)
        goal_key = str(key) if key is not None else uuid.hex()
        if not self.accepts(goal, goal_key):
            return None
        record = GoalRecord(goal_key, self.goal_order(goal), ROS2_STATUS["ACCEPTED"])
        world = self.bridge.world
        world.goals[goal_key] = record
        handle = GoalHandle(self, uuid, record, goal)
        self.goals[uuid] = handle
        self.publish_status()
        world.notify()
        task = asyncio.create_task(self._execute(handle, on_feedback))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return handle

    async def _execute(self, handle: GoalHandle, on_feedback: FeedbackFn | None) -> None:
        record = handle.record
        if not record.cancel_requested:
            record.status = ROS2_STATUS["EXECUTING"]
            self.publish_status()

        def feedback(values: dict[str, Any]) -> None:
            record.feedback_count += 1
            if on_feedback is not None:
                on_feedback(values)
            if self.bridge.has_subscribers(self.feedback_topic):
                self._publish_quietly(
                    self.feedback_topic,
                    self.feedback_type,
                    {"goal_id": {"uuid": list(handle.uuid)}, "feedback": values},
                )
            self.bridge.world.notify()

        outcome: str = "aborted"
        result: dict[str, Any] = {}
        try:
            outcome, result = await self.run_goal(handle, feedback)
        finally:
            status = ROS2_STATUS[outcome.upper()]
            record.status = status
            record.finished = True
            if not handle.done.done():
                handle.done.set_result((status, result))
            self._forget_old()
            self.publish_status()
            self.bridge.world.notify()

    def _forget_old(self) -> None:
        finished = [u for u, h in self.goals.items() if h.record.finished]
        for uuid in finished[:-KEEP_FINISHED]:
            del self.goals[uuid]

    def _publish_quietly(self, topic: str, msg_type: str, partial: dict[str, Any]) -> None:
        try:
            self.bridge.publish_json(topic, msg_type, partial)
        except Exception as exc:
            log.debug("cannot publish %s: %s", topic, exc)

    def publish_status(self) -> None:
        """``GoalStatusArray`` on the hidden status topic, sent on every change of a goal's state."""
        if not self.bridge.has_subscribers(self.status_topic):
            return
        status_list = [
            {
                "goal_info": {
                    "goal_id": {"uuid": list(h.uuid)},
                    "stamp": _stamp(h.record.accepted_at, "ros2"),
                },
                "status": h.record.status,
            }
            for h in self.goals.values()
        ]
        self._publish_quietly(
            self.status_topic, "action_msgs/msg/GoalStatusArray", {"status_list": status_list}
        )

    async def _send_goal_service(self, request: dict[str, Any]) -> dict[str, Any]:
        uuid = _uuid_bytes(request["goal_id"]["uuid"])
        handle = self.submit(request["goal"], key=None, on_feedback=None, uuid=uuid)
        if handle is None:
            return {"accepted": False}
        return {"accepted": True, "stamp": _stamp(handle.record.accepted_at, "ros2")}

    async def _get_result_service(self, request: dict[str, Any]) -> dict[str, Any]:
        handle = self.goals.get(_uuid_bytes(request["goal_id"]["uuid"]))
        if handle is None:
            return {"status": ROS2_STATUS["UNKNOWN"]}
        status, result = await handle.outcome()
        return {"status": status, "result": result}

    async def _cancel_goal_service(self, request: dict[str, Any]) -> dict[str, Any]:
        """``action_msgs/srv/CancelGoal``: zero id and stamp cancel all; a stamp, those accepted before."""
        info = request.get("goal_info", {})
        uuid = _uuid_bytes(info.get("goal_id", {}).get("uuid", bytes(16)))
        stamp = _stamp_seconds(info.get("stamp"))
        running = [h for h in self.goals.values() if not h.record.finished]
        if uuid == bytes(16):
            chosen = running if stamp == 0 else [h for h in running if h.record.accepted_at <= stamp]
        else:
            target = self.goals.get(uuid)
            if target is None:
                return {"return_code": 2}  # ERROR_UNKNOWN_GOAL_ID
            if target.record.finished:
                return {"return_code": 3}  # ERROR_GOAL_TERMINATED
            chosen = [target] + (
                [h for h in running if h.record.accepted_at <= stamp and h is not target] if stamp else []
            )
        canceling = [h for h in chosen if h.request_cancel()]
        return {
            "return_code": 0,
            "goals_canceling": [
                {"goal_id": {"uuid": list(h.uuid)}, "stamp": _stamp(h.record.accepted_at, "ros2")}
                for h in canceling
            ],
        }

    def remove(self) -> None:
        """Take the server out of the graph; goals still running end ABORTED."""
        graph = self.bridge.graph
        if graph.actions.get(self.name) is self:
            del graph.actions[self.name]
        graph.remove_publisher(self.node, self.status_topic)
        graph.remove_publisher(self.node, self.feedback_topic)
        for service, _, _ in self._services:
            entry = graph.services.get(service)
            if entry is not None and entry.node == self.node:
                graph.remove_service(service)
        for task in list(self._tasks):
            task.cancel()

    async def close(self) -> None:
        """Stop every goal (the robot is shutting down)."""
        for task in list(self._tasks):
            task.cancel()


class FibonacciServer(ActionServer):
    """ROS 2 action server ``/fibonacci`` (``example_interfaces/action/Fibonacci``)."""

    def __init__(self, bridge: Bridge, name: str, action_type: str, step: float) -> None:
        super().__init__(bridge, name, action_type, FIBONACCI_NODE)
        self.step = step

    def goal_order(self, goal: dict[str, Any]) -> int:
        return int(goal.get("order", 0))

    def accepts(self, goal: dict[str, Any], goal_key: str) -> bool:
        order = self.goal_order(goal)
        if not _order_ok(order):
            log.info("%s: goal %s with order %d rejected", self.name, goal_key, order)
            return False
        return True

    async def run_goal(self, handle: GoalHandle, feedback: FeedbackFn) -> tuple[str, dict[str, Any]]:
        run = _Run(handle.record, self.step, self.bridge.world.notify, handle.cancel)
        outcome = await run.execute(lambda sequence: feedback({"sequence": sequence}))
        return outcome, {"sequence": list(handle.record.sequence)}


class HostedActionServer(ActionServer):
    """An action server a client hosts with ``advertise_action`` (protocol §7.3).

    Every goal is accepted (rosbridge auto-accepts) and forwarded to the client as a server-initiated
    ``send_action_goal``; the client's ``action_feedback`` and ``action_result`` come back through
    :meth:`feedback_from_client` / :meth:`result_from_client`. A ROS-side cancel is forwarded as
    ``cancel_action_goal``; the goal stays open until the client sends its result.
    """

    def __init__(self, bridge: Bridge, name: str, action_type: str, owner: int, node: str) -> None:
        super().__init__(bridge, name, action_type, node)
        self.owner = owner
        self._counter = itertools.count(1)
        #: bridge goal id -> (handle, feedback function, result future)
        self.pending: dict[
            str, tuple[GoalHandle, FeedbackFn, asyncio.Future[tuple[str, dict[str, Any]]]]
        ] = {}

    async def run_goal(self, handle: GoalHandle, feedback: FeedbackFn) -> tuple[str, dict[str, Any]]:
        goal_type, _, _ = self.bridge.registry.action_parts(self.type)
        goal_id = f"action_goal:{self.name}:{next(self._counter)}"
        handle.bridge_id = goal_id
        future: asyncio.Future[tuple[str, dict[str, Any]]] = asyncio.get_running_loop().create_future()
        self.pending[goal_id] = (handle, feedback, future)
        try:
            conn = self.bridge.connections.get(self.owner)
            if conn is None:
                log.warning("action %s: its client has gone; the goal will never end", self.name)
            else:
                args = self.bridge.registry.to_json(goal_type, handle.goal)
                conn.send(
                    {
                        "op": "send_action_goal",
                        "id": goal_id,
                        "action": self.name,
                        "action_type": self.type,
                        "args": args,
                        "feedback": True,
                    }
                )
            return await future
        finally:
            self.pending.pop(goal_id, None)

    def on_cancel(self, handle: GoalHandle) -> None:
        goal_id = handle.bridge_id
        conn = self.bridge.connections.get(self.owner)
        if goal_id is not None and conn is not None:
            conn.send({"op": "cancel_action_goal", "id": goal_id, "action": self.name})

    def feedback_from_client(self, goal_id: str, values: dict[str, Any]) -> bool:
        """The client's ``action_feedback``; ``False`` if the goal is unknown."""
        pending = self.pending.get(goal_id)
        if pending is None:
            return False
        pending[1](values)
        return True

    def result_from_client(self, goal_id: str, status: int, ok: bool, values: Any) -> bool:
        """The client's ``action_result``: 4 succeeds, 5 cancels, else (or ``result: false``) aborts."""
        pending = self.pending.get(goal_id)
        if pending is None:
            return False
        outcome = {4: "succeeded", 5: "canceled"}.get(status, "aborted") if ok else "aborted"
        result = values if ok and isinstance(values, dict) else {}
        if not pending[2].done():
            pending[2].set_result((outcome, result))
        return True


class ActionlibFibonacciServer:
    """ROS 1 actionlib ``SimpleActionServer`` for ``/fibonacci``, over its five topics.

    Like ``SimpleActionServer``, one goal runs at a time: a new goal preempts the running one, and a goal
    still waiting is recalled when another arrives.
    """

    STATUS_PERIOD = 0.2  # actionlib's status_frequency of 5 Hz
    STATUS_LIST_TIMEOUT = 5.0  # finished goals stay in the status list this long

    def __init__(self, bridge: Bridge, name: str, package: str, step: float) -> None:
        self.bridge = bridge
        self.name = name
        self.step = step
        self.package = package
        self.goal_type = f"{package}/FibonacciActionGoal"
        self.feedback_type = f"{package}/FibonacciActionFeedback"
        self.result_type = f"{package}/FibonacciActionResult"
        self._ids = itertools.count(1)
        self._seq = itertools.count(1)
        self._tracked: dict[str, tuple[GoalRecord, dict[str, Any], float]] = {}
        self._runs: dict[str, _Run] = {}
        self._current: str | None = None
        self._next: str | None = None
        self._wakeup = asyncio.Event()
        self._texts: dict[str, str] = {}
        #: The newest stamp of a cancel request (actionlib's last_cancel_), in seconds.
        self._last_cancel = 0.0
        graph = bridge.graph
        graph.add_subscriber(FIBONACCI_NODE, f"{name}/goal", self.goal_type, self._on_goal)
        graph.add_subscriber(FIBONACCI_NODE, f"{name}/cancel", "actionlib_msgs/GoalID", self._on_cancel)
        graph.add_publisher(FIBONACCI_NODE, f"{name}/status", "actionlib_msgs/GoalStatusArray")
        graph.add_publisher(FIBONACCI_NODE, f"{name}/feedback", self.feedback_type)
        graph.add_publisher(FIBONACCI_NODE, f"{name}/result", self.result_type)

    def _header(self) -> dict[str, Any]:
        return {"seq": next(self._seq), "stamp": _stamp(time.time(), "ros1"), "frame_id": ""}

    def _status(self, goal_id: str) -> dict[str, Any]:
        record, goal_id_msg, _ = self._tracked[goal_id]
        return {"goal_id": goal_id_msg, "status": record.status, "text": self._texts.get(goal_id, "")}

    def _generate_id(self) -> dict[str, Any]:
        """actionlib's GoalIDGenerator: ``<node>-<n>-<secs>.<nsecs>`` (nsecs not zero-padded), stamped now."""
        now = _stamp(time.time(), "ros1")
        return {"id": f"{FIBONACCI_NODE}-{next(self._ids)}-{now['secs']}.{now['nsecs']}", "stamp": now}

    def _on_goal(self, msg: dict[str, Any], _source: int) -> None:
        goal_id_msg = dict(msg.get("goal_id", {}))
        order = int(msg.get("goal", {}).get("order", 0))
        known = self._tracked.get(goal_id_msg.get("id", ""))
        if goal_id_msg.get("id") and known is not None:
            # ActionServer: a goal already in the status list is never run again; one whose cancel came
            # first (RECALLING) ends RECALLED with an empty result and the cancel's goal id.
            record = known[0]
            if record.status == ROS1_STATUS["RECALLING"]:
                record.order = order
                self.bridge.world.goals[record.goal_id] = record
                self._finish(record.goal_id, "RECALLED")
            return
        if not goal_id_msg.get("id"):
            goal_id_msg = self._generate_id()
        stamp = _stamp_seconds(goal_id_msg.get("stamp"))
        if stamp == 0:
            stamp = time.time()  # actionlib stamps a goal sent with a zero stamp on arrival
        goal_id = str(goal_id_msg["id"])
        goal_id_msg = {"id": goal_id, "stamp": _stamp(stamp, "ros1")}
        record = GoalRecord(goal_id, order, ROS1_STATUS["PENDING"], accepted_at=stamp)
        self._tracked[goal_id] = (record, goal_id_msg, 0.0)
        self.bridge.world.goals[goal_id] = record
        given_stamp = _stamp_seconds(msg.get("goal_id", {}).get("stamp"))
        if given_stamp != 0 and given_stamp <= self._last_cancel:
            self._finish(goal_id, "RECALLED", CANCELED_BEFORE_STAMP)
            return
        if not _order_ok(order):
            self._finish(goal_id, "REJECTED")
            return
        newest = max(
            (self._tracked[g][0].accepted_at for g in (self._current, self._next) if g is not None),
            default=0.0,
        )
        if stamp < newest:
            # SimpleActionServer only takes goals stamped at or after the current and the next one.
            self._finish(goal_id, "RECALLED", REPLACED_BY_ANOTHER_GOAL)
            return
        if self._next is not None:
            # SimpleActionServer: a newer goal replaces the one still waiting.
            self._finish(self._next, "RECALLED", REPLACED_BY_ANOTHER_GOAL)
        self._next = goal_id
        if self._current is not None:
            self._runs[self._current].record.cancel_requested = True
            self._runs[self._current].cancel.set()
        # No status is published here: the goal is accepted (ACTIVE) at once when the server is idle, and
        # the first status a client sees says so; otherwise it waits PENDING until the 5 Hz status.
        self._wakeup.set()

    def _on_cancel(self, msg: dict[str, Any], _source: int) -> None:
        cancel_id = msg.get("id", "")
        stamp = _stamp_seconds(msg.get("stamp"))
        found = False
        for goal_id, (record, _, _) in list(self._tracked.items()):
            hit = (
                (not cancel_id and stamp == 0)
                or goal_id == cancel_id
                or (stamp != 0 and record.accepted_at <= stamp)
            )
            if not hit:
                continue
            found = found or goal_id == cancel_id
            if record.finished:
                continue
            record.cancel_requested = True
            if goal_id == self._next:
                self._next = None
                self._finish(goal_id, "RECALLED")
            elif goal_id == self._current:
                record.status = ROS1_STATUS["PREEMPTING"]
                self._runs[goal_id].cancel.set()
        if cancel_id and not found:
            # A cancel for a goal not seen yet is kept (RECALLING, for the status list's 5 s) so that the
            # goal, when it comes, is recalled at once (actionlib ActionServer).
            record = GoalRecord(cancel_id, 0, ROS1_STATUS["RECALLING"], accepted_at=stamp)
            goal_id_msg = {"id": cancel_id, "stamp": _stamp(stamp, "ros1")}
            self._tracked[cancel_id] = (record, goal_id_msg, time.monotonic())
        self._last_cancel = max(self._last_cancel, stamp)
        self.publish_status()
        self.bridge.world.notify()

    def _finish(self, goal_id: str, state: str, text: str = "") -> None:
        record, goal_id_msg, _ = self._tracked[goal_id]
        record.status = ROS1_STATUS[state]
        record.finished = True
        self._texts[goal_id] = text
        self._tracked[goal_id] = (record, goal_id_msg, time.monotonic())
        self._publish(
            f"{self.name}/result",
            self.result_type,
            {
                "header": self._header(),
                "status": self._status(goal_id),
                "result": {"sequence": record.sequence},
            },
        )
        self.publish_status()
        self.bridge.world.notify()

    def _publish(self, topic: str, msg_type: str, partial: dict[str, Any]) -> None:
        try:
            self.bridge.publish_json(topic, msg_type, partial)
        except Exception as exc:
            log.debug("cannot publish %s: %s", topic, exc)

    def publish_status(self) -> None:
        """The status list: goals running or waiting, and goals finished less than 5 s ago."""
        now = time.monotonic()
        for goal_id, (record, _, finished_at) in list(self._tracked.items()):
            expires = record.finished or record.status == ROS1_STATUS["RECALLING"]
            if expires and now - finished_at > self.STATUS_LIST_TIMEOUT:
                del self._tracked[goal_id]
                self._texts.pop(goal_id, None)
        status_list = [self._status(goal_id) for goal_id in self._tracked]
        self._publish(
            f"{self.name}/status",
            "actionlib_msgs/GoalStatusArray",
            {"header": self._header(), "status_list": status_list},
        )

    async def run(self) -> None:
        """Execute goals one at a time and publish the status list at 5 Hz."""
        status_task = asyncio.create_task(self._status_loop())
        try:
            while True:
                while self._next is None:
                    self._wakeup.clear()
                    await self._wakeup.wait()
                goal_id, self._next = self._next, None
                self._current = goal_id
                record = self._tracked[goal_id][0]
                run = self._runs[goal_id] = _Run(record, self.step, self.bridge.world.notify)
                record.status = ROS1_STATUS["ACTIVE"]
                self._texts[goal_id] = ACCEPTED_TEXT
                self.publish_status()

                def feedback(
                    sequence: list[int], goal_id: str = goal_id, record: GoalRecord = record
                ) -> None:
                    record.feedback_count += 1
                    self._publish(
                        f"{self.name}/feedback",
                        self.feedback_type,
                        {
                            "header": self._header(),
                            "status": self._status(goal_id),
                            "feedback": {"sequence": sequence},
                        },
                    )

                outcome = "aborted"  # if the robot stops mid-goal
                try:
                    outcome = await run.execute(feedback)
                finally:
                    self._current = None
                    del self._runs[goal_id]
                    self._finish(
                        goal_id,
                        {"succeeded": "SUCCEEDED", "canceled": "PREEMPTED", "aborted": "ABORTED"}[outcome],
                    )
        finally:
            status_task.cancel()

    async def _status_loop(self) -> None:
        while True:
            self.publish_status()
            await asyncio.sleep(self.STATUS_PERIOD)
