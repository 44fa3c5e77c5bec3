"""ROS 2 action servers: ``/fibonacci`` (``example_interfaces/action/Fibonacci``) and the servers clients
host through rosbridge (``advertise_action``).

Every server (:class:`ActionServer`) keeps its goals by UUID and offers what a real one shows in the graph:
the hidden ``_action/status`` and ``_action/feedback`` topics and ``_action/*`` services.
"""

from __future__ import annotations

import asyncio
import itertools
import logging
import os
from collections.abc import Callable
from typing import Any

from rosbridge_mcp_server.sim.actions.common import (
    FIBONACCI_NODE,
    KEEP_FINISHED,
    ROS2_STATUS,
    ActionHost,
    FibonacciRun,
    order_ok,
    stamp_seconds,
    time_msg,
    uuid_bytes,
)
from rosbridge_mcp_server.sim.graph import ServiceEntry
from rosbridge_mcp_server.sim.world import GoalRecord

__all__ = ["ActionServer", "FeedbackFn", "FibonacciServer", "GoalHandle", "HostedActionServer"]

log = logging.getLogger("rosbridge_mcp_server.sim")


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

    def __init__(self, host: ActionHost, name: str, action_type: str, node: str) -> None:
        self.host = host
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
        graph = host.graph
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
        world = self.host.world
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
            if self.host.has_subscribers(self.feedback_topic):
                self._publish_quietly(
                    self.feedback_topic,
                    self.feedback_type,
                    {"goal_id": {"uuid": list(handle.uuid)}, "feedback": values},
                )
            self.host.world.notify()

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
            self.host.world.notify()

    def _forget_old(self) -> None:
        finished = [u for u, h in self.goals.items() if h.record.finished]
        for uuid in finished[:-KEEP_FINISHED]:
            del self.goals[uuid]

    def _publish_quietly(self, topic: str, msg_type: str, partial: dict[str, Any]) -> None:
        try:
            self.host.publish_json(topic, msg_type, partial)
        except Exception as exc:
            log.debug("cannot publish %s: %s", topic, exc)

    def publish_status(self) -> None:
        """``GoalStatusArray`` on the hidden status topic, sent on every change of a goal's state."""
        if not self.host.has_subscribers(self.status_topic):
            return
        status_list = [
            {
                "goal_info": {
                    "goal_id": {"uuid": list(h.uuid)},
                    "stamp": time_msg(h.record.accepted_at, "ros2"),
                },
                "status": h.record.status,
            }
            for h in self.goals.values()
        ]
        self._publish_quietly(
            self.status_topic, "action_msgs/msg/GoalStatusArray", {"status_list": status_list}
        )

    async def _send_goal_service(self, request: dict[str, Any]) -> dict[str, Any]:
        uuid = uuid_bytes(request["goal_id"]["uuid"])
        handle = self.submit(request["goal"], key=None, on_feedback=None, uuid=uuid)
        if handle is None:
            return {"accepted": False}
        return {"accepted": True, "stamp": time_msg(handle.record.accepted_at, "ros2")}

    async def _get_result_service(self, request: dict[str, Any]) -> dict[str, Any]:
        handle = self.goals.get(uuid_bytes(request["goal_id"]["uuid"]))
        if handle is None:
            return {"status": ROS2_STATUS["UNKNOWN"]}
        status, result = await handle.outcome()
        return {"status": status, "result": result}

    async def _cancel_goal_service(self, request: dict[str, Any]) -> dict[str, Any]:
        """``action_msgs/srv/CancelGoal``: zero id and stamp cancel all; a stamp, those accepted before."""
        info = request.get("goal_info", {})
        uuid = uuid_bytes(info.get("goal_id", {}).get("uuid", bytes(16)))
        stamp = stamp_seconds(info.get("stamp"))
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
                {"goal_id": {"uuid": list(h.uuid)}, "stamp": time_msg(h.record.accepted_at, "ros2")}
                for h in canceling
            ],
        }

    def remove(self) -> None:
        """Take the server out of the graph; goals still running end ABORTED."""
        graph = self.host.graph
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

    def __init__(self, host: ActionHost, name: str, action_type: str, step: float) -> None:
        super().__init__(host, name, action_type, FIBONACCI_NODE)
        self.step = step

    def goal_order(self, goal: dict[str, Any]) -> int:
        return int(goal.get("order", 0))

    def accepts(self, goal: dict[str, Any], goal_key: str) -> bool:
        order = self.goal_order(goal)
        if not order_ok(order):
            log.info("%s: goal %s with order %d rejected", self.name, goal_key, order)
            return False
        return True

    async def run_goal(self, handle: GoalHandle, feedback: FeedbackFn) -> tuple[str, dict[str, Any]]:
        run = FibonacciRun(handle.record, self.step, self.host.world.notify, handle.cancel)
        outcome = await run.execute(lambda sequence: feedback({"sequence": sequence}))
        return outcome, {"sequence": list(handle.record.sequence)}


class HostedActionServer(ActionServer):
    """An action server a client hosts with ``advertise_action``.

    Every goal is accepted (rosbridge auto-accepts) and forwarded to the client as a server-initiated
    ``send_action_goal``; the client's ``action_feedback`` and ``action_result`` come back through
    :meth:`feedback_from_client` / :meth:`result_from_client`. A ROS-side cancel is forwarded as
    ``cancel_action_goal``; the goal stays open until the client sends its result.
    """

    def __init__(self, host: ActionHost, name: str, action_type: str, owner: int, node: str) -> None:
        super().__init__(host, name, action_type, node)
        self.owner = owner
        self._counter = itertools.count(1)
        #: bridge goal id -> (handle, feedback function, result future)
        self.pending: dict[
            str, tuple[GoalHandle, FeedbackFn, asyncio.Future[tuple[str, dict[str, Any]]]]
        ] = {}

    async def run_goal(self, handle: GoalHandle, feedback: FeedbackFn) -> tuple[str, dict[str, Any]]:
        goal_type, _, _ = self.host.registry.action_parts(self.type)
        goal_id = f"action_goal:{self.name}:{next(self._counter)}"
        handle.bridge_id = goal_id
        future: asyncio.Future[tuple[str, dict[str, Any]]] = asyncio.get_running_loop().create_future()
        self.pending[goal_id] = (handle, feedback, future)
        try:
            frame = {
                "op": "send_action_goal",
                "id": goal_id,
                "action": self.name,
                "action_type": self.type,
                "args": self.host.registry.to_json(goal_type, handle.goal),
                "feedback": True,
            }
            if not self.host.send_to_client(self.owner, frame):
                log.warning("action %s: its client has gone; the goal will never end", self.name)
            return await future
        finally:
            self.pending.pop(goal_id, None)

    def on_cancel(self, handle: GoalHandle) -> None:
        goal_id = handle.bridge_id
        if goal_id is not None:
            self.host.send_to_client(
                self.owner, {"op": "cancel_action_goal", "id": goal_id, "action": self.name}
            )

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
