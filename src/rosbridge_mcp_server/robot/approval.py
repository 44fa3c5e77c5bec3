"""Approval, the safety seam: what an act on the robot is, who approves it, and the person who may be asked.

``robot/acting/`` builds an :class:`Act` for every checked send and asks the :class:`Guard` before anything
is sent: ``await guard.approve(act, ask_person)``. The guard may return a clamped copy of the act (what is
then sent) or raise :class:`~rosbridge_mcp_server.errors.PolicyRefusal`; either way it is told the outcome
(``guard.record``), once per act. Then every frame of it passes the robot's send gate
(:mod:`rosbridge_mcp_server.robot.gate`), which asks :meth:`Guard.held` again at that moment. ``safety/``
implements the guard; nothing here knows a policy or MCP.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from contextvars import ContextVar
from dataclasses import dataclass, replace
from typing import Any, Literal, Protocol

from rosbridge_mcp_server.errors import PolicyRefusal
from rosbridge_mcp_server.robot.effects import Effect

__all__ = [
    "ALLOW_ALL",
    "Act",
    "ActKind",
    "Answer",
    "AnswerNotInForm",
    "Approving",
    "AskPerson",
    "Guard",
    "SendToLink",
    "approved",
    "asking",
    "call_ending",
    "cancelled_why",
    "carry_out",
    "nobody_to_ask",
]

#: Why the call running in this context would have ended had it been cancelled, in words; set by what runs
#: the call (the MCP edge knows whether its client asked). The audit says it, never the cancel's repr.
call_ending: ContextVar[Callable[[], str]] = ContextVar("call_ending")


def cancelled_why() -> str:
    """``cancelled by the client``, ``cancelled: …``: why the call running now was cancelled, in words."""
    why = call_ending.get(None)
    return why() if why is not None else "cancelled"


#: What an act on the robot goes through: the one spelling of the kinds (a tool's ``ToolSpec.acts_on``, the
#: audit's ``kind``, the policy's rules).
ActKind = Literal["topic", "service", "action", "parameter"]


@dataclass(frozen=True)
class Act:
    """One act on the robot, as it will be sent: checked, normalised, with an absolute name.

    ``kind`` and ``name`` are the carrier the tool names (the topic published on, the service called);
    ``effects`` what the robot does besides (:mod:`rosbridge_mcp_server.robot.effects`: the goal a
    ``…/goal`` topic starts, the parameters a ``set_parameters`` call writes, a teleport's motion), judged by
    the guard as if the matching tool had been used. ``given`` is the name as the caller wrote it, when that
    is not the canonical ``name``.
    """

    tool: str  #: the tool that asks, e.g. "publish_topic"
    kind: ActKind
    name: str  #: absolute ROS name (topic/service/action/parameter)
    type: str  #: ROS type as sent to the bridge ("" when none, e.g. a parameter)
    payload: Any  #: message / request / goal / value that will be sent
    rate_hz: float | None = None  #: publish streams only
    duration: float | None = None  #: publish streams only
    effects: tuple[Effect, ...] = ()
    given: str | None = None
    #: What the act is judged against beyond itself: for a navigation goal, the robot's map, its pose and the
    #: goal placed on it (a ``robot.navigation.Scene``), learnt just before the act was built; else None.
    scene: Any = None
    #: Who asked for it, for the audit: the name the MCP transport authenticated (a token's name, a JWT's
    #: subject); ``None`` when not known (stdio). :func:`approved` writes the call's own in.
    caller: str | None = None


Answer = Literal["accept", "decline", "cancel", "unsupported"]
#: Sends the person at the MCP client to a URL (``question``, ``url``, an id for the request): their answer
#: is given there; "accept" only means they went.
SendToLink = Callable[[str, str, str], Awaitable[Answer]]


class AnswerNotInForm(Exception):
    """The person's MCP client answered a question, but not in the form it was asked (an ``approve`` that is
    no yes/no, or none): raised by an :class:`AskPerson`; ``str()`` says what was wrong, never the answer's
    own values."""


class AskPerson:
    """The person at the MCP client, asked a yes/no question (the server's elicitation): ``await ask(text)``.

    This one has nobody to ask (no MCP client, or one without elicitation): every question is
    ``"unsupported"``; the MCP edge gives a call its own, which raises :class:`AnswerNotInForm` for an answer
    off the question's form. ``by_link`` is set when the client can also open a URL for the person: the guard
    then sends them to this call's approval on the operator console.
    """

    by_link: SendToLink | None = None

    async def __call__(self, question: str) -> Answer:
        return "unsupported"


class _Asking(AskPerson):
    def __init__(self, ask: Callable[[str], Awaitable[Answer]], by_link: SendToLink | None) -> None:
        self._ask = ask
        self.by_link = by_link

    async def __call__(self, question: str) -> Answer:
        return await self._ask(question)


def asking(ask: Callable[[str], Awaitable[Answer]], by_link: SendToLink | None = None) -> AskPerson:
    """An :class:`AskPerson` that asks with *ask* (and sends to a link with *by_link*, when given)."""
    return _Asking(ask, by_link)


class Guard(Protocol):
    """The safety policy's side of the seam."""

    async def approve(self, act: Act, ask: AskPerson) -> Act:
        """The act to send (*act*, or a clamped copy); raises :class:`PolicyRefusal` to refuse it."""
        ...

    def record(self, act: Act, outcome: str) -> None:
        """One audit line per acting call: ``sent``, ``refused: ...`` or ``failed: ...``."""
        ...

    def held(self) -> str | None:
        """Why nothing may be sent right now (the operator's latched E-STOP), or ``None``.

        Asked by the send gate (:mod:`rosbridge_mcp_server.robot.gate`) at every send, after approval too.
        """
        ...

    def send_interval(self, act: Act) -> float:
        """The shortest time (s) between two messages on *act*'s topic to the robot; 0 for no bound."""
        ...


class _AllowAll:
    """Approves every act unchanged and records nothing."""

    async def approve(self, act: Act, ask: AskPerson) -> Act:
        return act

    def record(self, act: Act, outcome: str) -> None:
        return None

    def held(self) -> str | None:
        return None

    def send_interval(self, act: Act) -> float:
        return 0.0

    def __repr__(self) -> str:
        return "ALLOW_ALL"


ALLOW_ALL: Guard = _AllowAll()


#: The default :class:`AskPerson`: nobody to ask (no MCP client, or one without elicitation).
nobody_to_ask = AskPerson()


class Approving(Protocol):
    """What the seam reads of a call to approve and carry out an act (a tool's ``ToolContext`` is one; all an
    act needs is :class:`rosbridge_mcp_server.robot.acting.Acting`)."""

    @property
    def guard(self) -> Guard: ...
    @property
    def ask_person(self) -> AskPerson: ...
    @property
    def caller(self) -> str | None: ...


async def approved(ctx: Approving, act: Act) -> Act:
    """*act* as the guard approved it (perhaps clamped), named with the call's caller; a refusal is recorded,
    then raised."""
    if act.caller is None and ctx.caller is not None:
        act = replace(act, caller=ctx.caller)
    try:
        return await ctx.guard.approve(act, ctx.ask_person)
    except PolicyRefusal as exc:
        ctx.guard.record(act, f"refused: {exc}")
        raise


async def carry_out(ctx: Approving, act: Act, send: Callable[[], Awaitable[Any]]) -> Any:
    """Run *send* for an approved *act* and tell the guard how it went."""
    try:
        result = await send()
    except PolicyRefusal:
        raise  # the send gate refused it at the moment of sending, and audited that
    except asyncio.CancelledError:
        ctx.guard.record(act, cancelled_why())
        raise
    except BaseException as exc:
        ctx.guard.record(act, f"failed: {type(exc).__name__}: {exc}")
        raise
    ctx.guard.record(act, "sent")
    return result
