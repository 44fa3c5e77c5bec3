"""The operator console: a web page for the person beside the robot (``--console [HOST:]PORT``).

It shows each robot's connection, the acting calls as they happen, the streams and goals running, the camera,
the robot's pose on its map and the confirmations waiting for the person, with Approve / Deny, E-STOP and
Release. It sits above ``safety/`` (it answers the :class:`~rosbridge_mcp_server.safety.Operator`'s questions
and latches its stop) and below ``cli/``; it imports no ``mcp``.

The web side (``serve.py``: uvicorn; ``web.py``: Starlette) is imported from its own modules, only when a
console is served, so a server without ``--console`` does not load them.
"""

from rosbridge_mcp_server.config.console import ConsoleSettings, console_settings
from rosbridge_mcp_server.console.hub import ConsoleHub, RobotView, summary_text
from rosbridge_mcp_server.console.pages import static_text

__all__ = [
    "ConsoleHub",
    "ConsoleSettings",
    "RobotView",
    "console_settings",
    "static_text",
    "summary_text",
]
