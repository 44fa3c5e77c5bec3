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

The package: ``rules.py`` (each section's rules and the :class:`Policy` holding them, in words for ``check``
and the start-up log) and ``reading.py`` (the file read and checked).
"""

from __future__ import annotations

from rosbridge_mcp_server.safety.policy.reading import load_policy, parse_policy
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
)

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
