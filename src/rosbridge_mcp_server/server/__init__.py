"""Everything that imports ``mcp``: the server (``app``), tool modules as MCP tools (``adapter``), the checks
every call gets first (``tool_calls``), several robots (``fleet``), the stdio and HTTP transports (``stdio``,
``http``), and every use of SDK internals (``sdk``)."""

from __future__ import annotations

from rosbridge_mcp_server.server.app import INSTRUCTIONS, SERVER_NAME, build_fleet_server, build_server
from rosbridge_mcp_server.server.fleet import Robot
from rosbridge_mcp_server.server.stdio import serve_stdio

__all__ = ["INSTRUCTIONS", "SERVER_NAME", "Robot", "build_fleet_server", "build_server", "serve_stdio"]
