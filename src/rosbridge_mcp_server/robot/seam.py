"""The safety seam: what an act on the robot is, who approves it, and the person who may be asked.

``robot/acting.py`` builds an :class:`Act` for every checked send and asks the :class:`Guard` before anything
is sent: ``await guard.approve(act, ask_person)``. The guard may return a clamped copy of the act (what is
then sent) or raise :class:`~rosbridge_mcp_server.errors.PolicyRefusal`; either way it is told the outcome
(``guard.record``), once per act. ``safety/`` implements the guard; nothing here knows a policy or MCP.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, Protocol

from rosbridge_mcp_server.errors import PolicyRefusal

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.activity import SessionActivity
    from rosbridge_mcp_server.robot.goals import GoalRegistry
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = [
    "ALLOW_ALL",
    "Act",
    "Acting",
    "Answer",
    "AskPerson",
    "Guard",
    "Timeouts",
    "approved",
    "carry_out",
    "nobody_to_ask",
]


@dataclass(frozen=True)
class Act:
    """One act on the robot, as it will be sent: checked, normalised, with an absolute name."""

    tool: str  #: the tool that asks, e.g. "publish_topic"
    kind: Literal["topic", "service", "action", "parameter"]
    name: str  #: absolute ROS name (topic/service/action/parameter)
    type: str  #: ROS type as sent to the bridge ("" when none, e.g. a parameter)
    payload: Any  #: message / request / goal / value that will be sent
    rate_hz: float | None = None  #: publish streams only
    duration: float | None = None  #: publish streams only
    #: What the act is judged against beyond itself: for a navigation goal, the robot's map, its pose and the
    #: goal placed on it (a ``robot.navigation.Scene``), learnt just before the act was built; else None.
    scene: Any = None


Answer = Literal["accept", "decline", "cancel", "unsupported"]
#: Asks the person at the MCP client a yes/no question (the server's elicitation).
AskPerson = Callable[[str], Awaitable[Answer]]


class Guard(Protocol):
    """The safety policy's side of the seam."""

    async def approve(self, act: Act, ask: AskPerson) -> Act:
        """The act to send (*act*, or a clamped copy); raises :class:`PolicyRefusal` to refuse it."""
        ...

    def record(self, act: Act, outcome: str) -> None:
        """One audit line per acting call: ``sent``, ``refused: ...`` or ``failed: ...``."""
        ...


class _AllowAll:
    """Approves every act unchanged and records nothing."""

    async def approve(self, act: Act, ask: AskPerson) -> Act:
        return act

    def record(self, act: Act, outcome: str) -> None:
        return None

    def __repr__(self) -> str:
        return "ALLOW_ALL"


ALLOW_ALL: Guard = _AllowAll()


async def nobody_to_ask(question: str) -> Answer:
    """The default :data:`AskPerson`: nobody to ask (no MCP client, or one without elicitation)."""
    return "unsupported"


class Timeouts(Protocol):
    """The one setting an act reads (the server's ``Config`` is one)."""

    @property
    def request_timeout(self) -> float: ...


class Acting(Protocol):
    """What an act needs: a robot session's parts and the call's own (a tool's ``ToolContext`` is one)."""

    @property
    def client(self) -> RosbridgeClient: ...
    @property
    def config(self) -> Timeouts: ...
    @property
    def graph(self) -> RosGraph: ...
    @property
    def guard(self) -> Guard: ...
    @property
    def ask_person(self) -> AskPerson: ...
    @property
    def activity(self) -> SessionActivity: ...
    @property
    def goals(self) -> GoalRegistry: ...


async def approved(ctx: Acting, act: Act) -> Act:
    """*act* as the guard approved it (perhaps clamped); a refusal is recorded, then raised."""
    try:
        return await ctx.guard.approve(act, ctx.ask_person)
    except PolicyRefusal as exc:
        ctx.guard.record(act, f"refused: {exc}")
        raise


async def carry_out(ctx: Acting, act: Act, send: Callable[[], Awaitable[Any]]) -> Any:
    """Run *send* for an approved *act* and tell the guard how it went."""
    try:
        result = await send()
    except BaseException as exc:
        ctx.guard.record(act, f"failed: {type(exc).__name__}: {exc}")
        raise
    ctx.guard.record(act, "sent")
    return result
