"""``navigate_to``'s goal as a model writes it, checked before anything is asked of the robot: a pose
(``{"x": 2, "y": 1.5, "yaw": 90}`` or ``[2, 1.5, 90]``: metres, degrees), poses in a row, a place named in the
policy's ``[places]``, or a move relative to the robot (forward, left, turn). A key written for another
(``theta``, ``heading``, ...) is named with the one meant; every refusal says nothing was sent."""

from __future__ import annotations

import difflib
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Final

from rosbridge_mcp_server.tools.base import ToolFailure

__all__ = ["GOAL_EXAMPLE", "MAX_COORDINATE", "GoalArgument", "Place", "read_goal"]

#: The farthest a goal's coordinate (metres; degrees for a yaw) may be: beyond any map, and drawable.
MAX_COORDINATE = 100_000.0
#: A place of the policy: x m, y m, yaw degrees in the map frame.
Place = tuple[float, float, float]


#: Keys a pose is often written with, and the key meant (``theta`` is turtlesim's, in radians).
_POSE_KEYS: Final[dict[str, str]] = {
    "theta": "yaw",
    "heading": "yaw",
    "angle": "yaw",
    "yaw_deg": "yaw",
    "yaw_degrees": "yaw",
    "rotation": "yaw",
    "orientation": "yaw",
    "direction": "yaw",
}


def _shown(value: Any) -> str:
    """A value the caller gave, as JSON (as they wrote it), shortened."""
    text = json.dumps(value, ensure_ascii=False, default=str)
    return text if len(text) <= 120 else text[:120] + "…"


def _number(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ToolFailure(f"{what} must be a finite number, not {_shown(value)}. Nothing was sent.")
    if abs(value) > MAX_COORDINATE:
        raise ToolFailure(
            f"{what} {value:g} is beyond ±{MAX_COORDINATE:g} (metres, or degrees for yaw). Nothing was sent."
        )
    return float(value)


def _meant(unknown: set[str]) -> str:
    """`` Did you mean "yaw" (degrees) for "theta"?`` for keys that stand for a pose's own, or ``""``."""
    pairs = []
    for key in sorted(unknown):
        meant = _POSE_KEYS.get(key.lower()) or next(
            iter(difflib.get_close_matches(key, ["x", "y", "yaw"])), ""
        )
        if meant:
            pairs.append(f'"{meant}"{" (degrees)" if meant == "yaw" else ""} for "{key}"')
    return f" Did you mean {', '.join(pairs)}?" if pairs else ""


def _waypoint(item: Any, where: str) -> tuple[float, float, float | None]:
    if isinstance(item, dict):
        unknown = set(item) - {"x", "y", "yaw"}
        if unknown or "x" not in item or "y" not in item:
            missing = [key for key in ("x", "y") if key not in item]
            wrong = f"unknown {', '.join(sorted(unknown))}" if unknown else f"no {' or '.join(missing)}"
            raise ToolFailure(
                f'{where} must be {{"x": m, "y": m, "yaw": degrees}} (no yaw keeps the heading); got '
                f"{_shown(item)}: {wrong}.{_meant(unknown)} Nothing was sent."
            )
        yaw = item.get("yaw")
        return (
            _number(item["x"], f"{where}.x"),
            _number(item["y"], f"{where}.y"),
            None if yaw is None else _number(yaw, f"{where}.yaw"),
        )
    if isinstance(item, list) and len(item) in (2, 3):
        yaw_value = item[2] if len(item) == 3 else None
        return (
            _number(item[0], f"{where}[0]"),
            _number(item[1], f"{where}[1]"),
            None if yaw_value is None else _number(yaw_value, f"{where}[2]"),
        )
    raise ToolFailure(
        f'{where} must be {{"x": m, "y": m, "yaw": degrees}} or [x, y, yaw]; got {_shown(item)}. Nothing was '
        "sent."
    )


GOAL_EXAMPLE = '{"x": 2, "y": 1.5, "yaw": 90} (metres, DEGREES; no yaw: keep heading)'


def _parse_goal(goal: Any) -> tuple[str, list[tuple[float, float, float | None]]]:
    """A pose or poses given as ``goal``: ("pose", [one]) or ("waypoints", [...])."""
    if isinstance(goal, dict):
        return "pose", [_waypoint(goal, "goal")]
    if isinstance(goal, list) and goal and all(isinstance(v, int | float) for v in goal):
        return "pose", [_waypoint(goal, "goal")]
    if isinstance(goal, list) and goal:
        ways = [_waypoint(item, f"goal[{i}]") for i, item in enumerate(goal)]
        return ("waypoints" if len(ways) > 1 else "pose"), ways
    raise ToolFailure(
        f"goal must be a pose {GOAL_EXAMPLE}, a place name, or a list of poses; got {_shown(goal)}. "
        "Nothing was sent."
    )


@dataclass(frozen=True)
class GoalArgument:
    """Where the call asks to go, checked: a ``pose`` or ``waypoints`` (``ways``: x m, y m, yaw degrees or
    ``None``), a ``place`` of the policy, or a ``relative`` move (``move``: forward m, left m, turn
    degrees)."""

    kind: str
    ways: list[tuple[float, float, float | None]]
    place: str
    move: tuple[float, float, float]
    frame: str


def read_goal(
    goal: Any, frame: str, move: tuple[float, float, float], places: Mapping[str, Place]
) -> GoalArgument:
    """``navigate_to``'s goal, frame and relative move (forward, left, turn) checked against each other and
    the policy's *places*; each fault said, with nothing sent."""
    relative = any(move)
    for value, what, limit in zip(move, ("forward", "left", "turn"), (100.0, 100.0, 360.0), strict=True):
        if not math.isfinite(value) or abs(value) > limit:
            raise ToolFailure(f"{what} must be within ±{limit:g}, not {value!r}. Nothing was sent.")
    if isinstance(goal, str) and not goal.strip():
        goal = None
    if goal is not None and relative:
        raise ToolFailure("Give a goal or a relative move (forward/left/turn), not both. Nothing was sent.")
    if goal is None and not relative:
        raise ToolFailure(
            f'Say where to go: goal {GOAL_EXAMPLE} in the map frame, goal "PLACE", or forward/left/turn '
            "relative to the robot. Nothing was sent."
        )
    place = goal.strip() if isinstance(goal, str) else ""
    kind, ways = ("place", []) if place else ("relative", []) if relative else _parse_goal(goal)
    if place and place not in places:
        known = ", ".join(sorted(places)) or "none (the policy has no [places])"
        raise ToolFailure(f"No place named {place!r}. Known places: {known}. Nothing was sent.")
    if frame and kind != "pose":
        raise ToolFailure(f"frame applies to one goal pose, not to a {kind}. Nothing was sent.")
    return GoalArgument(kind, ways, place, move, frame)
