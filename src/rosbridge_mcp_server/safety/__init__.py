"""Safety for real robots: the policy, the guard that applies it to every acting call, the audit, the e-stop.

Domain-level: nothing here knows MCP. Each robot's session holds its guard (:class:`PolicyGuard`), the server
gives each tool call a way to ask the person, and the acting layer calls the guard before anything is sent.
What this server set going on a robot (``robot/activity.py``) and its velocity rules (``robot/velocity.py``)
are domain, imported from ``robot/``.
"""

from rosbridge_mcp_server.safety.estop import PRESSER_NAMES, Presser, StopReport, emergency_stop
from rosbridge_mcp_server.safety.guard import (
    LATCH_RULE,
    Audit,
    AuditEntry,
    PolicyGuard,
    question,
)
from rosbridge_mcp_server.safety.operator import Operator, PendingConfirmation
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
    "LATCH_RULE",
    "PRESSER_NAMES",
    "Audit",
    "AuditEntry",
    "NameRules",
    "Operator",
    "PendingConfirmation",
    "Policy",
    "PolicyError",
    "PolicyGuard",
    "Presser",
    "PublishLimits",
    "StopReport",
    "VelocityCaps",
    "emergency_stop",
    "load_policy",
    "parse_policy",
    "question",
]
