"""The policy's rules: each section's (:class:`NameRules`, :class:`VelocityCaps`, :class:`PublishLimits`,
:class:`NavigationRules`, :class:`RecordingLimits`; ``[arm]``'s are ``safety/arm_rules.py``'s) and the
:class:`Policy` that holds them, which says itself in lines (:meth:`Policy.describe`)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from fnmatch import fnmatchcase
from typing import Literal

from rosbridge_mcp_server.safety.arm_rules import ArmRules, describe_arm

__all__ = [
    "ACT_KINDS",
    "APPROVALS",
    "CONFIRM_MODES",
    "DEFAULT_CONFIRM_TIMEOUT",
    "Approvals",
    "Confirm",
    "NameRules",
    "NavigationConfirm",
    "NavigationRules",
    "Policy",
    "PolicyError",
    "PublishLimits",
    "RecordingLimits",
    "VelocityCaps",
    "VelocityMode",
    "Zone",
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
        lines += self._asking_lines()
        for section in ACT_KINDS:
            rules: NameRules = getattr(self, section)
            if not rules.is_open:
                allowed = "everything" if rules.allow is None else ", ".join(rules.allow) or "nothing"
                denied = f"; deny {', '.join(rules.deny)}" if rules.deny else ""
                lines.append(f"  [{section}] allow {allowed}{denied}")
        said = (
            _velocity_line(self.velocity),
            _publish_line(self.publish),
            _recording_line(self.recording),
            _navigation_line(self.navigation),
            f"  [places] {', '.join(name for name, _ in self.places)}" if self.places else None,
            describe_arm(self.arm) if self.arm != ArmRules() else None,
        )
        return lines + [line for line in said if line is not None]

    def _asking_lines(self) -> list[str]:
        """Who is asked, and what the policy counts as motion besides the known commands."""
        asked = f" (no answer within {self.confirm_timeout:g} s is a no)" if self.confirm != "never" else ""
        said = _CONFIRM_TEXT[self.confirm]
        if self.confirm == "never" and self.navigation.confirm != "never":
            said = "nobody is asked, except for the motion goals [navigation] confirms (below)"
        lines = [f"  confirm = {self.confirm}: {said}{asked}"]
        if self.approvals == "console":
            lines.append("  approvals = console: only the person at the operator console confirms")
        if self.motion_topics:
            lines.append(f"  [topics] motion: {', '.join(self.motion_topics)} (besides the known ones)")
        if self.motion_services:
            lines.append(f"  [services] motion: {', '.join(self.motion_services)} (besides the known ones)")
        return lines


def _velocity_line(caps: VelocityCaps) -> str | None:
    parts = []
    if caps.max_linear is not None:
        parts.append(f"linear ≤ {caps.max_linear:g} m/s")
    if caps.max_angular is not None:
        parts.append(f"angular ≤ {caps.max_angular:g} rad/s")
    if not parts:
        return None
    return f"  [velocity] {', '.join(parts)} on every Twist/TwistStamped ({caps.mode} above)"


def _publish_line(limits: PublishLimits) -> str | None:
    parts = []
    if limits.max_rate_hz is not None:
        parts.append(f"rate ≤ {limits.max_rate_hz:g} Hz")
    if limits.max_duration is not None:
        parts.append(f"duration ≤ {limits.max_duration:g} s")
    return f"  [publish] streams: {', '.join(parts)}" if parts else None


def _recording_line(rec: RecordingLimits) -> str | None:
    if rec == RecordingLimits():
        return None
    if not rec.enabled:
        return "  [recording] record refuses"
    parts = []
    if rec.max_seconds is not None:
        parts.append(f"≤ {rec.max_seconds:g} s")
    if rec.max_megabytes is not None:
        parts.append(f"≤ {rec.max_megabytes:g} MB")
    return f"  [recording] {', '.join(parts)}"


def _navigation_line(nav: NavigationRules) -> str | None:
    if nav == NavigationRules():
        return None
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
    return f"  [navigation] {'; '.join(parts)}"


_CONFIRM_TEXT: dict[Confirm, str] = {
    "never": "nobody is asked",
    "motion": (
        "the person confirms every velocity command, action goal (also one sent through its topic or "
        "service) and service that moves the robot"
    ),
    "always": "the person confirms every acting call (topics, services, goals, parameters)",
}
