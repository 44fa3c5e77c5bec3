"""The person beside the robot, as the guard sees them: confirmations they answer and the latched e-stop.

:class:`Operator` is the seam between :class:`~rosbridge_mcp_server.safety.guard.PolicyGuard` and whatever
shows the robot to a person (the operator console): the guard asks it when the MCP client cannot ask, and
refuses every acting call while its e-stop is latched. It knows no web page; the console reads its state and
calls :meth:`Operator.answer`, :meth:`Operator.latch` and :meth:`Operator.release`.

**Confirmations by link.** While the console is served it sets :attr:`Operator.link_base` (its address).
When the MCP client can open a URL for the person (URL-mode elicitation), the guard asks through
:meth:`Operator.ask` with that client's ``by_link``: the client is sent the console's address with this one
confirmation's id and a token of its own in the fragment (``#confirm=c3&token=...``), never the console's
session secret. The token answers this confirmation only, and only while it waits: it is what a form
elicitation would let the client do (answer this one question), and nothing more.
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import itertools
import logging
import secrets
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.approval import Act, Answer, SendToLink

__all__ = ["Operator", "PendingConfirmation"]

_log = logging.getLogger("rosbridge_mcp_server.safety")


@dataclass
class PendingConfirmation:
    """One acting call waiting for the person's Approve or Deny."""

    id: str
    question: str
    act: Act
    asked_at: float = field(default_factory=time.time)
    answer: asyncio.Future[Answer] = field(default_factory=lambda: asyncio.get_running_loop().create_future())
    #: Lets a link (URL-mode elicitation) answer this confirmation, and nothing else.
    token: str = field(default_factory=lambda: secrets.token_urlsafe(24), repr=False)
    #: Whether the person was sent here by a link from the MCP client.
    by_link: bool = False


class Operator:
    """A person at a console: answers confirmations the MCP client cannot ask, and holds a latched e-stop.

    ``present`` says whether anyone can answer (a console is being served); without one, :meth:`ask` answers
    "unsupported" at once, as a client without elicitation does.
    """

    def __init__(self, *, present: bool = True) -> None:
        self.present = present
        self._pending: dict[str, PendingConfirmation] = {}
        self._ids = itertools.count(1)
        self._latched_by: str | None = None
        self._listeners: list[Callable[[], None]] = []
        #: The console's address (``http(s)://HOST:PORT/``) while it is served: links to confirmations.
        self.link_base: str | None = None

    # --- what the guard asks -------------------------------------------------------------------------------

    async def ask(self, question: str, act: Act, by_link: SendToLink | None = None) -> Answer:
        """Wait for the person's answer to ``question`` (the caller bounds the wait; no answer is a no).

        With ``by_link`` (the MCP client can open a URL) and the console served, the client is also sent to
        this confirmation on the console; declining to go there is a no, going there waits for the answer.
        """
        if not self.present:
            return "unsupported"
        if self._latched_by is not None:
            return "decline"
        pending = PendingConfirmation(f"c{next(self._ids)}", question, act)
        link = self.link_base
        pending.by_link = by_link is not None and link is not None
        self._pending[pending.id] = pending
        self._changed()
        sending: asyncio.Future[Answer] | None = None
        if by_link is not None and link is not None:
            url = f"{link}#confirm={pending.id}&token={pending.token}"
            sending = asyncio.ensure_future(by_link(question, url, pending.id))
            sending.add_done_callback(lambda done: _link_answered(pending, done))
        try:
            return await pending.answer
        finally:
            if sending is not None and not sending.done():
                sending.cancel()
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await sending
            self._pending.pop(pending.id, None)
            self._changed()

    def by_token(self, pending_id: str, token: str) -> PendingConfirmation | None:
        """The confirmation waiting under ``pending_id`` when ``token`` is its own, else ``None``."""
        pending = self._pending.get(pending_id)
        if pending is None or not hmac.compare_digest(pending.token.encode(), token.encode()):
            return None
        return pending

    @property
    def latched(self) -> str | None:
        """Who latched the e-stop (e.g. "console"), or ``None`` while acting calls may go through."""
        return self._latched_by

    # --- what the person does ------------------------------------------------------------------------------

    @property
    def pending(self) -> list[PendingConfirmation]:
        """The confirmations waiting now, oldest first."""
        return list(self._pending.values())

    def answer(self, pending_id: str, approve: bool) -> bool:
        """Approve or deny one waiting confirmation; ``False`` when it is no longer waiting."""
        pending = self._pending.get(pending_id)
        if pending is None or pending.answer.done():
            return False
        pending.answer.set_result("accept" if approve else "decline")
        return True

    def latch(self, by: str) -> None:
        """Latch the e-stop: waiting confirmations are denied, acting calls refused until released."""
        self._latched_by = by
        for pending in self._pending.values():
            if not pending.answer.done():
                pending.answer.set_result("decline")
        _log.warning("e-stop latched by the %s: acting calls are refused until it is released", by)
        self._changed()

    def release(self, by: str) -> bool:
        """Release the latched e-stop; ``False`` when it was not latched."""
        if self._latched_by is None:
            return False
        self._latched_by = None
        _log.warning("e-stop released by the %s", by)
        self._changed()
        return True

    # --- who is told of changes ----------------------------------------------------------------------------

    def listen(self, callback: Callable[[], None]) -> None:
        """Call ``callback`` (no arguments, must not block) whenever a confirmation or the latch changes."""
        self._listeners.append(callback)

    def _changed(self) -> None:
        for callback in self._listeners:
            try:
                callback()
            except Exception:
                _log.exception("an operator listener failed")


def _link_answered(pending: PendingConfirmation, sending: asyncio.Future[Answer]) -> None:
    """The client's answer to the link: a no ends the confirmation; going there (or a client that could not
    show it) leaves it waiting for the console."""
    if sending.cancelled() or pending.answer.done():
        return
    if sending.exception() is not None:
        _log.info("sending the person to the console failed: %s", sending.exception())
        return
    answer = sending.result()
    if answer in ("decline", "cancel"):
        pending.answer.set_result(answer)
