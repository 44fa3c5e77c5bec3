"""Checked sends: every act on the robot goes through here and through the safety seam (cancels: unguarded).

Each function takes what a caller gave (names, types, a message), makes the name absolute, has the client's
:class:`~rosbridge_mcp_server.client.Dialect` spell the type for the bridge, compares it with the graph,
checks the message as the bridge will read it against the type's definitions (raising a
:class:`~rosbridge_mcp_server.errors.NotSentError` that carries an example of the type), and only then asks
the guard of :mod:`rosbridge_mcp_server.robot.approval` whether the act may happen (:func:`approved`), telling
it the outcome once per act (:func:`carry_out`). Messages stay as the caller wrote them (time fields in
either spelling): the client respells them once, on the way out.

Nothing here knows MCP: the server hands in ``ask_person`` (its elicitation) through the tool's context.

The package, one module per kind of act: ``context.py`` (what an act needs, and what every send shares: the
scene a motion goal is judged against), ``topics.py`` (a publish, and the checks every publish makes),
``streams.py`` (a publish at a rate), ``services.py``, ``goals.py`` (action goals and their cancels) and
``parameters.py``.
"""

from __future__ import annotations

from rosbridge_mcp_server.robot.acting.context import SCENE_TIMEOUT, Acting, Timeouts, motion_scene
from rosbridge_mcp_server.robot.acting.goals import require_action_server, send_goal, stop_goals
from rosbridge_mcp_server.robot.acting.parameters import set_parameter
from rosbridge_mcp_server.robot.acting.services import ServiceReply, call_service
from rosbridge_mcp_server.robot.acting.streams import Streamed, StreamProgress, publish_stream
from rosbridge_mcp_server.robot.acting.topics import PING_LIMIT, Published, publish_once

__all__ = [
    "PING_LIMIT",
    "SCENE_TIMEOUT",
    "Acting",
    "Published",
    "ServiceReply",
    "StreamProgress",
    "Streamed",
    "Timeouts",
    "call_service",
    "motion_scene",
    "publish_once",
    "publish_stream",
    "require_action_server",
    "send_goal",
    "set_parameter",
    "stop_goals",
]
