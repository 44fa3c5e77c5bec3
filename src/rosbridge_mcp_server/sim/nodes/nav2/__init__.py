"""The Nav2 world: a mobile robot's graph as Nav2, ros2_control and its drivers make it (Jazzy names).

About 30 nodes (13 of them lifecycle nodes with their lifecycle services), ~70 topics, 350-400 services and
1,000+ declared parameters on ROS 2, and Nav2's action servers (``/navigate_to_pose``, ``/follow_path``,
``/spin``, ...) whose goals run a few steps and succeed; navigating moves the robot to the goal. With
``robots=N`` the same robot runs N times under ``/robot1``, ``/robot2``, ... (rosbridge, rosapi, ``/rosout``
and ``/parameter_events`` stay global).

What the robot sees comes from :class:`Surroundings`: the map on ``/map`` (latched) and the ranges on
``/scan``. The default, :class:`TurtleRoom`, is the turtle world's room (the square arena with its pillar)
as a grid and rays; a richer room plugs in by giving ``Nav2World(surroundings=...)`` (or setting
:attr:`Nav2World.surroundings` before the robot starts).

On ROS 1 the same nodes, topics and parameters are there in ROS 1 form (no lifecycle services, each node's
logger services, the actions as actionlib servers over their five topics).

* :mod:`.world`: :class:`Nav2World`, which builds the graph and runs the goals;
* :mod:`.layout`: the nodes, actions and topics of one robot; :mod:`.params`: their declared parameters;
* :mod:`.robot`: one robot's pose and command; :mod:`.motion`: the robots moving and what they publish;
* :mod:`.surroundings`: what the map and the laser see; :mod:`.lifecycle`: the lifecycle nodes' states;
* :mod:`.actionlib`: the actions in ROS 1 form.
"""

from rosbridge_mcp_server.sim.nodes.nav2.layout import LIFECYCLE_NODES, NAV2_ACTIONS, NAV2_NODES
from rosbridge_mcp_server.sim.nodes.nav2.robot import Nav2Robot
from rosbridge_mcp_server.sim.nodes.nav2.surroundings import Grid, Surroundings, TurtleRoom
from rosbridge_mcp_server.sim.nodes.nav2.world import Nav2World

__all__ = [
    "LIFECYCLE_NODES",
    "NAV2_ACTIONS",
    "NAV2_NODES",
    "Grid",
    "Nav2Robot",
    "Nav2World",
    "Surroundings",
    "TurtleRoom",
]
