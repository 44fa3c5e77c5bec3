"""A message published at a rate for a while (:func:`publish_stream`): approved once, each message through
the send gate, a velocity stream ended with one all-zero message whatever ends it."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import ConnectionLostError, NotConnectedError, PolicyRefusal
from rosbridge_mcp_server.robot.acting.context import Acting, given_name, motion_scene
from rosbridge_mcp_server.robot.acting.topics import adjusted_text, bridge_is_reading, checked_message
from rosbridge_mcp_server.robot.approval import Act, approved, cancelled_why
from rosbridge_mcp_server.robot.effects import topic_effects
from rosbridge_mcp_server.robot.goals.caused import caused_by_publish
from rosbridge_mcp_server.robot.velocity import is_velocity_type, stamped

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.activity import Stream
    from rosbridge_mcp_server.robot.gate import Ticket
    from rosbridge_mcp_server.robot.goals.caused import CausedGoal

__all__ = ["StreamProgress", "Streamed", "publish_stream"]

_log = logging.getLogger(__name__)

#: Told of a stream's progress: (messages sent, messages planned).
StreamProgress = Callable[[int, int], Awaitable[None]]


@dataclass(frozen=True)
class Streamed:
    """What a publish stream did."""

    topic: str
    type: str
    message: dict[str, Any]  #: as sent each time
    rate_hz: float  #: as approved (the guard may lower it)
    duration: float  #: as approved
    planned: int
    sent: int
    cancelled: bool  #: stopped early (an MCP cancel, or the server stopping)
    zero: dict[str, Any] | None  #: the all-zero message sent at the end (velocity types), else None
    stopped: bool = False  #: ended early because stop_robot (or the operator's E-STOP) asked
    #: How the safety policy changed the message before it was sent (velocity caps in clamp mode), or None.
    adjusted: str | None = None
    #: Who stopped it early, when ``stopped`` (the stop's ``by``: "stop_robot", or the operator's E-STOP).
    stopped_by: str = ""
    #: Ended before ``planned``: the topic's rate cap, shared with every other sender on it, left no slot
    #: within the stream's duration.
    rate_limited: bool = False


async def publish_stream(
    ctx: Acting,
    *,
    tool: str,
    topic: str,
    message_type: str,
    message: dict[str, Any],
    rate_hz: float,
    duration: float,
    on_progress: StreamProgress | None = None,
) -> Streamed:
    """Publish *message* at *rate_hz* for *duration* seconds, on an absolute schedule (no drift).

    The stream is approved once, at the start, with its rate and duration (the guard may clamp both); each
    message then passes the send gate (``robot/gate.py``): a stop or a latched E-STOP ends the stream (its
    first message refused: :class:`PolicyRefusal`), and the topic's rate cap may hold a message back (a slot
    after the stream's planned end ends it early). A velocity stream (``Twist``, ``TwistStamped``) always
    ends with one all-zero message, also when it is cancelled; cancellation stops it at once otherwise and is
    re-raised after that zero message.
    """
    ticket = ctx.gate.ticket()  # a stop from now on voids this stream
    name, bridge_type, body = await checked_message(ctx, topic, message_type, message)
    act = await approved(
        ctx,
        Act(
            tool,
            "topic",
            name,
            bridge_type,
            body,
            rate_hz=rate_hz,
            duration=duration,
            effects=topic_effects(name, bridge_type),
            given=given_name(topic, name),
            scene=await motion_scene(ctx, "topic", name, bridge_type, body),
        ),
    )
    caused = caused_by_publish(act.name, act.payload, act.effects, (await ctx.graph.dialect()).version)
    rate = act.rate_hz or rate_hz
    length = act.duration if act.duration is not None else duration
    stream = _Stream(ctx, act, ticket, caused, rate, length, on_progress)
    zero = _zero_velocity(act.type, act.payload)
    await stream.run_then_stop(zero)
    done = f"stopped by {stream.stopped_by} after" if stream.stopped else "sent"
    ctx.guard.record(act, f"{done} {stream.sent} of {stream.planned}")
    return stream.outcome(body, zero)


@dataclass
class _Stream:
    """One approved stream as it goes: its schedule, and what it has done so far."""

    ctx: Acting
    act: Act
    ticket: Ticket
    caused: CausedGoal | None
    rate: float
    length: float
    on_progress: StreamProgress | None
    sent: int = 0
    cancelled: bool = False
    stopped: bool = False
    stopped_by: str = ""  #: who, once stopped: the stream's or the gate's stopper
    rate_limited: bool = False

    @property
    def planned(self) -> int:
        return max(1, round(self.length * self.rate))

    async def run_then_stop(self, zero: dict[str, Any] | None) -> None:
        """:meth:`run`, then the all-zero *zero* (shielded) once anything was sent, whatever ended it; a
        cancel or a failure is audited here."""
        ctx, act = self.ctx, self.act
        try:
            await self.run()
        except asyncio.CancelledError:
            self.cancelled = True
            raise
        except PolicyRefusal:
            raise  # the gate refused its first message and audited it: nothing of the stream was sent
        except BaseException as exc:
            ctx.guard.record(act, f"failed after {self.sent} of {self.planned}: {type(exc).__name__}: {exc}")
            raise
        finally:
            if self.cancelled:
                # Recorded first: inside a cancelled anyio scope (the SDK's) every await raises again, the
                # shielded one below too, so a line written after it was lost.
                ctx.guard.record(act, f"{cancelled_why()} after {self.sent} of {self.planned}")
            if zero is not None and self.sent > 0:
                # Shielded: a second cancel must not leave the robot moving.
                await asyncio.shield(_publish_quietly(ctx, act, zero))

    async def run(self) -> None:
        """Send the planned messages on an absolute schedule until a stop, the rate cap, or the end."""
        ctx, act = self.ctx, self.act
        loop = asyncio.get_running_loop()
        # Registered before anything of it is sent (the ping included), so that stop_robot and the E-STOP
        # see it and end it: pause() returns early when asked.
        with ctx.activity.stream(act.name, act.type) as running:
            if not await running.unless_stopped(bridge_is_reading(ctx)):
                await ctx.client.advertise(act.name, act.type)
            start = loop.time()
            # A slot (the topic's rate, shared with every other sender) later than this ends the stream.
            latest = start + self.length + 1 / self.rate
            for index in range(self.planned):
                if await running.pause(start + index / self.rate - loop.time()):
                    self.stopped, self.stopped_by = True, running.stopped_by
                    return
                if not await self._paced(latest):
                    return
                await self._send_one(running)

    async def _paced(self, latest: float) -> bool:
        """Whether the send gate lets the next message go. A stop or a latched E-STOP ends the stream (raised
        for its first message: nothing was sent); no slot of the topic's rate before *latest* ends it too."""
        try:
            if await self.ctx.gate.pace(self.ticket, self.act, latest=latest):
                return True
            self.rate_limited = True
        except PolicyRefusal:
            if self.sent == 0:
                raise
            self.stopped, self.stopped_by = True, self.ctx.gate.stopped_by
        return False

    async def _send_one(self, running: Stream) -> None:
        ctx, act = self.ctx, self.act
        await ctx.client.publish(act.name, act.type, act.payload)
        if self.sent == 0:
            ctx.graph.remember_publishing(act.name, act.type)
            ctx.activity.published(act.name, act.type, act.payload)
            ctx.goals.caused(self.caused)
        self.sent += 1
        every = max(1, round(self.rate / 5))  # progress about five times a second at most
        if self.on_progress is not None and (self.sent % every == 0 or self.sent == self.planned):
            await self.on_progress(self.sent, self.planned)

    def outcome(self, body: dict[str, Any], zero: dict[str, Any] | None) -> Streamed:
        """What the stream did; *body* is the message as given (to say how the guard changed it)."""
        act = self.act
        return Streamed(
            act.name,
            act.type,
            act.payload,
            self.rate,
            self.length,
            self.planned,
            self.sent,
            self.cancelled,
            zero if self.sent > 0 else None,  # sent only after a message that moved
            self.stopped,
            adjusted_text(act.type, body, act.payload),
            self.stopped_by,
            self.rate_limited,
        )


async def _publish_quietly(ctx: Acting, act: Act, message: dict[str, Any]) -> None:
    try:
        await ctx.client.publish(act.name, act.type, message)
    except (NotConnectedError, ConnectionLostError):  # the connection is down: owed until it is back
        header = message.get("header")
        ctx.activity.owe_zero(
            act.name, act.type, header.get("frame_id", "") if isinstance(header, dict) else ""
        )
        _log.warning("the zero that ends the stream on %s goes out once the connection is back", act.name)
    except Exception:
        _log.warning("could not send the zero message that ends the stream on %s", act.name, exc_info=True)


def _zero_velocity(bridge_type: str, message: dict[str, Any]) -> dict[str, Any] | None:
    """The all-zero command that ends a stream of velocity commands (a stream of them ends with one, so the
    robot stops); ``None`` for other types."""
    if not is_velocity_type(bridge_type):
        return None
    still = {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
    if not stamped(bridge_type):
        return still
    header = message.get("header")
    frame = header.get("frame_id", "") if isinstance(header, dict) else ""
    # The stamp is left out: rosbridge stamps a root header it is not given (ROS 1; ROS 2 2.0.7 / 2.7.0 on).
    return {"header": {"frame_id": frame}, "twist": still}
