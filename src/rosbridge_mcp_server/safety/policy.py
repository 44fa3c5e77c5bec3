"""The safety policy: what the model may do to the robot, read once from a TOML file at start.

Every key is optional; an empty file (or no file) allows everything, as the server did without a policy. A key
the loader does not know is a start-up error naming it (a misspelt ``max_linaer`` must not silently leave the
robot uncapped). The file::

    read_only = false            # true: only reading tools are listed or callable
    confirm = "never"            # "never" | "motion" | "always": ask the person before acting
    confirm_timeout = 120        # seconds the person has to answer; no answer is a "no"
    [topics]                     # publishing; also [services], [actions], [parameters]
    allow = ["/turtle1/*"]       # absent = everything; shell-style globs, * crosses /
    deny = ["/rosout"]           # deny wins over allow
    [velocity]                   # every geometry_msgs Twist / TwistStamped, on any topic
    max_linear = 0.5             # m/s, length of the linear vector
    max_angular = 1.0            # rad/s, length of the angular vector
    mode = "refuse"              # or "clamp": scale down to the cap
    [publish]                    # publish_topic rate streams
    max_rate_hz = 20
    max_duration = 30            # seconds
    [navigation]                 # every navigation goal (navigate_to, or publish_action on Nav2 / move_base)
    robot_radius = 0.25          # m kept free around a goal on the map (default 0.2)
    max_goal_distance = 15       # m from the robot, straight line
    confirm = "motion"           # "never" | "motion": ask the person before each navigation goal
    [navigation.allowed_zones]   # polygons in the map frame, corners [x, y] in metres
    lab = [[0, 0], [10, 0], [10, 10], [0, 10]]
    [navigation.keep_out]
    stairs = [[8, 8], [9, 8], [9, 9], [8, 9]]
    [places]                     # named places for navigate_to: [x, y, yaw in degrees] in the map frame
    dock = [1.0, 1.0, 90]
"""

from __future__ import annotations

import difflib
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from fnmatch import fnmatchcase
from pathlib import Path
from typing import Any, Literal

__all__ = [
    "ACT_KINDS",
    "CONFIRM_MODES",
    "DEFAULT_CONFIRM_TIMEOUT",
    "NameRules",
    "NavigationRules",
    "Policy",
    "PolicyError",
    "PublishLimits",
    "VelocityCaps",
    "load_policy",
    "parse_policy",
]

Confirm = Literal["never", "motion", "always"]
CONFIRM_MODES: tuple[Confirm, ...] = ("never", "motion", "always")
VelocityMode = Literal["refuse", "clamp"]
#: How long the person has to answer a confirmation. An answer much later would send a command the situation
#: may no longer call for, so silence counts as a no.
DEFAULT_CONFIRM_TIMEOUT = 120.0
#: The policy sections with allow/deny lists, one per kind of act.
ACT_KINDS = ("topics", "services", "actions", "parameters")


class PolicyError(ValueError):
    """The policy file is missing, is not TOML, or holds a key or value it must not; ``str()`` says which.

    The configuration turns it into its own error, so a bad policy stops the start like a bad port.
    """


@dataclass(frozen=True)
class NameRules:
    """Allow/deny globs for one kind of name. ``allow is None`` means every name not denied."""

    allow: tuple[str, ...] | None = None
    deny: tuple[str, ...] = ()

    def refusal(self, name: str, section: str) -> str | None:
        """Why ``name`` is refused (the rule, in words), or ``None`` when it is allowed."""
        for pattern in self.deny:
            # Case-sensitive like ROS names; fnmatch's * also crosses "/", as in rosbridge's own
            # topics_glob / services_glob.
            if fnmatchcase(name, pattern):
                return f"[{section}] deny {pattern!r} matches {name}"
        if self.allow is not None and not any(fnmatchcase(name, pattern) for pattern in self.allow):
            listed = ", ".join(repr(p) for p in self.allow) or "nothing"
            return f"[{section}] allow lists only {listed}; {name} matches none of them"
        return None

    @property
    def is_open(self) -> bool:
        return self.allow is None and not self.deny


@dataclass(frozen=True)
class VelocityCaps:
    """Caps on every Twist / TwistStamped published, whatever the topic."""

    max_linear: float | None = None
    max_angular: float | None = None
    mode: VelocityMode = "refuse"


@dataclass(frozen=True)
class PublishLimits:
    """Limits on publish_topic rate streams."""

    max_rate_hz: float | None = None
    max_duration: float | None = None


#: A zone of the geofence: its name and corners (x, y) in the map frame, metres.
Zone = tuple[str, tuple[tuple[float, float], ...]]
NavigationConfirm = Literal["never", "motion"]


@dataclass(frozen=True)
class NavigationRules:
    """``[navigation]``: where navigation goals may go (whatever tool sends them)."""

    robot_radius: float | None = None
    max_goal_distance: float | None = None
    confirm: NavigationConfirm = "never"
    allowed_zones: tuple[Zone, ...] = ()
    keep_out: tuple[Zone, ...] = ()

    @property
    def configured(self) -> bool:
        """Whether anything restricts goals beyond the map check every goal gets."""
        return bool(self.max_goal_distance is not None or self.allowed_zones or self.keep_out)


