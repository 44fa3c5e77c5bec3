"""The fence stands on what the model cannot write.

``[navigation]``'s zones and distance limit are judged where the robot is and where its goal lands on the map,
and both are read from the robot's graph: its transforms (``/tf``), its localisation (``/initialpose``, AMCL),
its map, and Nav2's own fences (keep-out masks, the speed limit). An act that writes any of them (a *fence
write*, :mod:`rosbridge_mcp_server.robot.effects`: by type as well as by name, namespaced too) could move the
world under the zones: a forged ``map → odom`` puts a goal in keep-out where the fence sees free floor. So
while ``[navigation]`` has zones or limits, a fence write is refused, unless the policy names it in
``[navigation] allow_fence_writes`` (globs, matched against the canonical topic or service name).
"""

from __future__ import annotations

from fnmatch import fnmatchcase
from typing import TYPE_CHECKING

from rosbridge_mcp_server.safety.navigation import NavigationRefusal

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.approval import Act
    from rosbridge_mcp_server.safety.policy import NavigationRules

__all__ = ["fence_refusal", "writes_fence"]


def writes_fence(act: Act) -> bool:
    """Whether *act* changes what the safety fence or localisation reads."""
    return any(effect.kind == "fence" for effect in act.effects)


def fence_refusal(act: Act, rules: NavigationRules) -> NavigationRefusal | None:
    """Why the fence write *act* may not be sent while ``[navigation]`` has zones or limits, or ``None``."""
    if not rules.configured or not writes_fence(act):
        return None
    if any(fnmatchcase(act.name, pattern) for pattern in rules.allow_fence_writes):
        return None
    what = "; ".join(effect.why for effect in act.effects if effect.kind == "fence" and effect.why)
    return NavigationRefusal(
        f"[navigation] fence write: {act.name}",
        f"Refused: {act.tool} on {act.name} writes what the safety fence and localisation read ({what}). "
        "The safety policy's [navigation] zones and limits are judged on it, so while they are set it may "
        "not be written unless [navigation] allow_fence_writes lists it; nothing was sent. Tell the user; "
        "do not try to reach the same effect another way.",
    )
