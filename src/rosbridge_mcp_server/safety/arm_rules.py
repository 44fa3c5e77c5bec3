"""The policy's ``[arm]`` section: how fast and where a manipulator may move, whatever carries its goal.

The URDF's joint position and speed limits hold always (``safety/arm.py``); this section adds::

    [arm]
    speed_scale = 0.25           # at most this share of each joint's URDF speed (0 < scale ≤ 1; default 0.25)
    frame = "base_link"          # the link the boxes are given in (default: the URDF's root link)
    margin = 0.05                # m kept from every keep-out box and inside every workspace box (default 0)
    link_radius = 0.05           # m: a link's radius where its URDF geometry gives none (default 0.05)
    confirm = "motion"           # "never" | "motion": ask before each arm motion and controller switch
    max_gripper_effort = 20      # N: most effort a gripper goal may ask (default: the URDF's effort limit)
    [arm.workspace]              # boxes the tool stays inside (one of them): min and max corners [x, y, z] m
    table = [[0.1, -0.5, 0.0], [0.8, 0.5, 1.0]]
    [arm.keep_out]               # boxes no link of the arm may enter
    person = [[-1, 0.6, 0], [1, 2, 2]]

Parsed here so that ``policy.py`` stays one screenful per section; every key optional, unknown keys an error.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

__all__ = [
    "ARM_KEYS",
    "DEFAULT_LINK_RADIUS",
    "DEFAULT_SPEED_SCALE",
    "ArmRules",
    "Box",
    "describe_arm",
    "parse_arm",
]

#: The share of each joint's URDF speed an arm motion may use when the policy says nothing.
DEFAULT_SPEED_SCALE = 0.25
#: A link's capsule radius (m) against the keep-out boxes where its URDF geometry gives none.
DEFAULT_LINK_RADIUS = 0.05

ArmConfirm = Literal["never", "motion"]
#: A named box: its name, its minimum corner and its maximum corner (x, y, z in metres).
Box = tuple[str, tuple[float, float, float], tuple[float, float, float]]

ARM_KEYS = (
    "speed_scale",
    "frame",
    "margin",
    "link_radius",
    "confirm",
    "max_gripper_effort",
    "workspace",
    "keep_out",
)


@dataclass(frozen=True)
class ArmRules:
    """``[arm]``: the speed share of the URDF limits, the workspace and keep-out boxes, who confirms."""

    speed_scale: float = DEFAULT_SPEED_SCALE
    #: The link the boxes are given in; ``None``: the URDF's root link.
    frame: str | None = None
    margin: float = 0.0
    link_radius: float = DEFAULT_LINK_RADIUS
    confirm: ArmConfirm = "never"
    max_gripper_effort: float | None = None
    workspace: tuple[Box, ...] = ()
    keep_out: tuple[Box, ...] = ()

    @property
    def configured(self) -> bool:
        """Whether boxes restrict where the arm goes: then a motion that cannot be checked is refused."""
        return bool(self.workspace or self.keep_out)


class _ArmError(ValueError):
    pass


def _fail(where: str, text: str) -> _ArmError:
    return _ArmError(f"{where}: {text}")


def parse_arm(data: Mapping[str, Any], where: str) -> ArmRules:
    """``[arm]`` from parsed TOML (``data`` is the whole policy); :class:`ValueError` says what is wrong."""
    table = data.get("arm", {})
    if not isinstance(table, dict):
        raise _fail(where, f"arm must be a table ([arm]), not {table!r}")
    for key in table:
        if key not in ARM_KEYS:
            close = difflib.get_close_matches(key, ARM_KEYS, n=1, cutoff=0.6)
            hint = f"; did you mean {close[0]!r}?" if close else f"; known keys: {', '.join(ARM_KEYS)}"
            raise _fail(where, f"unknown key [arm] {key!r}{hint}")
    scale = _number(table, "speed_scale", where, DEFAULT_SPEED_SCALE)
    if not 0 < scale <= 1:
        raise _fail(
            where,
            f"[arm] speed_scale must be more than 0 and at most 1 (a share of the URDF speeds), "
            f"not {scale!r}",
        )
    margin = _number(table, "margin", where, 0.0)
    if margin < 0:
        raise _fail(where, f"[arm] margin must be a number of metres ≥ 0, not {margin!r}")
    radius = _number(table, "link_radius", where, DEFAULT_LINK_RADIUS)
    if radius < 0 or radius > 1:
        raise _fail(where, f"[arm] link_radius must be a number of metres from 0 to 1, not {radius!r}")
    effort = _number(table, "max_gripper_effort", where, None) if "max_gripper_effort" in table else None
    if effort is not None and effort <= 0:
        raise _fail(where, f"[arm] max_gripper_effort must be more than 0 N, not {effort!r}")
    confirm = table.get("confirm", "never")
    if confirm not in ("never", "motion"):
        raise _fail(where, f"[arm] confirm must be 'never' or 'motion', not {confirm!r}")
    frame = table.get("frame")
    if frame is not None and (not isinstance(frame, str) or not frame.strip().strip("/")):
        raise _fail(where, f'[arm] frame must be a link name, e.g. "base_link", not {frame!r}')
    return ArmRules(
        speed_scale=scale,
        frame=frame.strip().strip("/") if isinstance(frame, str) else None,
        margin=margin,
        link_radius=radius,
        confirm=confirm,
        max_gripper_effort=effort,
        workspace=_boxes(table, "workspace", where),
        keep_out=_boxes(table, "keep_out", where),
    )


def _number(table: Mapping[str, Any], key: str, where: str, default: float | None) -> Any:
    if key not in table:
        return default
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise _fail(where, f"[arm] {key} must be a finite number, not {value!r}")
    return float(value)


def _corner(value: Any) -> tuple[float, float, float] | None:
    if not isinstance(value, list) or len(value) != 3:
        return None
    out = []
    for item in value:
        if isinstance(item, bool) or not isinstance(item, int | float) or not math.isfinite(item):
            return None
        out.append(float(item))
    return out[0], out[1], out[2]


def _boxes(table: Mapping[str, Any], key: str, where: str) -> tuple[Box, ...]:
    boxes = table.get(key, {})
    example = f"[arm.{key}] table = [[0.1, -0.5, 0.0], [0.8, 0.5, 1.0]]"
    if not isinstance(boxes, dict):
        raise _fail(where, f"[arm] {key} must be a table of named boxes, e.g. {example}")
    out: list[Box] = []
    for name, corners in boxes.items():
        low = high = None
        if isinstance(corners, list) and len(corners) == 2:
            low, high = _corner(corners[0]), _corner(corners[1])
        if low is None or high is None or any(a >= b for a, b in zip(low, high, strict=True)):
            raise _fail(
                where,
                f"[arm.{key}] {name} must be two corners [[x, y, z], [x, y, z]] in metres, the first smaller "
                f"on every axis, e.g. {example}; got {corners!r}",
            )
        out.append((name, low, high))
    return tuple(out)


def describe_arm(rules: ArmRules) -> str:
    """``[arm]`` in one line for ``check`` and the start-up log."""
    parts = [f"every joint within its URDF limits, at most {rules.speed_scale:g} of its URDF speed"]
    if rules.workspace:
        parts.append(f"the tool inside {', '.join(name for name, _, _ in rules.workspace)}")
    if rules.keep_out:
        parts.append(
            f"no link in {', '.join(name for name, _, _ in rules.keep_out)} (links as capsules, "
            f"{rules.link_radius:g} m where the URDF gives no size)"
        )
    if rules.margin:
        parts.append(f"a margin of {rules.margin:g} m")
    if rules.max_gripper_effort is not None:
        parts.append(f"gripper effort ≤ {rules.max_gripper_effort:g} N")
    if rules.confirm != "never":
        parts.append("the person confirms each arm motion and controller switch")
    return f"  [arm] {'; '.join(parts)}"
