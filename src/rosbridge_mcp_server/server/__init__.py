"""Everything that imports ``mcp``: the server (``app``), tool modules as MCP tools (``adapter``), the stdio
transport (``stdio``), and every use of SDK internals (``sdk``)."""

from __future__ import annotations

from rosbridge_mcp_server.server.app import INSTRUCTIONS, SERVER_NAME, build_server
from rosbridge_mcp_server.server.stdio import serve_stdio

__all__ = ["INSTRUCTIONS", "SERVER_NAME", "build_server", "serve_stdio"]
