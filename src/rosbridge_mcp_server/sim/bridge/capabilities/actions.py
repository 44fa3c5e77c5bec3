"""rosbridge's ROS 2 action capabilities: goals for action servers in the graph (``send_action_goal``,
``cancel_action_goal``) and action servers hosted by clients (``advertise_action``, ``unadvertise_action``,
``action_feedback``, ``action_result``). ROS 1 rosbridge has none of these ops."""

from __future__ import annotations

import asyncio
import logging
from typing import Any

from rosbridge_mcp_server.sim.actions import ActionServer, GoalHandle, HostedActionServer
from rosbridge_mcp_server.sim.bridge.core import (
    BridgeCore,
    Capability,
    OpError,
    OpHandler,
    check_fields,
    extract_id,
)
from rosbridge_mcp_server.sim.connection import Connection
from rosbridge_mcp_server.sim.graph import ROSBRIDGE_NODE, resolve_name
from rosbridge_mcp_server.sim.interfaces import ConversionError, InterfaceError

__all__ = ["ACTION_SERVER_WAIT", "Actions"]

log = logging.getLogger("rosbridge_mcp_server.sim")

#: rosbridge (ROS 2, 2.0.5+/2.5.0+) waits this long for an action server before giving up.
ACTION_SERVER_WAIT = 1.0
#: action_msgs/GoalStatus codes.
SUCCEEDED = 4
ABORTED = 6


