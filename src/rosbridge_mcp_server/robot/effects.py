"""What an act does on the robot, whichever tool carries it: an action goal, a parameter write, a motion.

A tool names the carrier (a topic published on, a service called); the robot acts on what the carrier means.
ROS reaches the same effect several ways, and a rule written for one of them must hold for all:

* **Action goals and cancels.** ROS 1 actionlib takes goals on the ``<action>/goal`` topic (a ``…ActionGoal``
  message) and cancels on ``<action>/cancel`` (``actionlib_msgs/GoalID``); ROS 2 takes them through the hidden
  services ``<action>/_action/send_goal`` and ``…/cancel_goal`` (and hands results out through
  ``…/get_result``). ``publish_topic`` and ``publish_service`` reach them as ``publish_action`` and
  ``cancel_action`` do.
* **Parameter writes.** A ROS 2 node's ``set_parameters`` / ``set_parameters_atomically`` services (one write
  per parameter in the request), a ROS 1 node's dynamic_reconfigure ``set_parameters``
  (``dynamic_reconfigure/Reconfigure``: ``/<node>/<name>`` for each value in the config), rosapi's
  ``set_param`` and ``delete_param`` (both lines). On ROS 1 a write to a name replaces everything under it
  (a parameter is also a namespace), so such a write is marked ``subtree``.
* **Motion by topic**, besides velocity commands (which :mod:`~rosbridge_mcp_server.robot.velocity` knows
  by type): joint trajectories, jogs and Ackermann drive commands by type (:data:`MOTION_TOPIC_TYPES`), and a
  navigation goal published on ``/move_base_simple/goal`` (ROS 1 move_base) or ``/goal_pose`` (ROS 2 Nav2's
  bt_navigator) (:data:`MOTION_GOAL_TOPICS`).
* **Motion by service.** A service that moves the robot or a body of it: by type
  (:data:`MOTION_SERVICE_TYPES`: turtlesim's teleports, Gazebo's set-state services, MoveIt's
  ``ExecuteKnownTrajectory``, lifecycle transitions, Nav2's lifecycle managers, controller switches) or by
  the name's last part (:data:`MOTION_SERVICE_LEAVES`: also resets, which teleport: turtlesim's ``/reset``,
  Gazebo's ``reset_world`` and ``reset_simulation``). A policy may name more (``[services] motion``).
  A joystick message (``sensor_msgs/Joy``) is motion too: teleop turns it into velocity.
* **What the fence reads** (kind ``fence``): the robot's transforms (``/tf``, ``/tf_static``), a pose
  estimate (``/initialpose``; any ``PoseWithCovarianceStamped``), odometry, the sensors localisation and the
  collision monitor read (scans, point clouds, IMU), the map and Nav2's costmap filter masks and their info,
  the robot's footprint, the speed limit; and the services that relocalise or reload the map (AMCL's
  ``set_initial_pose`` and ``request_nomotion_update``, map_server's ``load_map``, ...). Decided by type
  (:data:`FENCE_TOPIC_TYPES`, :data:`FENCE_SERVICE_TYPES`) and by the name's last part
  (:data:`FENCE_TOPIC_LEAVES`, :data:`FENCE_SERVICE_LEAVES`), so ``/robot1/tf`` is ``/tf``'s kind. Writing
  them moves the world under the safety fence's zones (``safety/fence.py``).
* **Parameter writes by type as well as by name**: rosapi's ``SetParam`` / ``DeleteParam`` in both spellings
  (``rosapi/SetParam``, ``rosapi_msgs/srv/SetParam``) and ``rcl_interfaces`` ``SetParameters`` under any
  name meet ``[parameters]`` as ``/rosapi/set_param`` and ``<node>/set_parameters`` do.

Every name here is canonical (:mod:`rosbridge_mcp_server.robot.names`): what the robot will act on, so that a
rule written for ``/turtlesim:background_r`` holds for ``/turtlesim//:background_r`` too.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import Advice, NotSentError
from rosbridge_mcp_server.robot.motion_goals import GOAL_POSE_TOPICS
from rosbridge_mcp_server.robot.names import parameter_name

__all__ = [
    "FENCE_SERVICE_LEAVES",
    "FENCE_SERVICE_TYPES",
    "FENCE_TOPIC_LEAVES",
    "FENCE_TOPIC_TYPES",
    "MOTION_GOAL_TOPICS",
    "MOTION_SERVICE_LEAVES",
    "MOTION_SERVICE_TYPES",
    "MOTION_TOPIC_TYPES",
    "Effect",
    "parameter_write",
    "service_effects",
    "topic_effects",
]

EffectKind = Literal["action", "parameter", "motion", "fence"]


@dataclass(frozen=True)
class Effect:
    """One thing an act does on the robot besides what its carrier names."""

    kind: EffectKind
    name: str  #: canonical: the action, the parameter (ROS 2 ``/node:name``, ROS 1 ``/ns/name``), the service
    #: "goal", "cancel" or "result" (an action); "set" or "delete" (a parameter); "move" (motion); "write"
    #: (fence: what the safety fence or localisation reads)
    what: str
    #: A ROS 1 parameter write: everything under ``name`` is replaced as well.
    subtree: bool = False
    #: Why it is motion or a fence write, in words (e.g. "teleop turns it into velocity"); "" when plain.
    why: str = ""

    def describe(self) -> str:
        """E.g. ``a goal of action /fibonacci`` or ``a set of parameter /turtlesim:background_r``."""
        because = f" ({self.why})" if self.why else ""
        if self.kind == "motion":
            return f"motion of the robot through {self.name}{because}"
        if self.kind == "fence":
            return f"a change of what the safety fence and localisation read, through {self.name}{because}"
        under = " and everything under it" if self.subtree else ""
        return f"a {self.what} of {self.kind} {self.name}{under}"


#: Message types that command motion (velocity commands aside), in the short ``pkg/Type`` form.
MOTION_TOPIC_TYPES = frozenset(
    {
        "trajectory_msgs/JointTrajectory",
        "trajectory_msgs/MultiDOFJointTrajectory",
        "control_msgs/JointJog",
        "ackermann_msgs/AckermannDrive",
        "ackermann_msgs/AckermannDriveStamped",
        "sensor_msgs/Joy",
    }
)
#: Why a motion command type moves the robot, where that is not plain.
_MOTION_WHY = {"sensor_msgs/Joy": "a joystick: teleop turns it into velocity"}
#: Topics a navigation stack takes a goal pose on (the robot then drives there).
MOTION_GOAL_TOPICS = GOAL_POSE_TOPICS  # one tuple: robot/motion_goals.py reads the goals they carry

#: Service types that move the robot (or a simulated body), in the short ``pkg/Type`` form both lines share.
MOTION_SERVICE_TYPES = frozenset(
    {
        "turtlesim/TeleportAbsolute",
        "turtlesim/TeleportRelative",
        "gazebo_msgs/SetModelState",
        "gazebo_msgs/SetEntityState",
        "gazebo_msgs/SetLinkState",
        "gazebo_msgs/SetModelConfiguration",
        "gazebo_msgs/SetJointTrajectory",
        "ros_gz_interfaces/SetEntityPose",
        "moveit_msgs/ExecuteKnownTrajectory",
        "lifecycle_msgs/ChangeState",
        "nav2_msgs/ManageLifecycleNodes",
        "controller_manager_msgs/SwitchController",
    }
)
#: Why a motion service moves the robot, by type or by the name's last part, where that is not plain.
_MOTION_SERVICE_WHY = {
    "lifecycle_msgs/ChangeState": "a lifecycle transition: it can start, stop or unguard the robot's motion",
    "change_state": "a lifecycle transition: it can start, stop or unguard the robot's motion",
    "nav2_msgs/ManageLifecycleNodes": "starts, pauses or resets Nav2's nodes",
    "manage_nodes": "starts, pauses or resets Nav2's nodes",
    "controller_manager_msgs/SwitchController": "switches the robot's motion controllers",
    "switch_controller": "switches the robot's motion controllers",
    "reset": "a reset: it may put the robot back where it started",
    "reset_world": "a world reset: it puts the robot back where it started",
    "reset_simulation": "a simulation reset: it puts the robot back where it started",
}
#: The last part of a motion service's usual name, for when its type is not known.
MOTION_SERVICE_LEAVES = frozenset(
    {
        "teleport_absolute",
        "teleport_relative",
        "set_model_state",
        "set_entity_state",
        "set_link_state",
        "set_model_configuration",
        "set_entity_pose",
        "execute_kinematic_path",
        "reset",
        "reset_world",
        "reset_simulation",
        "change_state",
        "manage_nodes",
        "switch_controller",
    }
)

#: Message types whose messages change what the safety fence or localisation reads: type → what they are.
FENCE_TOPIC_TYPES = {
    "tf2_msgs/TFMessage": "the robot's transforms, which place the robot and its goals on the map",
    "geometry_msgs/PoseWithCovarianceStamped": "a pose estimate: it relocalises the robot",
    "nav_msgs/Odometry": "odometry, which localisation reads",
    "nav_msgs/OccupancyGrid": "a map or a costmap filter mask (Nav2's keep-out and speed masks)",
    "map_msgs/OccupancyGridUpdate": "an update of a map or costmap",
    "nav2_msgs/Costmap": "a costmap",
    "nav2_msgs/CostmapFilterInfo": "which mask Nav2's costmap filters read",
    "nav2_msgs/SpeedLimit": "Nav2's speed limit",
    "sensor_msgs/LaserScan": "a laser scan, which localisation, the costmaps and the collision monitor read",
    "sensor_msgs/PointCloud2": "a point cloud, which the costmaps and the collision monitor read",
    "sensor_msgs/Imu": "IMU readings, which localisation reads",
}
#: The last part of such a topic's usual name, whatever type it is sent with.
FENCE_TOPIC_LEAVES = {
    "tf": FENCE_TOPIC_TYPES["tf2_msgs/TFMessage"],
    "tf_static": FENCE_TOPIC_TYPES["tf2_msgs/TFMessage"],
    "initialpose": "the initial pose: it relocalises the robot",
    "amcl_pose": FENCE_TOPIC_TYPES["geometry_msgs/PoseWithCovarianceStamped"],
    "map": "the map",
    "map_updates": "an update of the map",
    "speed_limit": FENCE_TOPIC_TYPES["nav2_msgs/SpeedLimit"],
    "costmap_filter_info": FENCE_TOPIC_TYPES["nav2_msgs/CostmapFilterInfo"],
    "footprint": "the robot's footprint, which Nav2 keeps clear of obstacles",
}
#: A topic whose name ends so is a costmap filter mask (``/keepout_filter_mask``, ``/speed_filter_mask``).
_MASK_SUFFIX = "filter_mask"
#: Service types that relocalise the robot or replace its map: type → what they do.
FENCE_SERVICE_TYPES = {
    "nav2_msgs/SetInitialPose": "it relocalises the robot",
    "nav2_msgs/LoadMap": "it replaces the map or a costmap filter mask",
    "nav_msgs/LoadMap": "it replaces the map",
    "nav_msgs/SetMap": "it replaces the map and the pose",
    "robot_localization/SetPose": "it relocalises the robot",
    "robot_localization/SetDatum": "it moves localisation's origin",
}
#: The last part of such a service's usual name, whatever its type.
FENCE_SERVICE_LEAVES = {
    "set_initial_pose": "it relocalises the robot",
    "request_nomotion_update": "it updates localisation without motion",
    "reinitialize_global_localization": "it scatters localisation over the whole map",
    "global_localization": "it scatters localisation over the whole map",
    "load_map": "it replaces the map or a costmap filter mask",
    "change_map": "it replaces the map",
    "set_map": "it replaces the map and the pose",
    "set_pose": "it relocalises the robot",
    "set_datum": "it moves localisation's origin",
}

_ROS2_ACTION_SERVICES = {"send_goal": "goal", "cancel_goal": "cancel", "get_result": "result"}
_ROSAPI_PARAMETER_TYPES = {
    "rosapi/SetParam": "set",
    "rosapi/DeleteParam": "delete",
    "rosapi_msgs/SetParam": "set",
    "rosapi_msgs/DeleteParam": "delete",
}
#: rosapi's services by the name's last two parts: ``/rosapi/set_param``, and ``/<ns>/rosapi/set_param``
#: (ROS 2 rosapi 2.2+ names them after its node).
_ROSAPI_PARAMETER_SERVICES = {"rosapi/set_param": "set", "rosapi/delete_param": "delete"}
_ROS2_SET_PARAMETERS = ("set_parameters", "set_parameters_atomically")
_ROS2_SET_PARAMETERS_TYPES = ("rcl_interfaces/SetParameters", "rcl_interfaces/SetParametersAtomically")
_RECONFIGURE_LISTS = ("bools", "ints", "strs", "doubles")


def topic_effects(topic: str, type_name: str) -> tuple[Effect, ...]:
    """What publishing a ``type_name`` message on (the absolute) ``topic`` does besides the publish.

    ROS 1 actionlib: ``<action>/goal`` with a ``…ActionGoal`` message is a goal of ``<action>``;
    ``<action>/cancel`` with ``actionlib_msgs/GoalID`` a cancel of it. A motion command other than a velocity
    command (a joint trajectory, a joystick, a goal pose for the navigation stack, also under a namespace) is
    motion; a message the fence or localisation reads (by type or by name) a fence write.
    """
    parent, _, leaf = topic.rpartition("/")
    short = Dialect.short_type(type_name) if "/" in type_name else type_name
    if leaf == "goal" and short.endswith("ActionGoal"):
        return (Effect("action", parent or "/", "goal"),)
    if leaf == "cancel" and short == "actionlib_msgs/GoalID":
        return (Effect("action", parent or "/", "cancel"),)
    if short in MOTION_TOPIC_TYPES or topic in MOTION_GOAL_TOPICS or topic.endswith(MOTION_GOAL_TOPICS):
        return (Effect("motion", topic, "move", why=_MOTION_WHY.get(short, "")),)
    fence = FENCE_TOPIC_TYPES.get(short) or FENCE_TOPIC_LEAVES.get(leaf)
    if fence is None and leaf.endswith(_MASK_SUFFIX):
        fence = FENCE_TOPIC_TYPES["nav_msgs/OccupancyGrid"]
    if fence is not None:
        return (Effect("fence", topic, "write", why=fence),)
    return ()


def service_effects(service: str, type_name: str, request: Any, ros_version: int) -> tuple[Effect, ...]:
    """What calling (the absolute) ``service`` of ``type_name`` with ``request`` does on the robot.

    :class:`~rosbridge_mcp_server.errors.NotSentError` when a parameter service's request does not say
    plainly which parameters it writes (the policy could not judge it).
    """
    short = Dialect.short_type(type_name) if "/" in type_name else type_name
    parent, _, leaf = service.rpartition("/")
    action_parent, _, hidden = parent.rpartition("/")
    if hidden == "_action" and leaf in _ROS2_ACTION_SERVICES:
        return (Effect("action", action_parent or "/", _ROS2_ACTION_SERVICES[leaf]),)
    rosapi = _ROSAPI_PARAMETER_TYPES.get(short) or _ROSAPI_PARAMETER_SERVICES.get(f"{hidden}/{leaf}")
    if rosapi is not None:
        return (_rosapi_parameter(service, request, ros_version, rosapi),)
    if short in _ROS2_SET_PARAMETERS_TYPES or (leaf in _ROS2_SET_PARAMETERS and ros_version == 2):
        return _ros2_set_parameters(service, parent, request)
    if short == "dynamic_reconfigure/Reconfigure" or (leaf == "set_parameters" and ros_version == 1):
        return _reconfigure(service, parent, request)
    if short in MOTION_SERVICE_TYPES or leaf in MOTION_SERVICE_LEAVES:
        why = _MOTION_SERVICE_WHY.get(short) or _MOTION_SERVICE_WHY.get(leaf, "")
        return (Effect("motion", service, "move", why=why),)
    fence = FENCE_SERVICE_TYPES.get(short) or FENCE_SERVICE_LEAVES.get(leaf)
    if fence is not None:
        return (Effect("fence", service, "write", why=fence),)
    return ()


def _unreadable(service: str, what: str) -> NotSentError:
    return NotSentError(
        f"The request to {service} does not name plainly which parameters it {what}, so the safety policy "
        "could not judge it; nothing was sent."
    ).advise(Advice.ONE_PARAMETER)


def _rosapi_parameter(service: str, request: Any, ros_version: int, what: str) -> Effect:
    name = request.get("name") if isinstance(request, dict) else None
    if not isinstance(name, str):
        raise _unreadable(service, "writes")
    canonical = parameter_name(name, ros_version)
    return Effect("parameter", canonical, what, subtree=ros_version == 1)


def _ros2_set_parameters(service: str, node: str, request: Any) -> tuple[Effect, ...]:
    parameters = request.get("parameters") if isinstance(request, dict) else None
    if not isinstance(parameters, list):
        raise _unreadable(service, "sets")
    effects = []
    for parameter in parameters:
        local = parameter.get("name") if isinstance(parameter, dict) else None
        if not isinstance(local, str):
            raise _unreadable(service, "sets")
        effects.append(Effect("parameter", parameter_name(f"{node or '/'}:{local}", 2), "set"))
    return tuple(effects)


def _reconfigure(service: str, node: str, request: Any) -> tuple[Effect, ...]:
    """dynamic_reconfigure (ROS 1): ``{"config": {"bools": [{"name", "value"}], "ints": ..., ...}}``."""
    config = request.get("config") if isinstance(request, dict) else None
    if config is None:
        return ()
    if not isinstance(config, dict):
        raise _unreadable(service, "sets")
    effects = []
    for key in _RECONFIGURE_LISTS:
        entries = config.get(key) or []
        if not isinstance(entries, list):
            raise _unreadable(service, "sets")
        for entry in entries:
            local = entry.get("name") if isinstance(entry, dict) else None
            if not isinstance(local, str):
                raise _unreadable(service, "sets")
            effects.append(Effect("parameter", parameter_name(f"{node}/{local}", 1), "set", subtree=True))
    return tuple(effects)


def parameter_write(name: str, ros_version: int) -> Effect:
    """The effect of ``set_parameter`` on the canonical ``name``: on ROS 1 it replaces everything under it."""
    return Effect("parameter", name, "set", subtree=ros_version == 1)
