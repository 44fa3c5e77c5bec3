"""The simulated robot: a rosbridge v2 server with a small world behind it, needing no ROS.

``SimulatedRobot`` serves it in-process (tests, ``--demo``); ``python -m rosbridge_mcp_server.sim`` or the
``rosbridge-sim-robot`` command serves it standalone. See ``docs/simulated-robot.md``.
"""

from __future__ import annotations

from rosbridge_mcp_server.sim.robot import SimulatedRobot
from rosbridge_mcp_server.sim.world import GoalRecord, PublishedMessage, Turtle, World

__all__ = ["GoalRecord", "PublishedMessage", "SimulatedRobot", "Turtle", "World"]
