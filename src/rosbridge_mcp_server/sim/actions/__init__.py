"""Action servers of the simulated robot: ROS 2 servers (``/fibonacci`` and those clients host through
rosbridge) and ROS 1's actionlib ``/fibonacci``. They reach the bridge only through :class:`ActionHost`."""

from rosbridge_mcp_server.sim.actions.common import FIBONACCI_NODE, ROS1_STATUS, ROS2_STATUS, ActionHost
from rosbridge_mcp_server.sim.actions.ros1 import ActionlibFibonacciServer
from rosbridge_mcp_server.sim.actions.ros2 import (
    ActionServer,
    FibonacciServer,
    GoalHandle,
    HostedActionServer,
)

__all__ = [
    "FIBONACCI_NODE",
    "ROS1_STATUS",
    "ROS2_STATUS",
    "ActionHost",
    "ActionServer",
    "ActionlibFibonacciServer",
    "FibonacciServer",
    "GoalHandle",
    "HostedActionServer",
]
