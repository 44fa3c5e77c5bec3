"""The policy file read (:func:`load_policy`) and checked (:func:`parse_policy`): every key optional, every
unknown key an error naming it and the likely meant one, every value checked with a worded
:class:`PolicyError`."""

from __future__ import annotations

import difflib
import math
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rosbridge_mcp_server.safety.arm_rules import ArmRules, parse_arm
from rosbridge_mcp_server.safety.policy.rules import (
    ACT_KINDS,
    APPROVALS,
    CONFIRM_MODES,
    DEFAULT_CONFIRM_TIMEOUT,
    NameRules,
    NavigationRules,
    Policy,
    PolicyError,
    PublishLimits,
    RecordingLimits,
    VelocityCaps,
    Zone,
)

__all__ = ["load_policy", "parse_policy"]

_TOP_KEYS = (
    "read_only",
    "confirm",
    "confirm_timeout",
    "approvals",
    *ACT_KINDS,
    "velocity",
    "publish",
    "recording",
    "navigation",
    "places",
    "arm",
)
_RULE_KEYS = ("allow", "deny")
_MOTION_KEYS = ("allow", "deny", "motion")
_VELOCITY_KEYS = ("max_linear", "max_angular", "mode")
_PUBLISH_KEYS = ("max_rate_hz", "max_duration")
_RECORDING_KEYS = ("enabled", "max_seconds", "max_megabytes")
_NAVIGATION_KEYS = (
    "robot_radius",
    "max_goal_distance",
    "confirm",
    "allowed_zones",
    "keep_out",
    "allow_fence_writes",
)


