"""The send gate: the one place every act passes at the moment it goes to the bridge.

The guard approves an act once (rules, caps, a person's yes); a stream then runs for seconds and a goal may
wait for its action server first. So approval alone cannot make a stop win: the E-STOP may come after the yes
and before the send. Every send therefore passes :class:`SendGate` right before its frame is written:

* :meth:`SendGate.ticket` is taken before the act is approved; :meth:`SendGate.stop` (``stop_robot``, the
  console's E-STOP) voids every ticket taken before it, so whatever was approved (or being approved) before a
  stop never sends again;
* the guard's :meth:`~rosbridge_mcp_server.robot.approval.Guard.held` is asked at each send too: while the
  operator's E-STOP is latched nothing goes out, whenever it was approved;
* :meth:`SendGate.pace` bounds the rate of messages per topic on this robot, across every stream and single
  publish (the guard's ``send_interval``: ``[publish] max_rate_hz``), by handing out send slots.

A refused send raises :class:`~rosbridge_mcp_server.errors.PolicyRefusal` whose text says who stopped it.
What only takes motion away (zero commands, cancels) never passes the gate: a stop always goes out.
"""

from __future__ import annotations

import asyncio
import contextlib
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rosbridge_mcp_server.errors import PolicyRefusal

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.approval import Act, Guard

__all__ = ["SendGate", "Ticket"]


@dataclass(frozen=True)
class Ticket:
    """What a call holds from before its approval to its last send: the gate's stop count then."""

    stops: int


class SendGate:
    """Send-time checks for one robot: the latch, stops since the call began, and the per-topic rate."""

    def __init__(self, guard: Guard) -> None:
        self._guard = guard
        self._stops = 0
        self._stopped_by = ""  # set by every stop(): no refusal names it before one
        self._stopped = asyncio.Event()
        #: topic → the loop time from which the next message on it may go out
        self._next_slot: dict[str, float] = {}

    # --- stops -----------------------------------------------------------------------------------------

    def ticket(self) -> Ticket:
        """Taken before an act is approved; a stop after this voids it."""
        return Ticket(self._stops)

    def stop(self, by: str) -> None:
        """Void every ticket taken so far (``by`` is named in their refusals) and wake every paced send."""
        self._stops += 1
        self._stopped_by = by
        self._stopped.set()
        self._stopped = asyncio.Event()

    @property
    def stopped_by(self) -> str:
        """Who asked for the latest stop ("stop_robot", or the console's E-STOP)."""
        return self._stopped_by

    def refusal(self, ticket: Ticket) -> str | None:
        """Why *ticket*'s act may not be sent now, or ``None``."""
        held = self._guard.held()
        if held is not None:
            return held
        if ticket.stops != self._stops:
            return (
                f"Stopped: {self._stopped_by} stopped this call before it was sent, so nothing more of it "
                "went to the robot. Do not send it again unless the user asks you to."
            )
        return None

    def check(self, ticket: Ticket, act: Act) -> None:
        """Raise :class:`PolicyRefusal` (audited) unless *act* may be sent right now."""
        text = self.refusal(ticket)
        if text is not None:
            self._guard.record(act, f"not sent: {_first_sentence(text)}")
            raise PolicyRefusal(text)

    # --- rate ------------------------------------------------------------------------------------------

    async def pace(self, ticket: Ticket, act: Act, *, latest: float | None = None) -> bool:
        """Wait until *act*'s topic may take another message, then :meth:`check`; ``False`` (nothing waited)
        when that would be after the loop time *latest*.

        Each topic's next turn is kept, and the next message on the topic waits until the guard's
        ``send_interval`` after the last turn (after the yes itself when it came an interval or more late),
        whoever sends it: the caller writes its frame right after the yes, with nothing awaited between, so in
        any window of T seconds at most ``2 + T / interval`` messages leave for one topic
        (``1 + T / interval`` when no yes comes late). A stop during the wait ends it at once (with the
        refusal).
        """
        interval = self._guard.send_interval(act)
        if interval > 0:
            loop = asyncio.get_running_loop()
            while (due := self._next_slot.get(act.name, 0.0)) > loop.time():
                if latest is not None and due > latest:
                    return False
                self.check(ticket, act)
                await self._wait_unless_stopped(due - loop.time())
            self.check(ticket, act)
            now = loop.time()
            # A yes a little after its turn keeps the turns' grid (the next turn is one interval after this
            # one's), so a stream at the cap is not pushed later by every hiccup of the loop; after a pause
            # (or the first message) the grid starts again from now.
            late = now - due
            self._next_slot[act.name] = (due if 0.0 <= late < interval else now) + interval
            return True
        self.check(ticket, act)
        return True

    async def _wait_unless_stopped(self, seconds: float) -> None:
        stopped = self._stopped
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(seconds):
                await stopped.wait()


def _first_sentence(text: str) -> str:
    head, _, _ = text.partition(". ")
    return head.rstrip(".")
