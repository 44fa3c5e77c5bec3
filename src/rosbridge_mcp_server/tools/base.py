"""What every tool module shares: its spec, its answer, and the context it runs in.

A tool module never imports ``mcp`` and never touches a socket: it gets a :class:`ToolContext` (the robot's
session, the configuration, a way to ask the person, a progress callback) and its arguments as its strict
model validated them (``tools/arguments.py``), calls one function of the domain layer (``robot/``) and renders
a :class:`ToolAnswer`. ``server/adapter.py`` turns these into MCP tools.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

from pydantic import BaseModel

from rosbridge_mcp_server.client.frame_limits import MAX_NESTING, MAX_PAYLOAD_CHARS, payload_problem
from rosbridge_mcp_server.errors import Advised
from rosbridge_mcp_server.robot.approval import ActKind, AskPerson, Guard, nobody_to_ask
from rosbridge_mcp_server.robot.messages import compact_json
from rosbridge_mcp_server.robot.names import absolute_name

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.config import Config
    from rosbridge_mcp_server.robot.activity import SessionActivity
    from rosbridge_mcp_server.robot.gate import SendGate
    from rosbridge_mcp_server.robot.goals import GoalRegistry
    from rosbridge_mcp_server.robot.graph import RosGraph
    from rosbridge_mcp_server.robot.session import RobotSession

__all__ = [
    "ACTS_ON_ROBOT",
    "MAX_NESTING",
    "MAX_PAYLOAD_CHARS",
    "READS_ROBOT",
    "LongWork",
    "Need",
    "ProgressReporter",
    "ToolAnswer",
    "ToolContext",
    "ToolFailure",
    "ToolHints",
    "ToolImage",
    "ToolSpec",
    "absolute_name",
    "compact_json",
    "payload_problem",
]


@dataclass(frozen=True)
class ToolHints:
    """The MCP tool annotations, in our own words (``server/adapter.py`` maps them to ``ToolAnnotations``)."""

    read_only: bool
    destructive: bool
    idempotent: bool
    # Every tool talks to a robot: an open world that changes on its own.
    open_world: bool = True


READS_ROBOT = ToolHints(read_only=True, destructive=False, idempotent=True)
ACTS_ON_ROBOT = ToolHints(read_only=False, destructive=True, idempotent=False)


#: What a tool needs the robot's session to keep for it in the background, from the moment the server starts:
#: ``service_types`` (each service's type learnt after every connect, ``RobotSession.learn_service_types``),
#: ``robot_log`` (the robot's log and diagnostics since the server connected, ``RobotSession.keep_logs``).
Need = Literal["service_types", "robot_log"]


@dataclass(frozen=True)
class LongWork:
    """A tool whose call may be long work (a drive, a goal, a recording, a timed reading): the server runs
    such a call as an MCP task when the client can follow one (``server/tasks.py``), and cancelling the task
    cancels the call.

    ``given``: only a call that gives this argument (not null) is long (``duration``); ``unless``: a call
    that sets this argument true is not (``record``'s ``stop``). ``cancelled``: what cancelling the run ends
    on the robot, in words, as the task's status says it ("its goal was cancelled on the robot").
    """

    given: str | None = None
    unless: str | None = None
    cancelled: str = "its reading ended"

    def applies(self, arguments: Mapping[str, Any]) -> bool:
        """Whether a call with *arguments* (as sent) is long work."""
        if self.given is not None and arguments.get(self.given) is None:
            return False
        return self.unless is None or arguments.get(self.unless) is not True


@dataclass(frozen=True)
class ToolSpec:
    """One tool as it declares itself: name, title, description (with an example), hints, answer, and what
    the server must know of it. The server reads these, never a tool's name.

    ``output`` is the pydantic model of the structured content of a successful answer; the server publishes
    its JSON schema as the tool's output schema. Answers carry an instance of it, so they fit by construction.

    ``acts_on`` is what an acting tool acts on the robot through (the audit line of a call refused before it
    ran names it). A tool that is not read-only says either ``acts_on`` or, when it sends nothing to the
    robot, ``changes`` (what it changes instead, in words: ``record`` writes "files on the server's host"); no
    reading tool says either. A spec that gets this wrong fails where it is written.

    ``needs``: what the robot's session keeps for it in the background (:data:`Need`), started only when the
    tool is served. ``stops``: the tool is the stop, which only ever takes motion away: it is served whenever
    a tool that acts is (whatever ``--tools`` chose) and works on a read-only robot of a fleet.
    ``every_robot``: on a server that drives several robots the ``robot`` argument is optional, and a call
    without it runs on every robot, the answers merged under each robot's name (such a tool never asks the
    person). ``long_work``: a call of it may run long, as an MCP task (:class:`LongWork`); when the tool acts
    on the robot (``acts_on``), a stop ends that run as it ends a plain call.
    """

    name: str
    title: str
    description: str
    hints: ToolHints
    output: type[BaseModel]
    acts_on: ActKind | None = None
    changes: str | None = None
    needs: frozenset[Need] = frozenset()
    stops: bool = False
    every_robot: bool = False
    long_work: LongWork | None = None

    def __post_init__(self) -> None:
        if not self.hints.read_only and (self.acts_on is None) == (self.changes is None):
            raise TypeError(
                f"{self.name}: an acting tool's ToolSpec must say acts_on= (topic, service, ...), or, when "
                "it sends nothing to the robot, changes= (what it changes instead); not both"
            )
        if self.hints.read_only and (self.acts_on is not None or self.changes is not None):
            raise TypeError(f"{self.name}: a reading tool acts on nothing; leave acts_on out of its ToolSpec")
        if self.stops and self.acts_on is None:
            raise TypeError(f"{self.name}: a tool that stops the robot acts on it; say acts_on=")


@dataclass(frozen=True)
class ToolImage:
    """A picture in an answer (e.g. a camera frame): encoded bytes and their MIME type."""

    data: bytes
    mime_type: str


@dataclass(frozen=True)
class ToolAnswer:
    """A tool's answer: short readable text for the model and the same facts as structured data.

    ``images`` follow the text as MCP image content (the structured data describes them, never holds them).
    """

    text: str
    data: BaseModel
    images: tuple[ToolImage, ...] = ()


ProgressReporter = Callable[[float, float | None, str | None], Awaitable[None]]


async def _no_progress(progress: float, total: float | None, message: str | None) -> None:
    """Default reporter: the caller did not ask for progress."""


@dataclass(frozen=True)
class ToolContext:
    """What one tool call may use: the robot's session (shared by every call on that robot), the robot's
    configuration, and the call's own: ways to ask the person at the MCP client (elicitation) and to report
    progress, and who is calling (the name the transport authenticated, for the audit; ``None`` on stdio).

    It is the :class:`~rosbridge_mcp_server.robot.acting.Acting` every checked send in ``robot/`` takes: the
    session's parts are read through it (``ctx.client``, ``ctx.graph``, ``ctx.guard``, ...).
    """

    robot: RobotSession
    config: Config
    report_progress: ProgressReporter = field(default=_no_progress)
    ask_person: AskPerson = field(default=nobody_to_ask)
    caller: str | None = None

    @property
    def client(self) -> RosbridgeClient:
        return self.robot.client

    @property
    def graph(self) -> RosGraph:
        return self.robot.graph

    @property
    def guard(self) -> Guard:
        return self.robot.guard

    @property
    def activity(self) -> SessionActivity:
        """What this server set going on the robot (velocity topics, streams): stop_robot's list."""
        return self.robot.activity

    @property
    def goals(self) -> GoalRegistry:
        return self.robot.goals

    @property
    def gate(self) -> SendGate:
        """The send gate every frame of an act passes as it is sent (``robot/gate.py``)."""
        return self.robot.gate


class ToolFailure(Advised):
    """A tool could not do what was asked (an unknown topic, a malformed argument, a goal that timed out).

    ``str()`` is a sentence saying what happened and what to try. The server turns it into an ``isError``
    result, like a :class:`~rosbridge_mcp_server.errors.RosbridgeError`.
    """
