"""The bridge's dialect as one object per session: what ``robot/`` asks instead of knowing ROS 1 from ROS 2.

``robot/`` works with type names as people write them and with ROS 2's time fields; a :class:`Dialect`,
built once per :class:`~rosbridge_mcp_server.client.session.BridgeSession` from its
:class:`~rosbridge_mcp_server.wire.ros_versions.RosInfo`, spells them for the bridge behind that session. The
client adapts an outgoing message once, on the way out (``publish``, ``call_service``); nothing above it
converts time fields. The rules themselves are pure and live in :mod:`rosbridge_mcp_server.wire.ros_versions`.
"""

from __future__ import annotations

from typing import Any, Final, Literal

from rosbridge_mcp_server.client.capabilities import BridgeCapabilities, capabilities_of
from rosbridge_mcp_server.wire import ros_versions as rules
from rosbridge_mcp_server.wire.ros_versions import ActionTypeNames, Ros1ActionTypes, RosInfo

__all__ = ["ActionTypeNames", "Dialect", "Ros1ActionTypes"]

_QOS_NOT_ON_ROS1: Final = "QoS not applied: ROS 1 has no QoS (rosbridge 0.11 ignores it)."
_QOS_SENT: Final = (
    "QoS sent; rosbridge applies it from 2.0.7 (Humble), 2.7.0 (Jazzy), 3.3.0 (Kilted) on, older bridges "
    "ignore it, and only the first subscriber of a topic on the bridge sets it."
)


class Dialect:
    """How the bridge of one session spells types, time fields, goal states and subscription options, and
    what it can do (:attr:`capabilities`, decided once here)."""

    __slots__ = ("capabilities", "info", "version")

    def __init__(self, info: RosInfo) -> None:
        self.info = info
        self.version: Literal[1, 2] = info.version
        #: What this bridge can do, named (what ``robot/`` asks instead of which bridge it is).
        self.capabilities: BridgeCapabilities = capabilities_of(info)

    @classmethod
    def for_version(cls, version: int) -> Dialect:
        """The dialect of a ROS *version* when no session is at hand (a goal record's end, say)."""
        return _BY_VERSION[1 if version == 1 else 2]

    def __repr__(self) -> str:
        return f"Dialect({self.info.describe()})"

    # --- type names ---------------------------------------------------------------------------------

    def message_type(self, type_name: str) -> str:
        """*type_name* as this bridge accepts a message type (ROS 1 ``pkg/T``, ROS 2 ``pkg/msg/T``)."""
        return rules.normalize_type(type_name, self.version, "msg")

    def service_type(self, type_name: str) -> str:
        """*type_name* as this bridge accepts a service type (ROS 1 ``pkg/T``, ROS 2 ``pkg/srv/T``)."""
        return rules.normalize_type(type_name, self.version, "srv")

    def action_type(self, type_name: str) -> str:
        """The name this bridge knows an action by (ROS 1 ``pkg/TAction``, ROS 2 ``pkg/action/T``)."""
        return rules.action_type_names(type_name).for_version(self.version)

    @staticmethod
    def short_type(type_name: str) -> str:
        """``pkg/msg/Type`` (and ``/srv/``, ``/action/``) → ``pkg/Type``, the form both dialects share."""
        return rules.short_type(type_name)

    @staticmethod
    def same_type(a: str, b: str) -> bool:
        """Whether two spellings name the same type (``pkg/msg/Type`` and ``pkg/Type`` do)."""
        return rules.same_type(a, b)

    @staticmethod
    def split_type(type_name: str) -> tuple[str, str | None, str]:
        """``(package, category or None, name)``; :class:`UnknownTypeError` for a name that is not a type."""
        return rules.split_type(type_name)

    @staticmethod
    def action_names(type_name: str) -> ActionTypeNames:
        """Every spelling of an action type (``pkg/T``, ``pkg/action/T``, ``pkg/TAction`` name the same)."""
        return rules.action_type_names(type_name)

    @staticmethod
    def same_action(a: str, b: str) -> bool:
        """Whether two spellings name the same action type."""
        first, second = rules.action_type_names(a), rules.action_type_names(b)
        return (first.package, first.name) == (second.package, second.name)

    # --- messages -----------------------------------------------------------------------------------

    def outgoing(self, message: Any) -> Any:
        """*message* with its time fields spelled the way this bridge reads them.

        ROS 1 (0.11) reads only ``secs``/``nsecs`` and silently leaves a time at zero given ``sec``/
        ``nanosec``; ROS 2 reads both, so its messages go out untouched (the same object).
        """
        return rules.adapt_message(message, self.version)

    @staticmethod
    def seconds(stamp: Any) -> float | None:
        """A received time or duration, in seconds, whichever spelling the bridge wrote it in; ``None`` when
        *stamp* is not one or is zero."""
        return rules.time_seconds(stamp)

    # --- goals --------------------------------------------------------------------------------------

    def goal_status(self, code: int) -> str:
        """The status word for *code* in this dialect's numbering (``status 17`` if unknown)."""
        return rules.goal_status_name(code, self.version)

    def goal_ended(self, code: int) -> bool:
        """The goal has finished in state *code*."""
        return rules.is_terminal_status(code, self.version)

    def goal_succeeded(self, code: int) -> bool:
        """The goal succeeded (4 on ROS 2, 3 on ROS 1)."""
        return rules.is_success_status(code, self.version)

    # --- subscriptions ------------------------------------------------------------------------------

    def subscription_qos(self, requested: dict[str, Any] | None) -> tuple[dict[str, Any] | None, str | None]:
        """The ``qos`` object to send for *requested* (reliability, durability, depth) and a note saying
        what the bridge makes of it; ``(None, None)`` when nothing was asked."""
        if not requested:
            return None, None
        if self.version == 1:
            return None, _QOS_NOT_ON_ROS1
        wire = dict(requested)
        if "depth" in wire:
            wire["history"] = "keep_last"
        return wire, _QOS_SENT

    @staticmethod
    def compression_for(*, fixed_size_arrays: bool) -> Literal["cbor"] | None:
        """``"cbor"`` for a large message the bridge can send as CBOR, else ``None`` (JSON).

        rosbridge_suite cannot send a message with a fixed-size array as CBOR (its typed-array table misses
        them and the conversion fails, so such a message never comes), on both lines; byte arrays would
        arrive as bytes rather than base64.
        """
        return None if fixed_size_arrays else "cbor"

    @property
    def drops_large_cbor(self) -> bool:
        """A CBOR message above the connection's fragment size never comes (ROS 2 rosbridge_suite cannot
        fragment a CBOR frame, 10 MB by default): read it once more as JSON, which it fragments."""
        return self.capabilities.drops_large_cbor


_BY_VERSION: Final = {1: Dialect(RosInfo(version=1)), 2: Dialect(RosInfo(version=2))}
