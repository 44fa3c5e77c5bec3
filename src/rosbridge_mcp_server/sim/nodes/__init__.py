"""The simulated world's nodes, each registering its topics, services and parameters on the graph."""

from rosbridge_mcp_server.sim.nodes.builder import WorldNodes
from rosbridge_mcp_server.sim.nodes.camera import CameraSettings

__all__ = ["CameraSettings", "WorldNodes"]
