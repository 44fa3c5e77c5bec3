"""The safety policy: what the model may do to the robot, read once from a TOML file at start.

Every key is optional; an empty file (or no file) allows everything, as the server did without a policy. A key
the loader does not know is a start-up error naming it (a misspelt ``max_linaer`` must not silently leave the
robot uncapped). The file::

    read_only = false            # true: only reading tools are listed or callable
    confirm = "never"            # "never" | "motion" | "always": ask the person before acting
    confirm_timeout = 120        # seconds the person has to answer; no answer is a "no"
    approvals = "client"         # or "console": only the operator console's person confirms
    [topics]                     # publishing; also [services], [actions], [parameters]
    allow = ["/turtle1/*"]       # absent = everything; shell-style globs, * crosses /
    deny = ["/rosout"]           # deny wins over allow
    [services]                   # [topics] too
    motion = ["/arm/move_to"]    # what moves the robot (confirm = "motion" asks), besides the known ones
    [velocity]                   # every geometry_msgs Twist / TwistStamped, on any topic
    max_linear = 0.5             # m/s, length of the linear vector
    max_angular = 1.0            # rad/s, length of the angular vector
    mode = "refuse"              # or "clamp": scale down to the cap
    [publish]                    # publish_topic rate streams
    max_rate_hz = 20
    max_duration = 30            # seconds
    [recording]                  # record: MCAP files in the recording directory
    enabled = true               # false: record refuses
    max_seconds = 600            # longest recording
    max_megabytes = 2000         # largest file
    [navigation]                 # every motion goal (Nav2, move_base) by any carrier (robot/motion_goals.py)
    robot_radius = 0.25          # m: the robot's footprint, clear on the map and of the zones (default 0.2)
    max_goal_distance = 15       # m from the robot, straight line
    confirm = "motion"           # "never" | "motion": ask the person before each motion goal
    allow_fence_writes = ["/initialpose"]  # what the fence reads that may still be written (default: none)
    [navigation.allowed_zones]   # polygons in the map frame, corners [x, y] in metres
    lab = [[0, 0], [10, 0], [10, 10], [0, 10]]
    [navigation.keep_out]
    stairs = [[8, 8], [9, 8], [9, 9], [8, 9]]
    [places]                     # named places for navigate_to: [x, y, yaw in degrees] in the map frame
    dock = [1.0, 1.0, 90]
    [arm]                        # every arm motion by any carrier: safety/arm_rules.py has the keys
    speed_scale = 0.25           # share of the URDF joint speeds (default 0.25)
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

from rosbridge_mcp_server.safety.arm_rules import ArmRules, describe_arm, parse_arm

__all__ = [
    "ACT_KINDS",
    "APPROVALS",
    "CONFIRM_MODES",
    "DEFAULT_CONFIRM_TIMEOUT",
    "NameRules",
    "NavigationRules",
    "Policy",
    "PolicyError",
    "PublishLimits",
    "RecordingLimits",
    "VelocityCaps",
    "load_policy",
    "parse_policy",
]

Confirm = Literal["never", "motion", "always"]
CONFIRM_MODES: tuple[Confirm, ...] = ("never", "motion", "always")
#: Who may answer a confirmation: the MCP client's person (elicitation; the console when the client cannot
#: ask), or the operator console's person only (a token holder's own client cannot approve its own acts).
Approvals = Literal["client", "console"]
APPROVALS: tuple[Approvals, ...] = ("client", "console")
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

    def refusal(self, name: str, section: str, *, subtree: bool = False) -> str | None:
        """Why ``name`` is refused (the rule, in words), or ``None`` when it is allowed.

        With ``subtree`` (a ROS 1 parameter write, which replaces everything under the name) a deny glob
        that may match a name under ``name`` refuses it too: ``deny = ["/turtlesim/background_r"]`` refuses
        a write to ``/turtlesim``.
        """
        for pattern in self.deny:
            # Case-sensitive like ROS names; fnmatch's * also crosses "/", as in rosbridge's own
            # topics_glob / services_glob.
            if fnmatchcase(name, pattern):
                return f"[{section}] deny {pattern!r} matches {name}"
            if subtree and _may_match_under(name, pattern):
                return f"[{section}] deny {pattern!r} matches names under {name}, which a write replaces"
        if self.allow is not None and not any(fnmatchcase(name, pattern) for pattern in self.allow):
            listed = ", ".join(repr(p) for p in self.allow) or "nothing"
            return f"[{section}] allow lists only {listed}; {name} matches none of them"
        return None

    @property
    def is_open(self) -> bool:
        return self.allow is None and not self.deny


def _may_match_under(name: str, pattern: str) -> bool:
    """Whether ``pattern`` may match some name below ``name`` (``name/...``); errs towards yes."""
    below = name.rstrip("/") + "/"
    cut = min((i for i, ch in enumerate(pattern) if ch in "*?["), default=len(pattern))
    literal = pattern[:cut]
    if cut == len(pattern):
        return literal.startswith(below)
    # A glob: its fixed start must agree with "name/" as far as both go (* crosses "/").
    return literal.startswith(below) or below.startswith(literal)


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
    """``[navigation]``: where motion goals may take the robot's footprint (whatever tool or carrier sends
    them); with zones or a distance set, a goal the fence cannot place is refused."""

    robot_radius: float | None = None
    max_goal_distance: float | None = None
    confirm: NavigationConfirm = "never"
    allowed_zones: tuple[Zone, ...] = ()
    keep_out: tuple[Zone, ...] = ()
    #: Globs of topics and services that change what the fence reads (``/tf``, ``/initialpose``, the map,
    #: ...) and may still be written while zones or limits are set; by default none may.
    allow_fence_writes: tuple[str, ...] = ()

    @property
    def configured(self) -> bool:
        """Whether anything restricts goals beyond the map check every goal gets."""
        return bool(self.max_goal_distance is not None or self.allowed_zones or self.keep_out)


@dataclass(frozen=True)
class RecordingLimits:
    """What ``record`` may do: whether it may record at all, and how long and how large at most."""

    enabled: bool = True
    max_seconds: float | None = None
    max_megabytes: float | None = None


@dataclass(frozen=True)
class Policy:
    """The policy in force. ``Policy()`` allows everything and asks no one."""

    read_only: bool = False
    confirm: Confirm = "never"
    confirm_timeout: float = DEFAULT_CONFIRM_TIMEOUT
    approvals: Approvals = "client"
    #: Services that move the robot, besides the known motion services (``[services] motion``).
    motion_services: tuple[str, ...] = ()
    #: Topics whose messages move the robot, besides velocity commands and known ones (``[topics] motion``).
    motion_topics: tuple[str, ...] = ()
    topics: NameRules = field(default_factory=NameRules)
    services: NameRules = field(default_factory=NameRules)
    actions: NameRules = field(default_factory=NameRules)
    parameters: NameRules = field(default_factory=NameRules)
    velocity: VelocityCaps = field(default_factory=VelocityCaps)
    publish: PublishLimits = field(default_factory=PublishLimits)
    recording: RecordingLimits = field(default_factory=RecordingLimits)
    navigation: NavigationRules = field(default_factory=NavigationRules)
    #: Named places for navigate_to: name → (x m, y m, yaw degrees) in the map frame.
    places: tuple[tuple[str, tuple[float, float, float]], ...] = ()
    #: ``[arm]``: speeds, workspace and keep-out boxes for every arm motion (``safety/arm.py``).
    arm: ArmRules = field(default_factory=ArmRules)
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
        said = _CONFIRM_TEXT[self.confirm]
        if self.confirm == "never" and self.navigation.confirm != "never":
            said = "nobody is asked, except for the motion goals [navigation] confirms (below)"
        lines.append(f"  confirm = {self.confirm}: {said}{asked}")
        if self.approvals == "console":
            lines.append("  approvals = console: only the person at the operator console confirms")
        if self.motion_topics:
            lines.append(f"  [topics] motion: {', '.join(self.motion_topics)} (besides the known ones)")
        if self.motion_services:
            lines.append(f"  [services] motion: {', '.join(self.motion_services)} (besides the known ones)")
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
        rec = self.recording
        if rec != RecordingLimits():
            if not rec.enabled:
                lines.append("  [recording] record refuses")
            else:
                parts = []
                if rec.max_seconds is not None:
                    parts.append(f"≤ {rec.max_seconds:g} s")
                if rec.max_megabytes is not None:
                    parts.append(f"≤ {rec.max_megabytes:g} MB")
                lines.append(f"  [recording] {', '.join(parts)}")
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
                parts.append(f"a footprint of radius {nav.robot_radius:g} m")
            if nav.confirm != "never":
                parts.append("the person confirms each goal")
            if nav.configured:
                fence = ", ".join(nav.allow_fence_writes) or "none"
                parts.append(f"writes to what the fence reads (/tf, /initialpose, /map, ...): only {fence}")
            lines.append(f"  [navigation] {'; '.join(parts)}")
        if self.places:
            lines.append(f"  [places] {', '.join(name for name, _ in self.places)}")
        if self.arm != ArmRules():
            lines.append(describe_arm(self.arm))
        return lines


_CONFIRM_TEXT: dict[Confirm, str] = {
    "never": "nobody is asked",
    "motion": (
        "the person confirms every velocity command, action goal (also one sent through its topic or "
        "service) and service that moves the robot"
    ),
    "always": "the person confirms every acting call (topics, services, goals, parameters)",
}

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
