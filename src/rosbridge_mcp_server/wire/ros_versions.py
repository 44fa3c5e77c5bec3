"""ROS 1 vs ROS 2 rules, without I/O.

* Type names: ROS 1 (rosbridge 0.11.x) only accepts ``pkg/Type``; a three-part name is an invalid
  type string there. ROS 2 accepts both ``pkg/Type`` and ``pkg/msg/Type``; we send the full form,
  which is also what its graph queries return.
* Action types as people write them (``pkg/Fibonacci``, ``pkg/action/Fibonacci``,
  ``pkg/FibonacciAction``) map to the ROS 2 ``pkg/action/Fibonacci`` and to the ROS 1 actionlib
  message family (``pkg/FibonacciAction``, ``...ActionGoal``, ``...ActionFeedback``, ``...ActionResult``).
* Time fields: ROS 1 reads only ``secs``/``nsecs`` and silently ignores ``sec``/``nanosec`` (the time
  stays 0), so messages are converted before they go to ROS 1. ROS 2 accepts both spellings.
* Goal status numbers differ: ROS 2 ``action_msgs/GoalStatus`` 0..6, ROS 1
  ``actionlib_msgs/GoalStatus`` 0..9.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Final, Literal

from rosbridge_mcp_server.errors import UnknownTypeError

__all__ = [
    "ROS1_GOAL_STATUS",
    "ROS1_TERMINAL",
    "ROS2_GOAL_STATUS",
    "ROS2_TERMINAL",
    "ActionTypeNames",
    "Ros1ActionTypes",
    "RosInfo",
    "action_type_names",
    "adapt_message",
    "goal_status_name",
    "is_success_status",
    "is_terminal_status",
    "normalize_type",
    "same_type",
    "short_type",
    "split_type",
    "to_ros1_time",
]

Category = Literal["msg", "srv", "action"]

_NAME = r"[A-Za-z][A-Za-z0-9_]*"
_TYPE_RE: Final = re.compile(rf"^/?({_NAME})/(?:(msg|srv|action)/)?({_NAME})$")


@dataclass(frozen=True, slots=True)
class RosInfo:
    """What kind of bridge is on the other side, detected once per connection.

    ``calls_threaded`` and ``goals_threaded`` say whether a ROS 2 bridge runs each call and each goal apart
    from the rest of its connection, as judged from its behaviour; ``None`` when that could not be told
    (then it is taken to handle a connection in order, the safe side). They are never read from a node's
    parameters: the node named ``/rosbridge_websocket`` may be another bridge on the same graph.
    ``status_replies``: the bridge answered a refused op with an error ``status`` (rosbridge-server-rs does;
    rosbridge_suite never). ``cancel_owner_only``: only the connection that started a goal may cancel it.
    The distro says nothing here: rosbridge 2.1.0 runs a connection's calls in order on Jazzy and Kilted
    alike, later releases changed the launch defaults, and a launch file may override them. What was
    verified on which bridge: docs/rosbridge-behaviour.md. What this means a bridge can do is decided once, in
    ``client/capabilities.py``; nothing above the client reads these fields.
    """

    version: Literal[1, 2]
    distro: str | None = None
    calls_threaded: bool | None = None
    goals_threaded: bool | None = None
    status_replies: bool = False
    cancel_owner_only: bool | None = None

    @property
    def has_action_ops(self) -> bool:
        """The bridge has ``send_action_goal`` (ROS 2; ROS 1 uses actionlib topics)."""
        return self.version == 2

    @property
    def honours_service_timeout(self) -> bool:
        """``call_service`` reads ``timeout`` (ROS 2 Humble 2.0.1+, Jazzy 2.2.0+; ignored before)."""
        return self.version == 2

    @property
    def may_be_in_order(self) -> bool:
        """One connection's service calls may hold each other up.

        rosbridge 0.11 (ROS 1) runs every call in a thread of its own. A ROS 2 bridge that did not say it
        does the same is taken to handle a connection strictly in order: 2.1.0's defaults and Humble's do.
        """
        return self.version == 2 and self.calls_threaded is not True

    @property
    def goals_may_block(self) -> bool:
        """A goal may hold up its connection until it ends, so a cancel on that connection comes too late."""
        return self.version == 2 and self.goals_threaded is not True

    @property
    def one_call_per_connection(self) -> bool:
        """Two calls in flight on one connection answer slowly: spread them over connections.

        rosbridge 0.11.17 sends the second of two answers on one socket about 40 ms late (its server side
        leaves Nagle's algorithm on): three rosapi look-ups took 52 ms side by side on one connection, 17 ms
        one after another and 13 ms side by side on three connections.
        """
        return self.version == 1

    def describe(self) -> str:
        """``ROS 2 (jazzy)``, ``ROS 1``."""
        return f"ROS {self.version}" + (f" ({self.distro})" if self.distro else "")


def split_type(type_name: str) -> tuple[str, str | None, str]:
    """``(package, category or None, name)`` of a type name; raises :class:`UnknownTypeError`."""
    match = _TYPE_RE.match(type_name.strip())
    if match is None:
        raise UnknownTypeError(
            type_name,
            "A type name looks like `pkg/Type` (ROS 1 and 2) or `pkg/msg/Type` (ROS 2), "
            "e.g. `geometry_msgs/Twist`.",
        )
    pkg, category, name = match.groups()
    return pkg, category, name


def normalize_type(type_name: str, version: int, category: Category = "msg") -> str:
    """The spelling of *type_name* that the bridge of this ROS *version* accepts.

    ROS 1: ``pkg/Type``. ROS 2: ``pkg/<category>/Type`` (*category* fills in a missing middle part).
    """
    pkg, given, name = split_type(type_name)
    if version == 1:
        return f"{pkg}/{name}"
    return f"{pkg}/{given or category}/{name}"


def short_type(name: str) -> str:
    """``pkg/msg/Type`` (and ``/srv/``, ``/action/``) → ``pkg/Type``; other names unchanged."""
    parts = name.strip().strip("/").split("/")
    if len(parts) == 3 and parts[1] in ("msg", "srv", "action"):
        return f"{parts[0]}/{parts[2]}"
    return name.strip()


def same_type(a: str, b: str) -> bool:
    """Whether two spellings name the same type (``pkg/msg/Type`` and ``pkg/Type`` do)."""
    return short_type(a) == short_type(b)


@dataclass(frozen=True, slots=True)
class Ros1ActionTypes:
    """The actionlib message family of one ROS 1 action."""

    action: str
    goal: str
    feedback: str
    result: str
    goal_id: str = "actionlib_msgs/GoalID"
    status_array: str = "actionlib_msgs/GoalStatusArray"


@dataclass(frozen=True, slots=True)
class ActionTypeNames:
    """Every spelling of one action type."""

    package: str
    name: str

    @property
    def ros2(self) -> str:
        """``pkg/action/Name``."""
        return f"{self.package}/action/{self.name}"

    @property
    def ros1(self) -> Ros1ActionTypes:
        """``pkg/NameAction`` and its ``...ActionGoal``/``...ActionFeedback``/``...ActionResult``."""
        base = f"{self.package}/{self.name}Action"
        return Ros1ActionTypes(
            action=base, goal=f"{base}Goal", feedback=f"{base}Feedback", result=f"{base}Result"
        )

    @property
    def ros1_parts(self) -> tuple[str, str, str]:
        """The ROS 1 messages inside actionlib's family: ``pkg/NameGoal``, ``...Result``, ``...Feedback``."""
        base = f"{self.package}/{self.name}"
        return f"{base}Goal", f"{base}Result", f"{base}Feedback"

    def for_version(self, version: int) -> str:
        """The name the bridge of this ROS *version* knows the action by."""
        return self.ros2 if version == 2 else self.ros1.action


_ACTION_SUFFIXES: Final = ("ActionGoal", "ActionFeedback", "ActionResult", "Action")


def action_type_names(type_name: str) -> ActionTypeNames:
    """Read an action type as users write it.

    ``pkg/Fibonacci``, ``pkg/action/Fibonacci``, ``pkg/FibonacciAction``, ``pkg/msg/FibonacciAction``
    and ``pkg/FibonacciActionGoal`` all name the same action. In the ``pkg/action/Name`` form the
    name is taken as written (ROS 2 action names do not carry an ``Action`` suffix).
    """
    pkg, category, name = split_type(type_name)
    if category == "srv":
        raise UnknownTypeError(
            type_name, "That is a service type; an action type looks like `pkg/action/Name`."
        )
    if category != "action":
        for suffix in _ACTION_SUFFIXES:
            if name.endswith(suffix) and len(name) > len(suffix):
                name = name[: -len(suffix)]
                break
    return ActionTypeNames(pkg, name)


# --- time fields ------------------------------------------------------------------------------------

_ROS2_TIME_KEYS: Final = frozenset({"sec", "nanosec"})


def _convert_time(value: Any, from_keys: frozenset[str], mapping: dict[str, str]) -> Any:
    if isinstance(value, dict):
        keys = value.keys()
        if keys and keys <= from_keys and all(isinstance(v, int | float) for v in value.values()):
            return {mapping[k]: v for k, v in value.items()}
        return {k: _convert_time(v, from_keys, mapping) for k, v in value.items()}
    if isinstance(value, list):
        return [_convert_time(v, from_keys, mapping) for v in value]
    return value


def to_ros1_time(msg: Any) -> Any:
    """A copy of *msg* with every ``{sec, nanosec}`` object spelled ``{secs, nsecs}``.

    ROS 1 rosbridge (0.11.x) reads only ``secs``/``nsecs`` and silently leaves a time at zero when
    given ``sec``/``nanosec``.
    """
    return _convert_time(msg, _ROS2_TIME_KEYS, {"sec": "secs", "nanosec": "nsecs"})


def time_seconds(value: Any) -> float | None:
    """A time or duration read in either spelling (ROS 1 ``secs``/``nsecs``, ROS 2 ``sec``/``nanosec``), in
    seconds; ``None`` when *value* is not one, or is zero (an unset stamp)."""
    if not isinstance(value, dict):
        return None
    seconds = value.get("sec", value.get("secs"))
    nanos = value.get("nanosec", value.get("nsecs", 0))
    if not isinstance(seconds, int | float) or not isinstance(nanos, int | float):
        return None
    return (float(seconds) + float(nanos) / 1e9) or None


def adapt_message(msg: Any, version: int) -> Any:
    """*msg* with time fields spelled the way the bridge of this ROS *version* reads them.

    ROS 2 reads both spellings, so its messages go out untouched.
    """
    return to_ros1_time(msg) if version == 1 else msg


# --- goal status ------------------------------------------------------------------------------------

ROS2_GOAL_STATUS: Final[dict[int, str]] = {
    0: "unknown",
    1: "accepted",
    2: "executing",
    3: "canceling",
    4: "succeeded",
    5: "canceled",
    6: "aborted",
}
ROS2_TERMINAL: Final = frozenset({4, 5, 6})

ROS1_GOAL_STATUS: Final[dict[int, str]] = {
    0: "pending",
    1: "active",
    2: "preempted",
    3: "succeeded",
    4: "aborted",
    5: "rejected",
    6: "preempting",
    7: "recalling",
    8: "recalled",
    9: "lost",
}
# 9 (lost) is never sent by a server; actionlib clients use it locally, so it counts as final.
ROS1_TERMINAL: Final = frozenset({2, 3, 4, 5, 8, 9})


def goal_status_name(code: int, version: int) -> str:
    """The status word for *code* in the numbering of ROS *version* (``status 17`` if unknown)."""
    names = ROS2_GOAL_STATUS if version == 2 else ROS1_GOAL_STATUS
    return names.get(code, f"status {code}")


def is_terminal_status(code: int, version: int) -> bool:
    """The goal has finished in this state."""
    return code in (ROS2_TERMINAL if version == 2 else ROS1_TERMINAL)


def is_success_status(code: int, version: int) -> bool:
    """The goal succeeded (4 on ROS 2, 3 on ROS 1)."""
    return code == (4 if version == 2 else 3)
