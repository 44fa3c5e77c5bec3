"""One robot as this server drives it: the one owner of everything that lasts as long as the server does.

A :class:`RobotSession` is made once per robot, beside its client, and lives across reconnects (unlike the
client's ``BridgeSession``, which is one connection). It holds:

* ``client``: the rosbridge client (started and closed by whoever serves, not here);
* ``graph``: what was learnt about the robot's graph (:class:`RosGraph`, per connection inside);
* ``goals``: the goals sent through the client (:class:`GoalRegistry`: running ones, and those a publish or
  a service call started; those a drop cut off are the client's, cancelled once the connection is back);
* ``activity``: what this server set going (velocity topics, streams), which ``stop_robot`` and the operator
  console's E-STOP stop, and the closing zeros a drop kept from the robot (sent once the connection is back:
  ``robot/owed_zeros.py``);
* ``guard``: the safety seam's guard every act asks first, and that records every outcome;
* ``gate``: the send gate every frame of an act passes at the moment it is sent (the latch, stops since the
  call began, the per-topic rate; see :mod:`~rosbridge_mcp_server.robot.gate`);
* ``warm_up``: the background learning of service types after every (re)connect, when asked for
  (:meth:`learn_service_types`; only a server that offers ``list_services`` needs it);
* ``logs``: the robot's log since the server connected, and the graph as first seen, when asked for
  (:meth:`keep_logs`; only a server that offers ``read_logs`` or ``diagnose`` needs it).

The tools reach it through their context, ``safety.emergency_stop`` and the operator console through it:
nothing of a robot session hangs off a module.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rosbridge_mcp_server.robot.activity import SessionActivity
from rosbridge_mcp_server.robot.gate import SendGate
from rosbridge_mcp_server.robot.goals import GoalRegistry
from rosbridge_mcp_server.robot.graph import RosGraph
from rosbridge_mcp_server.robot.log_keeper import LogKeeper
from rosbridge_mcp_server.robot.owed_zeros import OwedZeros
from rosbridge_mcp_server.robot.recording import RunningRecordings
from rosbridge_mcp_server.robot.warm_up import ServiceTypeWarmUp

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.approval import Guard

__all__ = ["RobotSession"]


class RobotSession:
    """The client, graph, goals, activity, guard and warm-up of one robot (see the module docstring)."""

    def __init__(self, client: RosbridgeClient, guard: Guard) -> None:
        self.client = client
        self.guard = guard
        self.graph = RosGraph(client)
        self.goals = GoalRegistry(client)
        self.activity = SessionActivity()
        client.watch(OwedZeros(client, self.activity))  # the closing zeros a drop kept from the robot
        self.gate = SendGate(guard)
        #: The recordings ``record`` is making on this robot now (a later ``record`` call can stop them).
        self.recordings = RunningRecordings()
        self.warm_up: ServiceTypeWarmUp | None = None
        self.logs: LogKeeper | None = None

    def learn_service_types(self) -> ServiceTypeWarmUp:
        """Learn the service types in the background after every (re)connect, from now on (once)."""
        if self.warm_up is None:
            self.warm_up = ServiceTypeWarmUp(self.client, self.graph)
            self.client.watch(self.warm_up)
        return self.warm_up

    def keep_logs(self) -> LogKeeper:
        """Keep the robot's log (and the graph as first seen) from every (re)connect on, in the background
        (once; call it before the client starts to miss nothing of the first connection)."""
        if self.logs is None:
            self.logs = LogKeeper(self.client, self.graph)
            self.client.watch(self.logs)
            facts = self.client.session_facts
            if facts is not None:
                self.logs.session_started(facts)
        return self.logs

    def __repr__(self) -> str:
        return f"RobotSession({self.client.url!r})"
