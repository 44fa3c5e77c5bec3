"""``python -m rosbridge_mcp_server``: the same as the ``rosbridge-mcp-server`` command."""

from __future__ import annotations

from rosbridge_mcp_server.cli import main

__all__: list[str] = []

if __name__ == "__main__":
    main()
