"""The operator console: a web page for the person beside the robot (``--console [HOST:]PORT``).

It shows each robot's connection, the acting calls as they happen, the streams and goals running, the camera
and the confirmations waiting for the person, with Approve / Deny, E-STOP and Release. It sits above
``safety/`` (it answers the :class:`~rosbridge_mcp_server.safety.Operator`'s questions and latches its stop)
and below ``cli/``; it imports no ``mcp``.
"""

from rosbridge_mcp_server.console.hub import ConsoleHub, Frame, RobotView, summary_text
from rosbridge_mcp_server.console.serve import RunningConsole, open_console
from rosbridge_mcp_server.console.settings import ConsoleSettings, console_settings
from rosbridge_mcp_server.console.web import SECRET_HEADER, console_app, static_text

__all__ = [
    "SECRET_HEADER",
    "ConsoleHub",
    "ConsoleSettings",
    "Frame",
    "RobotView",
    "RunningConsole",
    "console_app",
    "console_settings",
    "open_console",
    "static_text",
    "summary_text",
]
