"""The MCP server: ``build_server`` registers every tool module on an ``MCPServer``.

The rosbridge client connects in the background from the server's lifespan, so ``initialize`` and
``tools/list`` work while the robot is down; tools then fail fast with the not-connected text naming the URL.
"""

from __future__ import annotations

import logging
import typing
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from typing import Any, Literal

from mcp.server.mcpserver import MCPServer
from mcp.types import CallToolResult, TextContent

from rosbridge_mcp_server import __version__
from rosbridge_mcp_server.robot.acting import Act, Guard
from rosbridge_mcp_server.robot.graph import RosGraph
from rosbridge_mcp_server.robot.warm_up import ServiceTypeWarmUp
from rosbridge_mcp_server.safety import PolicyGuard, SessionActivity
from rosbridge_mcp_server.server.adapter import tool_from_module
from rosbridge_mcp_server.server.console_app import console_app
from rosbridge_mcp_server.server.sdk import server_answering_unlisted
from rosbridge_mcp_server.tools import TOOL_MODULES, list_services, stop_robot

if typing.TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.config import Config

__all__ = ["INSTRUCTIONS", "SERVER_NAME", "build_server"]

_log = logging.getLogger("rosbridge_mcp_server.server")

SERVER_NAME = "rosbridge"

INSTRUCTIONS = """\
This server connects to a real (or simulated) ROS robot through rosbridge. Some tools only read the robot's \
state; publish_topic, publish_service, publish_action, cancel_action and set_parameter act on the robot and \
can make it move or change how it behaves.

Work like this:
1. Look before acting: list_topics, list_services and list_actions show what the robot has, with the exact \
names and types; get_topic_info shows who publishes and subscribes a topic; describe_type shows a type's \
fields with an example. To see the robot's state: subscribe_topic reads messages, get_image shows a camera, \
get_transform says where a frame is (e.g. base_link in odom).
2. Use those exact names and types. Messages, requests and goals are JSON objects; omitted fields are \
zero or empty, and {} is fine for empty messages. Units are SI: metres, seconds, radians, m/s, rad/s.
3. Movement: velocity commands (e.g. geometry_msgs/msg/Twist on /turtle1/cmd_vel) usually act briefly; \
publish_topic with rate_hz and duration keeps the robot moving and stops it with zeros at the end. Prefer \
small, safe values and say what you are about to do.
4. publish_action waits for the goal to finish and cancels it on timeout; cancel_action stops goals that run.
5. stop_robot stops everything this server started (streams, velocity, goals): use it when in doubt.

A safety policy set by the robot's operator may refuse a call (the error names the rule) or ask the person \
at the client to confirm it. A refusal is final: do not try to reach the same effect another way; tell the \
user what was refused and why.

A failed call comes back as an error whose text says what went wrong and what to try (a field that does not \
fit the type, an unknown name, the robot being unreachable). Nothing is queued while the robot is \
unreachable, and publish_topic first checks that the bridge answers, so a command is not delivered late. A \
request that timed out may still take effect later: check the robot's state before repeating it.\
"""


_READ_ONLY_NOTE = """

This server is read-only: it lists only tools that read the robot, and refuses any other.\
"""


def build_server(
    client: RosbridgeClient,
    config: Config,
    *,
    guard: Guard | None = None,
    activity: SessionActivity | None = None,
    console_view: Callable[[], dict[str, Any]] | None = None,
) -> MCPServer[None]:
    """An ``MCPServer`` with every tool, driving ``client`` (started and closed by the server's lifespan).

    Every act on the robot is first approved by *guard* (default: a :class:`PolicyGuard` for
    ``config.policy``, audited on stderr). A read-only policy lists only the reading tools. *activity*
    (default: a new one) is what the tools record they set going; pass one to share it (the console's E-STOP).
    With *console_view* (the operator console's snapshot) the server also offers the console's read-only view
    as an MCP App: the ``show_console`` tool and its ``ui://`` resource (``server/console_app.py``).
    """
    graph = RosGraph(client)
    policy = config.policy
    approver: Guard = guard if guard is not None else PolicyGuard(policy)
    activity = activity if activity is not None else SessionActivity()
    chosen = [m for m in TOOL_MODULES if config.tools is None or m.SPEC.name in config.tools]
    if any(not m.SPEC.hints.read_only for m in chosen) and stop_robot not in chosen:
        # Whoever can set the robot going can stop it, whatever --tools picked.
        chosen.append(stop_robot)
    modules = [m for m in chosen if m.SPEC.hints.read_only or not policy.read_only]
    if list_services in modules:
        client.watch(ServiceTypeWarmUp(client, graph))

    @asynccontextmanager
    async def lifespan(_server: MCPServer[None]) -> AsyncIterator[None]:
        await client.start()
        _log.info("rosbridge-mcp-server %s: connecting to %s in the background", __version__, client.url)
        try:
            yield None
        finally:
            await client.close()

    tools = [
        tool_from_module(module, client, config, graph, guard=approver, activity=activity)
        for module in modules
    ]
    # Acting tools a read-only policy keeps from the list; a tool --tools left out stays simply unknown.
    withheld = {m.SPEC.name for m in chosen} - {m.SPEC.name for m in modules}

    def unlisted(name: str, arguments: dict[str, Any]) -> CallToolResult | None:
        """A withheld acting tool called by name anyway: refused, and audited like any refusal."""
        if name not in withheld:
            return None
        approver.record(Act(name, _KIND_OF.get(name, "topic"), "", "", arguments), "withheld: read-only")
        text = (
            f"{name} is not available: this server is read-only (its operator started it with --read-only or "
            "a policy with read_only = true), so nothing was sent. Only the tools in tools/list can be used."
        )
        return CallToolResult(content=[TextContent(type="text", text=text)], is_error=True)

    return server_answering_unlisted(
        unlisted,
        name=SERVER_NAME,
        title="rosbridge MCP server",
        description="Watch and drive a ROS 1 / ROS 2 robot through rosbridge",
        instructions=INSTRUCTIONS + (_READ_ONLY_NOTE if policy.read_only else ""),
        version=__version__,
        tools=tools,
        extensions=[console_app(console_view)] if console_view is not None else None,
        lifespan=lifespan,
        log_level=config.log_level,
    )


#: What a withheld tool would have acted on, for its audit line.
_KIND_OF: dict[str, Literal["topic", "service", "action", "parameter"]] = {
    "publish_service": "service",
    "publish_action": "action",
    "cancel_action": "action",
    "set_parameter": "parameter",
}
