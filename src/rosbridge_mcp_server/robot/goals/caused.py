"""Goals this server caused through another carrier than its own goal runner, so that a stop reaches them.

``publish_action`` and ``navigate_to`` run their goals themselves (the registry tracks them while they run).
A goal can also be started by a plain publish or service call, which ends as soon as it is sent while the
goal runs on:

* a ROS 1 actionlib goal published on ``<action>/goal`` (a ``…ActionGoal`` message): its ``goal_id.id``; an
  empty id is named by the action server, so it is not known here;
* a ROS 2 goal sent through ``<action>/_action/send_goal``: its goal UUID;
* a goal pose for a navigator: ``/goal_pose`` (Nav2's bt_navigator sends itself a NavigateToPose goal) and
  ``/move_base_simple/goal`` (move_base gives its own action server a goal), also under a namespace. The
  navigator makes the goal, so its id is never known.

A goal whose id is not known is stopped by cancelling every goal of its action: what the robot would be
doing because of it.
"""

from __future__ import annotations

import base64
import binascii
import contextlib
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any, Final

from rosbridge_mcp_server.robot.effects import Effect

__all__ = ["GOAL_POSE_NAVIGATORS", "CausedGoal", "caused_by_call", "caused_by_publish", "uuid_hex"]

#: Goal pose topics and the action their navigator turns a pose into (in the topic's namespace).
GOAL_POSE_NAVIGATORS: Final = {"/goal_pose": "/navigate_to_pose", "/move_base_simple/goal": "/move_base"}


@dataclass(frozen=True)
class CausedGoal:
    """A goal a publish or a service call of this server started: on which action, its id if known."""

    action: str
    #: ROS 1 ``goal_id.id``, ROS 2 UUID in hex; ``None``: not known, so every goal of the action is cancelled.
    goal_id: str | None
    dialect: int
    #: The topic or service that carried it.
    carrier: str
    since: float = field(default_factory=time.monotonic, compare=False)

    @property
    def key(self) -> tuple[str, str | None]:
        return self.action, self.goal_id

    def describe(self) -> str:
        """E.g. ``goal g on /move_base (sent on /move_base/goal)``."""
        which = f"goal {self.goal_id}" if self.goal_id is not None else "every goal"
        return f"{which} on {self.action} (sent on {self.carrier})"


def caused_by_publish(topic: str, message: Any, effects: Iterable[Effect], dialect: int) -> CausedGoal | None:
    """The goal a message published on (the canonical) *topic* starts, if any; *effects* are the act's."""
    for effect in effects:
        if effect.kind == "action" and effect.what == "goal":
            goal_id = message.get("goal_id") if isinstance(message, dict) else None
            gid = goal_id.get("id") if isinstance(goal_id, dict) else None
            return CausedGoal(effect.name, gid if isinstance(gid, str) and gid else None, dialect, topic)
    for leaf, action in GOAL_POSE_NAVIGATORS.items():
        if topic == leaf or topic.endswith(leaf):
            namespace = topic[: -len(leaf)]
            return CausedGoal(f"{namespace}{action}", None, dialect, topic)
    return None


def caused_by_call(service: str, request: Any, effects: Iterable[Effect], dialect: int) -> CausedGoal | None:
    """The goal a call of (the canonical) *service* starts (ROS 2 ``_action/send_goal``), if any."""
    for effect in effects:
        if effect.kind == "action" and effect.what == "goal":
            goal_id = uuid_hex(request) if isinstance(request, dict) else None
            return CausedGoal(effect.name, goal_id, dialect, service)
    return None


def uuid_hex(goal_info: Any) -> str | None:
    """The hex of ``goal_info["goal_id"]["uuid"]`` (a ``GoalInfo``, a ``SendGoal`` request), or None."""
    if not isinstance(goal_info, dict):
        return None
    goal_id = goal_info.get("goal_id")
    uuid = goal_id.get("uuid") if isinstance(goal_id, dict) else None
    # uint8[16] arrives base64-encoded from rosbridge's JSON mode; accept a list of ints too.
    if isinstance(uuid, str):
        with contextlib.suppress(binascii.Error, ValueError):
            return base64.b64decode(uuid, validate=True).hex()
        return uuid
    if isinstance(uuid, list) and all(isinstance(b, int) and 0 <= b < 256 for b in uuid):
        return bytes(uuid).hex()
    return None
