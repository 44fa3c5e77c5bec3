"""What a read-only server or robot refuses before a tool runs: each refusal worded, and audited when the tool
acts on the robot.

* A read-only server (``--read-only``, a policy's ``read_only = true``, or every robot of a fleet read-only)
  does not list its acting tools; one called by name anyway is refused (:meth:`ReadOnlyRefusals.unlisted`).
* On a fleet, a tool that is not read-only called on a read-only robot is refused
  (:meth:`ReadOnlyRefusals.robot_check`); the stop (a spec's ``stops``) is allowed everywhere.

Either way nothing reaches the robot, and the robot's guard records the act it would have been, as the kind
its spec says it acts on (``acts_on``); a tool that sends nothing to the robot (``changes``) has no act to
audit. What a tool is comes from its spec, never from its name.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.robot.approval import Act, ActKind

if TYPE_CHECKING:
    from rosbridge_mcp_server.server.adapter import EdgeTool
    from rosbridge_mcp_server.server.fleet import Fleet, Robot
    from rosbridge_mcp_server.tools.base import ToolSpec

__all__ = ["ReadOnlyRefusals"]


class ReadOnlyRefusals:
    """The refusals of one server: *withheld* are the acting tools it does not list (read-only), *stops* the
    names of the tools that stop a robot."""

    def __init__(self, fleet: Fleet, withheld: Sequence[ToolSpec], stops: Sequence[str]) -> None:
        self._fleet = fleet
        self._withheld = {spec.name: spec for spec in withheld}
        self._stops = list(stops)

    def unlisted(self, name: str, arguments: dict[str, Any], caller: str | None) -> str | None:
        """A withheld acting tool called by name anyway: refused, and audited like any refusal."""
        spec = self._withheld.get(name)
        if spec is None:
            return None
        if spec.acts_on is not None:
            for robot in self._fleet.robots:
                robot.session.guard.record(
                    _withheld_act(spec.name, spec.acts_on, arguments, caller), "withheld: read-only"
                )
        return (
            f"{name} is not available: this server is read-only (its operator started it with --read-only or "
            "a policy with read_only = true), so nothing was sent. Only the tools in tools/list can be used."
        )

    def robot_check(
        self, tool: EdgeTool, chosen: tuple[Robot, ...], arguments: dict[str, Any], caller: str | None
    ) -> str | None:
        """A tool that is not read-only on a read-only robot of the fleet: refused, and audited on that robot
        when it acts on it. Stopping is allowed everywhere."""
        spec = tool.spec
        if tool.reads or spec is None or spec.stops:
            return None
        refusal = self._fleet.read_only_refusal(tool.name, chosen, self._stops)
        if refusal is not None and spec.acts_on is not None:
            for robot in chosen:
                if robot.config.policy.read_only:
                    robot.session.guard.record(
                        _withheld_act(tool.name, spec.acts_on, arguments, caller), "withheld: read-only"
                    )
        return refusal


def _withheld_act(name: str, acts_on: ActKind, arguments: dict[str, Any], caller: str | None) -> Act:
    """The audit's act for an acting tool refused before it ran: what it acts through, and its arguments."""
    return Act(name, acts_on, "", "", arguments, caller=caller)
