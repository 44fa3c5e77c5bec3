"""Safety for real robots: the policy, the guard that applies it to every acting call, the audit, the e-stop.

Domain-level: nothing here knows MCP. The server gives each tool a guard (:class:`PolicyGuard`) and a way to
ask the person; the acting layer calls the guard before anything is sent.
"""

from rosbridge_mcp_server.robot.activity import SessionActivity, Stream, VelocityTopic
from rosbridge_mcp_server.robot.velocity import clamp_text, is_velocity_type, measure
from rosbridge_mcp_server.safety.estop import StopReport, emergency_stop
from rosbridge_mcp_server.safety.guard import Audit, PolicyGuard, calling_as, current_caller, question
from rosbridge_mcp_server.safety.policy import (
    NameRules,
    Policy,
    PolicyError,
    PublishLimits,
    VelocityCaps,
    load_policy,
    parse_policy,
)

__all__ = [
    "Audit",
    "NameRules",
    "Policy",
    "PolicyError",
    "PolicyGuard",
    "PublishLimits",
    "SessionActivity",
    "StopReport",
    "Stream",
    "VelocityCaps",
    "VelocityTopic",
    "calling_as",
    "clamp_text",
    "current_caller",
    "emergency_stop",
    "is_velocity_type",
    "load_policy",
    "measure",
    "parse_policy",
    "question",
]
