"""The domain layer: what the tools know about a robot, with no MCP in it."""
