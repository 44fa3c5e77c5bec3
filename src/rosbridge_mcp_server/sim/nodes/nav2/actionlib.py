"""ROS 1 form of the Nav2 world's actions: a small actionlib server per action, over its five topics.

Simpler than ``/fibonacci``'s SimpleActionServer (:mod:`sim.actions.ros1`): every goal is accepted and runs on
its own (no preemption by a newer goal), a goal runs the Nav2 world's steps with one feedback each and
succeeds, a cancel ends it PREEMPTED; the status list goes out at 5 Hz while anyone listens.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import time
from collections.abc import Awaitable, Callable
from typing import Any

from rosbridge_mcp_server.sim.actions.common import ROS1_STATUS, stamp_seconds, time_msg
from rosbridge_mcp_server.sim.nodes.kit import NodeKit

__all__ = ["ActionlibServer", "Runner"]

#: Runs a goal instead of the fixed steps: (goal, cancel, feedback) → (``succeeded``/``canceled``/``aborted``,
#: result); feedback gets the action's feedback message.
Runner = Callable[
    [dict[str, Any], asyncio.Event, Callable[[dict[str, Any]], None]], Awaitable[tuple[str, dict[str, Any]]]
]
_STATES = {"succeeded": "SUCCEEDED", "canceled": "PREEMPTED", "aborted": "ABORTED"}

STATUS_PERIOD = 0.2
#: Finished goals stay in the status list this long (actionlib's default).
KEEP_FINISHED = 5.0


class ActionlibServer:
    """``<name>/goal`` → ACTIVE, ``steps`` feedbacks ``step`` s apart → SUCCEEDED (PREEMPTED on a cancel)."""

    def __init__(
        self,
        kit: NodeKit,
        *,
        name: str,
        node: str,
        package: str,
        action: str,
        steps: int,
        step: float,
        on_success: Callable[[dict[str, Any]], None] | None = None,
        runner: Runner | None = None,
    ) -> None:
        self.kit = kit
        self.name = name
        self.types = {
            part: f"{package}/{action}Action{part.capitalize()}" for part in ("goal", "feedback", "result")
        }
        self.steps = steps
        self.step = step
        self.on_success = on_success
        self.runner = runner
        self._ids = itertools.count(1)
        #: goal id -> (status code, goal_id message, finished at (monotonic) or 0, cancel event)
        self._goals: dict[str, tuple[int, dict[str, Any], float, asyncio.Event]] = {}
        self._tasks: set[asyncio.Task[None]] = set()
        graph = kit.graph
        graph.add_subscriber(node, f"{name}/goal", self.types["goal"], self._on_goal)
        graph.add_subscriber(node, f"{name}/cancel", "actionlib_msgs/GoalID", self._on_cancel)
        graph.add_publisher(node, f"{name}/status", "actionlib_msgs/GoalStatusArray")
        graph.add_publisher(node, f"{name}/feedback", self.types["feedback"])
        graph.add_publisher(node, f"{name}/result", self.types["result"])
        kit.loops.append(self._status_loop)

    def _publish(self, leaf: str, msg_type: str, partial: dict[str, Any]) -> None:
        topic = f"{self.name}/{leaf}"
        if self.kit.bridge.has_subscribers(topic):
            self.kit.bridge.publish_json(topic, msg_type, partial)

    def _status(self, goal_id: str) -> dict[str, Any]:
        code, goal_id_msg, _, _ = self._goals[goal_id]
        return {"goal_id": goal_id_msg, "status": code, "text": ""}

    def take_goal(self, msg: dict[str, Any], source: int) -> None:
        """A ``…ActionGoal`` as if it came on ``<name>/goal`` (move_base's own goal pose topic sends one)."""
        self._on_goal(msg, source)

    def _on_goal(self, msg: dict[str, Any], _source: int) -> None:
        goal_id_msg = dict(msg.get("goal_id") or {})
        goal_id = str(goal_id_msg.get("id") or f"{self.name}-{next(self._ids)}-{time.time():.6f}")
        if goal_id in self._goals:
            return
        goal_id_msg = {"id": goal_id, "stamp": goal_id_msg.get("stamp") or time_msg(time.time(), "ros1")}
        self._goals[goal_id] = (ROS1_STATUS["ACTIVE"], goal_id_msg, 0.0, asyncio.Event())
        task = asyncio.get_running_loop().create_task(self._run(goal_id, dict(msg.get("goal") or {})))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        self.publish_status()

    def _on_cancel(self, msg: dict[str, Any], _source: int) -> None:
        """actionlib's cancel: an empty id with a zero stamp cancels every goal, an id that goal, a stamp
        every goal stamped at or before it."""
        wanted = msg.get("id") or ""
        stamp = stamp_seconds(msg.get("stamp"))
        for goal_id, (code, goal_id_msg, finished, cancel) in self._goals.items():
            hit = (
                (not wanted and stamp == 0)
                or wanted == goal_id
                or (stamp != 0 and stamp_seconds(goal_id_msg.get("stamp")) <= stamp)
            )
            if not finished and hit and code == ROS1_STATUS["ACTIVE"]:
                self._goals[goal_id] = (ROS1_STATUS["PREEMPTING"], self._goals[goal_id][1], 0.0, cancel)
                cancel.set()
        self.publish_status()

    async def _run(self, goal_id: str, goal: dict[str, Any]) -> None:
        cancel = self._goals[goal_id][3]
        if self.runner is not None:

            def feedback(values: dict[str, Any]) -> None:
                self._publish(
                    "feedback",
                    self.types["feedback"],
                    {"header": self.kit.header(""), "status": self._status(goal_id), "feedback": values},
                )

            state, result = await self.runner(goal, cancel, feedback)
            self._end(goal_id, _STATES.get(state, "ABORTED"), cancel, result)
            return
        for _ in range(self.steps):
            if cancel.is_set():
                break
            self._publish(
                "feedback",
                self.types["feedback"],
                {"header": self.kit.header(""), "status": self._status(goal_id), "feedback": {}},
            )
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(cancel.wait(), self.step)
        state = "PREEMPTED" if cancel.is_set() else "SUCCEEDED"
        if state == "SUCCEEDED" and self.on_success is not None:
            self.on_success(goal)
        self._end(goal_id, state, cancel, {})

    def _end(self, goal_id: str, state: str, cancel: asyncio.Event, result: dict[str, Any]) -> None:
        self._goals[goal_id] = (ROS1_STATUS[state], self._goals[goal_id][1], time.monotonic(), cancel)
        self._publish(
            "result",
            self.types["result"],
            {"header": self.kit.header(""), "status": self._status(goal_id), "result": result},
        )
        self.publish_status()
        self.kit.world.notify()

    def publish_status(self) -> None:
        now = time.monotonic()
        for goal_id in [
            g for g, (_, _, done, _) in self._goals.items() if done and now - done > KEEP_FINISHED
        ]:
            del self._goals[goal_id]
        self._publish(
            "status",
            "actionlib_msgs/GoalStatusArray",
            {"header": self.kit.header(""), "status_list": [self._status(g) for g in self._goals]},
        )

    async def _status_loop(self) -> None:
        try:
            while True:
                self.publish_status()
                await asyncio.sleep(STATUS_PERIOD)
        finally:
            for task in list(self._tasks):
                task.cancel()
