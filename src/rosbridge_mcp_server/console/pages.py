"""The console's static files (the page, its script and style, the MCP App's page), read from the package."""

from __future__ import annotations

from importlib import resources

__all__ = ["static_text"]


def static_text(name: str) -> str:
    """One of the files in ``console/static``."""
    return resources.files("rosbridge_mcp_server.console").joinpath("static", name).read_text("utf-8")
