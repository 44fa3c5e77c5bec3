"""What is wrong with the robot: diagnostics, logs, streams, tf, lifecycle and the graph, looked at at once.

:func:`diagnose` asks rosapi for the topics, nodes and services, then listens to the streams that matter,
``/tf`` and ``/tf_static`` and ``/diagnostics`` side by side for :data:`WINDOW` seconds while it asks every
lifecycle node its state and the graph who publishes and reads the key topics; the log and the diagnostics
since the server connected come from the session's :class:`~rosbridge_mcp_server.robot.log_keeper.LogKeeper`.
Each area becomes :class:`Finding`\\ s (a problem or a warning, what it is about, and what to call next) and a
line of what was checked; an area the robot does not have (no ``/rosout``, no ``/diagnostics``, no lifecycle
services, ROS 1's missing lifecycle) says so and the others are reported.

The areas:

* ``diagnostics``: the latest status per name and hardware id: ERROR is a problem, WARN and STALE warnings;
* ``logs``: errors (problems) and warnings since the server connected, folded;
* ``streams``: the sensors, odometry, joint states, camera (its ``camera_info`` when it has one, else the
  image, compressed when offered) and ``/tf``: a topic a node publishes that sends nothing in the window is a
  problem; a rate under half the one this session measured before a warning;
* ``tf``: dynamic transforms stamped over a second before the newest one, a frame with two parents, no path
  along map → odom → base (``base_footprint`` or ``base_link``), for the root's ``/tf`` and for each robot's
  namespace with its own (``/robot2/tf``, ``robot/namespaces.py``), each tree on its own;
* ``lifecycle`` (ROS 2): every node offering ``get_state`` that is not active is a problem;
* ``graph``: nodes gone since the last look (the first look is when the server connected), a ``cmd_vel``
  nobody reads (nothing drives), a key stream a node reads that nobody publishes;
* ``arm`` (where ros2_control's ``…/list_controllers`` is served): a controller not active is a problem, a
  joint at a limit of the URDF (``/robot_description``, fingers left out) a warning (``robot/arm/health.py``);
  a silent ``/joint_states`` is the streams area's.

The package, one module per part: ``findings.py`` (what a diagnosis says: areas, focuses, findings, next
steps, and which steps' names may go into a call), ``look.py`` (:func:`diagnose`: what to listen to, the look,
each area's judgement), ``streams.py`` (the key streams, listening to them, the streams area), ``graph.py``
(the graph and lifecycle areas), ``reports.py`` (what the robot reports: diagnostics and logs), ``tf.py`` and
``arm.py`` (their areas).
"""

from __future__ import annotations

from rosbridge_mcp_server.robot.diagnosis.findings import (
    AREAS,
    FOCUSES,
    WINDOW,
    Diagnosis,
    Finding,
    Look,
    Step,
    UnknownFocusError,
    areas_for,
)
from rosbridge_mcp_server.robot.diagnosis.look import diagnose
from rosbridge_mcp_server.robot.diagnosis.streams import MAX_STREAMS

__all__ = [
    "AREAS",
    "FOCUSES",
    "MAX_STREAMS",
    "WINDOW",
    "Diagnosis",
    "Finding",
    "Look",
    "Step",
    "UnknownFocusError",
    "areas_for",
    "diagnose",
]