class Actions(Capability):
    """Goals sent through the bridge, and action servers clients host."""

    def __init__(self, core: BridgeCore) -> None:
        super().__init__(core)
        #: rosbridge's ``client_handler_list``: a class attribute, so shared by every connection.
        self.goal_table: dict[Any, GoalHandle] = {}

    def ops(self) -> dict[str, OpHandler]:
        if not self.core.ros2:
            return {}
        return {
            "send_action_goal": self.send_action_goal,
            "cancel_action_goal": self.cancel_action_goal,
            "advertise_action": self.advertise_action,
            "unadvertise_action": self.unadvertise_action,
            "action_feedback": self.action_feedback,
            "action_result": self.action_result,
        }

    # --- goals --------------------------------------------------------------------------------------------

    async def send_action_goal(self, conn: Connection, msg: dict[str, Any]) -> None:
        core = self.core
        check_fields(
            msg,
            [
                (True, "action", (str,)),
                (True, "action_type", (str,)),
                (False, "fragment_size", (int, type(None))),
                (False, "compression", (str,)),
            ],
        )
        action = msg["action"]
        name, cid = extract_id(action, msg.get("id"))
        hash(cid)  # the goal table is keyed by id: an unhashable id fails before anything starts

        owner_only = core.config.rs
        # rosbridge_suite: one goal table for the process; rosbridge-server-rs: the starting connection's.
        key = (conn.id, cid) if owner_only else cid

        def finish(values: Any, status: int, result: bool) -> None:
            if owner_only:
                # rosbridge-server-rs: result true only for a goal that succeeded; a failure is ABORTED.
                result = result and status == SUCCEEDED
                status = status or ABORTED
            reply: dict[str, Any] = {
                "op": "action_result",
                "action": action,
                "values": values,
                "status": status,
                "result": result,
            }
            if cid is not None:
                reply["id"] = cid
            conn.send(reply)

        try:
            action_type = core.registry.resolve(msg["action_type"], "action")
            goal_type, result_type, feedback_type = core.registry.action_parts(action_type)
            goal = core.registry.from_json(goal_type, core.args_dict(goal_type, msg.get("args", {})))
        except (InterfaceError, ConversionError) as exc:
            log.error("client %d: send_action_goal %s: %s", conn.id, action, exc)
            finish(str(exc), 0, False)
            return
        server = core.graph.actions.get(resolve_name(name))
        if not isinstance(server, ActionServer) or server.type != action_type:
            await asyncio.sleep(ACTION_SERVER_WAIT)
            finish("No action server available", 0, False)
            return

        def on_feedback(partial: dict[str, Any]) -> None:
            reply = {
                "op": "action_feedback",
                "action": action,
                "values": core.json_form(feedback_type, partial),
            }
            if cid is not None:
                reply["id"] = cid
            conn.send(reply)

        handle = server.submit(goal, key=cid, on_feedback=on_feedback if msg.get("feedback", False) else None)
        if handle is None:
            finish("Action goal was rejected", 0, False)
            return
        self.goal_table[key] = handle
        try:
            status, partial_result = await handle.outcome()
        finally:
            if self.goal_table.get(key) is handle:
                del self.goal_table[key]
        finish(core.json_form(result_type, partial_result), status, True)

    def cancel_action_goal(self, conn: Connection, msg: dict[str, Any]) -> None:
        check_fields(msg, [(True, "action", (str,))])
        _, cid = extract_id(msg["action"], msg.get("id"))
        if self.core.config.rs:
            handle = self.goal_table.get((conn.id, cid))
            if handle is None:
                # Also for a goal another connection started: only that connection may cancel it.
                raise OpError("unknown active goal")
            handle.request_cancel()
            return
        handle = self.goal_table.get(cid)
        if handle is not None:
            handle.request_cancel()

    def client_gone(self, conn: Connection) -> None:
        """rosbridge_suite lets a departed client's goals run on; rosbridge-server-rs cancels them."""
        if not self.core.config.rs:
            return
        for key, handle in list(self.goal_table.items()):
            if isinstance(key, tuple) and key[0] == conn.id:
                handle.request_cancel()

    # --- action servers hosted by clients -----------------------------------------------------------------

    def _hosted(self, conn: Connection, action: str) -> HostedActionServer:
        server = self.core.graph.actions.get(resolve_name(action))
        if not isinstance(server, HostedActionServer) or server.owner != conn.id:
            raise OpError(f"Action {action} has not been advertised via rosbridge.")
        return server

    def advertise_action(self, conn: Connection, msg: dict[str, Any]) -> None:
        check_fields(msg, [(True, "action", (str,)), (True, "type", (str,))])
        name = self.core.name(msg["action"])
        action_type = self.core.resolve_type(msg["type"], "action")
        old = self.core.graph.actions.get(name)
        if old is not None:
            old.remove()
        HostedActionServer(self.core, name, action_type, conn.id, ROSBRIDGE_NODE)
        self.core.world.notify()

    def unadvertise_action(self, conn: Connection, msg: dict[str, Any]) -> None:
        check_fields(msg, [(True, "action", (str,))])
        # Goals still running end ABORTED, as rosbridge's unadvertise_action does.
        self._hosted(conn, msg["action"]).remove()
        self.core.world.notify()

    def action_feedback(self, conn: Connection, msg: dict[str, Any]) -> None:
        check_fields(msg, [(True, "action", (str,)), (True, "id", (str,)), (True, "values", (dict,))])
        server = self._hosted(conn, msg["action"])
        _, _, feedback_type = self.core.registry.action_parts(server.type)
        try:
            self.core.registry.from_json(feedback_type, msg["values"])
        except ConversionError as exc:
            raise OpError(str(exc)) from exc
        if not server.feedback_from_client(msg["id"], msg["values"]):
            raise OpError(f"Action goal {msg['id']} not found")

    def action_result(self, conn: Connection, msg: dict[str, Any]) -> None:
        check_fields(
            msg,
            [
                (True, "action", (str,)),
                (True, "id", (str,)),
                (True, "status", (int,)),
                (True, "result", (bool,)),
            ],
        )
        server = self._hosted(conn, msg["action"])
        values = msg.get("values", {})
        if msg["result"]:
            _, result_type, _ = self.core.registry.action_parts(server.type)
            try:
                self.core.registry.from_json(result_type, values)
            except ConversionError as exc:
                raise OpError(str(exc)) from exc
        if not server.result_from_client(msg["id"], msg["status"], msg["result"], values):
            raise OpError(f"Action goal {msg['id']} not found")