@dataclass(frozen=True)
class Policy:
    """The policy in force. ``Policy()`` allows everything and asks no one."""

    read_only: bool = False
    confirm: Confirm = "never"
    confirm_timeout: float = DEFAULT_CONFIRM_TIMEOUT
    topics: NameRules = field(default_factory=NameRules)
    services: NameRules = field(default_factory=NameRules)
    actions: NameRules = field(default_factory=NameRules)
    parameters: NameRules = field(default_factory=NameRules)
    velocity: VelocityCaps = field(default_factory=VelocityCaps)
    publish: PublishLimits = field(default_factory=PublishLimits)
    navigation: NavigationRules = field(default_factory=NavigationRules)
    #: Named places for navigate_to: name → (x m, y m, yaw degrees) in the map frame.
    places: tuple[tuple[str, tuple[float, float, float]], ...] = ()
    source: str | None = None

    def rules_for(self, kind: str) -> tuple[str, NameRules]:
        """The section name and the allow/deny rules for an act of ``kind`` (topic, service, ...)."""
        section = f"{kind}s"
        rules: NameRules = getattr(self, section)
        return section, rules

    @property
    def restricts(self) -> bool:
        """Whether this policy changes anything compared with no policy at all."""
        return self != Policy(source=self.source)

    def with_read_only(self) -> Policy:
        return replace(self, read_only=True)

    def describe(self) -> list[str]:
        """The policy as lines for ``check`` and the start-up log."""
        origin = f" (from {self.source})" if self.source else ""
        if not self.restricts:
            return [f"no restrictions{origin}: every acting tool may act, nobody is asked"]
        lines = [f"policy{origin}:"]
        if self.read_only:
            lines.append("  read_only: only reading tools are listed or callable")
            return lines
        asked = f" (no answer within {self.confirm_timeout:g} s is a no)" if self.confirm != "never" else ""
        lines.append(f"  confirm = {self.confirm}: {_CONFIRM_TEXT[self.confirm]}{asked}")
        for section in ACT_KINDS:
            rules: NameRules = getattr(self, section)
            if rules.is_open:
                continue
            allowed = "everything" if rules.allow is None else ", ".join(rules.allow) or "nothing"
            denied = f"; deny {', '.join(rules.deny)}" if rules.deny else ""
            lines.append(f"  [{section}] allow {allowed}{denied}")
        caps = self.velocity
        if caps.max_linear is not None or caps.max_angular is not None:
            parts = []
            if caps.max_linear is not None:
                parts.append(f"linear ≤ {caps.max_linear:g} m/s")
            if caps.max_angular is not None:
                parts.append(f"angular ≤ {caps.max_angular:g} rad/s")
            lines.append(f"  [velocity] {', '.join(parts)} on every Twist/TwistStamped ({caps.mode} above)")
        limits = self.publish
        if limits.max_rate_hz is not None or limits.max_duration is not None:
            parts = []
            if limits.max_rate_hz is not None:
                parts.append(f"rate ≤ {limits.max_rate_hz:g} Hz")
            if limits.max_duration is not None:
                parts.append(f"duration ≤ {limits.max_duration:g} s")
            lines.append(f"  [publish] streams: {', '.join(parts)}")
        nav = self.navigation
        if nav != NavigationRules():
            parts = []
            if nav.allowed_zones:
                parts.append(f"goals inside {', '.join(name for name, _ in nav.allowed_zones)}")
            if nav.keep_out:
                parts.append(f"none in {', '.join(name for name, _ in nav.keep_out)}")
            if nav.max_goal_distance is not None:
                parts.append(f"at most {nav.max_goal_distance:g} m away")
            if nav.robot_radius is not None:
                parts.append(f"{nav.robot_radius:g} m clear on the map")
            if nav.confirm != "never":
                parts.append("the person confirms each goal")
            lines.append(f"  [navigation] {'; '.join(parts)}")
        if self.places:
            lines.append(f"  [places] {', '.join(name for name, _ in self.places)}")
        return lines


_CONFIRM_TEXT: dict[Confirm, str] = {
    "never": "nobody is asked",
    "motion": "the person confirms every velocity command and action goal",
    "always": "the person confirms every acting call",
}

_TOP_KEYS = (
    "read_only",
    "confirm",
    "confirm_timeout",
    *ACT_KINDS,
    "velocity",
    "publish",
    "navigation",
    "places",
)
_RULE_KEYS = ("allow", "deny")
_VELOCITY_KEYS = ("max_linear", "max_angular", "mode")
_PUBLISH_KEYS = ("max_rate_hz", "max_duration")
_NAVIGATION_KEYS = ("robot_radius", "max_goal_distance", "confirm", "allowed_zones", "keep_out")


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
    rules = {section: _name_rules(data, section, where) for section in ACT_KINDS}
    return Policy(
        read_only=read_only,
        confirm=confirm_text,
        confirm_timeout=DEFAULT_CONFIRM_TIMEOUT if timeout is None else timeout,
        topics=rules["topics"],
        services=rules["services"],
        actions=rules["actions"],
        parameters=rules["parameters"],
        velocity=_velocity(data, where),
        publish=_publish(data, where),
        navigation=_navigation(data, where),
        places=_places(data, where),
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
    table = _table(data, section, where, _RULE_KEYS)
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
    )


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
