"""The only module of the benchmark that imports rosbridge_mcp_server's internals, and why each is needed.

Every other figure goes through the package's public ways in (the console script, the simulated robot's
``python -m`` entry, MCP over stdio or HTTP, the rosbridge protocol on a raw WebSocket). These figures measure
a part on its own, so they need the part itself:

* :class:`RosbridgeClient`: rows 2a (our client's ``call_service`` against the raw floor), 4· (100 calls
  at once through our client) and 5a (1,000 messages of the 1 kHz topic through our client's
  ``subscribe``). They hold the client to the floor, below any tool, which no public entry shows on its own.
* :func:`infrastructure_types`: the floor of row 8b, a fresh raw client asking the types of the services our
  server asks about on a connection's first ``list_services``: which ones it can tell from their names is the
  server's own knowledge.

When one of these moves, this is the one file to change.
"""

from __future__ import annotations

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.robot.known_types import infrastructure_types

__all__ = ["RosbridgeClient", "infrastructure_types"]