def load_policy(path: str | Path, *, source: str = "--policy") -> Policy:
    """Read and check the policy file at ``path``; :class:`PolicyError` names the file and the problem."""
    file = Path(path)
    try:
        data = tomllib.loads(file.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise PolicyError(f"{source}: policy file {str(file)!r} does not exist") from None
    except OSError as exc:
        raise PolicyError(f"{source}: cannot read policy file {str(file)!r}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise PolicyError(f"{source}: policy file {str(file)!r} is not UTF-8 text") from None
    except tomllib.TOMLDecodeError as exc:
        raise PolicyError(f"{source}: policy file {str(file)!r} is not valid TOML: {exc}") from None
    return parse_policy(data, where=str(file))


def parse_policy(data: Mapping[str, Any], *, where: str = "policy") -> Policy:
    """A :class:`Policy` from parsed TOML; every key optional, every unknown key an error."""
    _known_keys(data, _TOP_KEYS, where, "")
    read_only = _bool(data, "read_only", where)
    confirm_text = data.get("confirm", "never")
    if confirm_text not in CONFIRM_MODES:
        raise PolicyError(
            f"{where}: confirm must be one of {', '.join(repr(m) for m in CONFIRM_MODES)}, not "
            f"{confirm_text!r}"
        )
    timeout = _positive(data, "confirm_timeout", "", where, "seconds")
    if timeout == 0:
        raise PolicyError(f"{where}: confirm_timeout must be more than 0 seconds")
    approvals = data.get("approvals", "client")
    if approvals not in APPROVALS:
        raise PolicyError(
            f"{where}: approvals must be one of {', '.join(repr(a) for a in APPROVALS)}, not {approvals!r}"
        )
    rules = {section: _name_rules(data, section, where) for section in ACT_KINDS}
    motion = {
        section: _globs(table, "motion", section, where) if "motion" in table else ()
        for section in ("topics", "services")
        for table in (_table(data, section, where, _MOTION_KEYS),)
    }
    return Policy(
        read_only=read_only,
        confirm=confirm_text,
        confirm_timeout=DEFAULT_CONFIRM_TIMEOUT if timeout is None else timeout,
        approvals=approvals,
        motion_services=motion["services"],
        motion_topics=motion["topics"],
        topics=rules["topics"],
        services=rules["services"],
        actions=rules["actions"],
        parameters=rules["parameters"],
        velocity=_velocity(data, where),
        publish=_publish(data, where),
        recording=_recording(data, where),
        navigation=_navigation(data, where),
        places=_places(data, where),
        arm=_arm(data, where),
        source=where,
    )


def _known_keys(table: Mapping[str, Any], known: tuple[str, ...], where: str, section: str) -> None:
    for key in table:
        if key in known:
            continue
        close = difflib.get_close_matches(key, known, n=1, cutoff=0.6)
        hint = f"; did you mean {close[0]!r}?" if close else f"; known keys: {', '.join(known)}"
        place = f"[{section}] " if section else ""
        raise PolicyError(f"{where}: unknown key {place}{key!r}{hint}")


def _table(data: Mapping[str, Any], section: str, where: str, known: tuple[str, ...]) -> Mapping[str, Any]:
    table = data.get(section, {})
    if not isinstance(table, dict):
        raise PolicyError(f"{where}: {section} must be a table ([{section}]), not {table!r}")
    _known_keys(table, known, where, section)
    return table


def _bool(data: Mapping[str, Any], key: str, where: str) -> bool:
    value = data.get(key, False)
    if not isinstance(value, bool):
        raise PolicyError(f"{where}: {key} must be true or false, not {value!r}")
    return value


def _name_rules(data: Mapping[str, Any], section: str, where: str) -> NameRules:
    table = _table(data, section, where, _MOTION_KEYS if section in ("topics", "services") else _RULE_KEYS)
    allow = _globs(table, "allow", section, where) if "allow" in table else None
    deny = _globs(table, "deny", section, where) if "deny" in table else ()
    return NameRules(allow=allow, deny=deny)


def _globs(table: Mapping[str, Any], key: str, section: str, where: str) -> tuple[str, ...]:
    value = table[key]
    if not isinstance(value, list) or not all(isinstance(item, str) and item.strip() for item in value):
        raise PolicyError(
            f'{where}: [{section}] {key} must be a list of names or globs, e.g. ["/turtle1/*"], not {value!r}'
        )
    return tuple(item.strip() for item in value)


def _positive(table: Mapping[str, Any], key: str, section: str, where: str, unit: str) -> float | None:
    if key not in table:
        return None
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value < 0:
        place = f"[{section}] " if section else ""
        raise PolicyError(f"{where}: {place}{key} must be a number of {unit} ≥ 0, not {value!r}")
    return float(value)


def _velocity(data: Mapping[str, Any], where: str) -> VelocityCaps:
    table = _table(data, "velocity", where, _VELOCITY_KEYS)
    mode = table.get("mode", "refuse")
    if mode not in ("refuse", "clamp"):
        raise PolicyError(f"{where}: [velocity] mode must be 'refuse' or 'clamp', not {mode!r}")
    return VelocityCaps(
        max_linear=_positive(table, "max_linear", "velocity", where, "m/s"),
        max_angular=_positive(table, "max_angular", "velocity", where, "rad/s"),
        mode=mode,
    )


def _publish(data: Mapping[str, Any], where: str) -> PublishLimits:
    table = _table(data, "publish", where, _PUBLISH_KEYS)
    rate = _positive(table, "max_rate_hz", "publish", where, "Hz")
    if rate == 0:
        raise PolicyError(f"{where}: [publish] max_rate_hz must be more than 0 (use [topics] deny to forbid)")
    return PublishLimits(
        max_rate_hz=rate, max_duration=_positive(table, "max_duration", "publish", where, "seconds")
    )


def _recording(data: Mapping[str, Any], where: str) -> RecordingLimits:
    table = _table(data, "recording", where, _RECORDING_KEYS)
    enabled = table.get("enabled", True)
    if not isinstance(enabled, bool):
        raise PolicyError(f"{where}: [recording] enabled must be true or false, not {enabled!r}")
    return RecordingLimits(
        enabled=enabled,
        max_seconds=_positive(table, "max_seconds", "recording", where, "seconds"),
        max_megabytes=_positive(table, "max_megabytes", "recording", where, "megabytes"),
    )


def _navigation(data: Mapping[str, Any], where: str) -> NavigationRules:
    table = _table(data, "navigation", where, _NAVIGATION_KEYS)
    confirm = table.get("confirm", "never")
    if confirm not in ("never", "motion"):
        raise PolicyError(f"{where}: [navigation] confirm must be 'never' or 'motion', not {confirm!r}")
    radius = _positive(table, "robot_radius", "navigation", where, "metres")
    distance = _positive(table, "max_goal_distance", "navigation", where, "metres")
    return NavigationRules(
        robot_radius=radius,
        max_goal_distance=distance,
        confirm=confirm,
        allowed_zones=_zones(table, "allowed_zones", where),
        keep_out=_zones(table, "keep_out", where),
        allow_fence_writes=(
            _globs(table, "allow_fence_writes", "navigation", where) if "allow_fence_writes" in table else ()
        ),
    )


def _arm(data: Mapping[str, Any], where: str) -> ArmRules:
    try:
        return parse_arm(data, where)
    except ValueError as exc:
        raise PolicyError(str(exc)) from None


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        return None
    return float(value)


def _zones(table: Mapping[str, Any], key: str, where: str) -> tuple[Zone, ...]:
    zones = table.get(key, {})
    example = f"[navigation.{key}] lab = [[0, 0], [4, 0], [4, 3], [0, 3]]"
    if not isinstance(zones, dict):
        raise PolicyError(f"{where}: [navigation] {key} must be a table of named polygons, e.g. {example}")
    out: list[Zone] = []
    for name, corners in zones.items():
        points: list[tuple[float, float]] = []
        if isinstance(corners, list):
            for corner in corners:
                if isinstance(corner, list) and len(corner) == 2:
                    x, y = _number(corner[0]), _number(corner[1])
                    if x is not None and y is not None:
                        points.append((x, y))
                        continue
                points = []
                break
        if len(points) < 3:
            raise PolicyError(
                f"{where}: [navigation.{key}] {name} must be a polygon of at least 3 corners [x, y] in "
                f"metres, e.g. {example}; got {corners!r}"
            )
        out.append((name, tuple(points)))
    return tuple(out)


def _places(data: Mapping[str, Any], where: str) -> tuple[tuple[str, tuple[float, float, float]], ...]:
    table = data.get("places", {})
    example = "[places] dock = [1.0, 2.0, 90]  # x, y (m), yaw (degrees) in the map frame"
    if not isinstance(table, dict):
        raise PolicyError(f"{where}: places must be a table ([places]), e.g. {example}")
    out: list[tuple[str, tuple[float, float, float]]] = []
    for name, value in table.items():
        if isinstance(value, dict):
            unknown = set(value) - {"x", "y", "yaw"}
            numbers = [_number(value.get(k, 0.0)) for k in ("x", "y", "yaw")]
            ok = not unknown and "x" in value and "y" in value
        elif isinstance(value, list) and len(value) in (2, 3):
            numbers = [_number(v) for v in value] + ([0.0] if len(value) == 2 else [])
            ok = True
        else:
            numbers, ok = [], False
        if not ok or any(n is None for n in numbers):
            raise PolicyError(
                f"{where}: [places] {name} must be [x, y, yaw] or {{x, y, yaw}}, e.g. {example}"
            )
        x, y, yaw = (float(n) for n in numbers if n is not None)
        out.append((name, (x, y, yaw)))
    return tuple(out)
