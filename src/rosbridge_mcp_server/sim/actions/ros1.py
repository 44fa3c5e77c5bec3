"""ROS 1: actionlib's ``SimpleActionServer`` for ``/fibonacci`` over its five topics."""

from __future__ import annotations

import asyncio
import itertools
import logging
import time
from typing import Any

from rosbridge_mcp_server.sim.actions.common import (
    ACCEPTED_TEXT,
    CANCELED_BEFORE_STAMP,
    FIBONACCI_NODE,
    REPLACED_BY_ANOTHER_GOAL,
    ROS1_STATUS,
    ActionHost,
    FibonacciRun,
    order_ok,
    stamp_seconds,
    time_msg,
)
from rosbridge_mcp_server.sim.world import GoalRecord

__all__ = ["ActionlibFibonacciServer"]

log = logging.getLogger("rosbridge_mcp_server.sim")


class ActionlibFibonacciServer:
    """ROS 1 actionlib ``SimpleActionServer`` for ``/fibonacci``, over its five topics.

    Like ``SimpleActionServer``, one goal runs at a time: a new goal preempts the running one, and a goal
    still waiting is recalled when another arrives.
    """

    STATUS_PERIOD = 0.2  # actionlib's status_frequency of 5 Hz
    STATUS_LIST_TIMEOUT = 5.0  # finished goals stay in the status list this long

    def __init__(self, host: ActionHost, name: str, package: str, step: float) -> None:
        self.host = host
        self.name = name
        self.step = step
        self.package = package
        self.goal_type = f"{package}/FibonacciActionGoal"
        self.feedback_type = f"{package}/FibonacciActionFeedback"
        self.result_type = f"{package}/FibonacciActionResult"
        self._ids = itertools.count(1)
        self._seq = itertools.count(1)
        self._tracked: dict[str, tuple[GoalRecord, dict[str, Any], float]] = {}
        self._runs: dict[str, FibonacciRun] = {}
        self._current: str | None = None
        self._next: str | None = None
        self._wakeup = asyncio.Event()
        self._texts: dict[str, str] = {}
        #: The newest stamp of a cancel request (actionlib's last_cancel_), in seconds.
        self._last_cancel = 0.0
        graph = host.graph
        graph.add_subscriber(FIBONACCI_NODE, f"{name}/goal", self.goal_type, self._on_goal)
        graph.add_subscriber(FIBONACCI_NODE, f"{name}/cancel", "actionlib_msgs/GoalID", self._on_cancel)
        graph.add_publisher(FIBONACCI_NODE, f"{name}/status", "actionlib_msgs/GoalStatusArray")
        graph.add_publisher(FIBONACCI_NODE, f"{name}/feedback", self.feedback_type)
        graph.add_publisher(FIBONACCI_NODE, f"{name}/result", self.result_type)

    def _header(self) -> dict[str, Any]:
        return {"seq": next(self._seq), "stamp": time_msg(time.time(), "ros1"), "frame_id": ""}

    def _status(self, goal_id: str) -> dict[str, Any]:
        record, goal_id_msg, _ = self._tracked[goal_id]
        return {"goal_id": goal_id_msg, "status": record.status, "text": self._texts.get(goal_id, "")}

    def _generate_id(self) -> dict[str, Any]:
        """actionlib's GoalIDGenerator: ``<node>-<n>-<secs>.<nsecs>`` (nsecs not zero-padded), stamped now."""
        now = time_msg(time.time(), "ros1")
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
                self.host.world.goals[record.goal_id] = record
                self._finish(record.goal_id, "RECALLED")
            return
        if not goal_id_msg.get("id"):
            goal_id_msg = self._generate_id()
        stamp = stamp_seconds(goal_id_msg.get("stamp"))
        if stamp == 0:
            stamp = time.time()  # actionlib stamps a goal sent with a zero stamp on arrival
        goal_id = str(goal_id_msg["id"])
        goal_id_msg = {"id": goal_id, "stamp": time_msg(stamp, "ros1")}
        record = GoalRecord(goal_id, order, ROS1_STATUS["PENDING"], accepted_at=stamp)
        self._tracked[goal_id] = (record, goal_id_msg, 0.0)
        self.host.world.goals[goal_id] = record
        given_stamp = stamp_seconds(msg.get("goal_id", {}).get("stamp"))
        if given_stamp != 0 and given_stamp <= self._last_cancel:
            self._finish(goal_id, "RECALLED", CANCELED_BEFORE_STAMP)
            return
        if not order_ok(order):
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
        stamp = stamp_seconds(msg.get("stamp"))
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
            goal_id_msg = {"id": cancel_id, "stamp": time_msg(stamp, "ros1")}
            self._tracked[cancel_id] = (record, goal_id_msg, time.monotonic())
        self._last_cancel = max(self._last_cancel, stamp)
        self.publish_status()
        self.host.world.notify()

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
        self.host.world.notify()

    def _publish(self, topic: str, msg_type: str, partial: dict[str, Any]) -> None:
        try:
            self.host.publish_json(topic, msg_type, partial)
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
                run = self._runs[goal_id] = FibonacciRun(record, self.step, self.host.world.notify)
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
