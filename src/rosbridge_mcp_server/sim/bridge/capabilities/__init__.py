"""The ops of the simulated rosbridge, grouped like rosbridge_suite's ``capabilities/``: topics, services,
actions and fragments. Each capability owns its op handlers and what it keeps per client."""

from rosbridge_mcp_server.sim.bridge.capabilities.actions import Actions
from rosbridge_mcp_server.sim.bridge.capabilities.fragments import Fragments
from rosbridge_mcp_server.sim.bridge.capabilities.services import Services
from rosbridge_mcp_server.sim.bridge.capabilities.topics import Topics

__all__ = ["Actions", "Fragments", "Services", "Topics"]
