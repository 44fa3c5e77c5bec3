"""The rosbridge side of the simulated robot: every op a client may send, handled as rosbridge_suite does.

Laid out along rosbridge_suite's own seams: :mod:`.protocol` (the input buffer and the dispatch), the
:mod:`.capabilities` that own the ops (topics, services, actions, fragments), the :mod:`.core` they share,
rosbridge's :mod:`.client_manager`, and :mod:`.server` (connections). Each handler follows the capability of
the same name in rosbridge_suite: the same field checks, the same replies, and the same silences. Errors
that the real server only logs are logged here too (to stderr, logger ``rosbridge_mcp_server.sim``) and
nothing is sent back; the only failures a client ever sees on the wire are ``service_response`` /
``action_result`` with ``result: false``.
"""

from rosbridge_mcp_server.sim.bridge.core import BridgeConfig, CallFailed, OpError
from rosbridge_mcp_server.sim.bridge.server import Bridge

__all__ = ["Bridge", "BridgeConfig", "CallFailed", "OpError"]
