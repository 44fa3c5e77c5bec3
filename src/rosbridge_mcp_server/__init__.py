"""rosbridge-mcp-server: an MCP server that watches and drives a ROS robot through rosbridge.

The layers, each a package that imports only those listed before it: ``wire`` (the rosbridge protocol, no
I/O) → ``client`` (asyncio connections) → ``robot`` (the domain: graph, messages, goals, checked sends) →
``tools`` (one module per MCP tool) → ``server`` (everything that imports ``mcp``) → ``cli`` (the command,
whose ``main()`` is the console script). ``sim`` is a simulated robot that shares only the wire with them.
"""

from __future__ import annotations

__all__ = ["__version__"]

__version__ = "0.1.0"
