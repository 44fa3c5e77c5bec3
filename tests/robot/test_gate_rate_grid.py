"""The send gate's turns for ``[publish] max_rate_hz``, read off a virtual clock: a grid that holds, no burst.

``tests/mcp/test_mcp_rate_bound.py`` counts on the robot what a capped stream delivers, on the machine's own
clock, so it runs at 5 Hz to ride out a loaded CI machine's stalls, and at 5 Hz it no longer sees a gate whose
turns drift. Here the gate runs on an event loop whose clock is the test's: a wait costs no real time, every
wake comes as late as the test says (what timer latency and a busy loop do to a real one), and a stall is the
clock jumping while nothing runs. What is checked is the loop time of each yes the gate gives one sender that
is always ready (as eight streams side by side are):

* a wake a little late keeps the grid: the k-th yes is less than one turn after ``first + k * interval``, so
  a stream at exactly the cap sends all it planned (a gate that re-anchors its grid at each send loses a
  little of the rate at every turn, and the stream falls behind);
* a stall longer than a turn costs the turns it spans and is not caught up: in any window of T seconds at
  most ``2 + T / interval`` yeses (a gate that hands out the missed turns at once sends a burst).
"""

from __future__ import annotations

import asyncio
import io
import selectors
from collections.abc import Callable, Iterator, Mapping
from itertools import cycle
from typing import Any

import pytest

from rosbridge_mcp_server.robot.approval import Act
from rosbridge_mcp_server.robot.gate import SendGate
from rosbridge_mcp_server.safety import Audit, PolicyGuard, parse_policy

RATE = 20.0
INTERVAL = 1 / RATE
#: How late each wake comes, in turn: a few milliseconds mostly, now and then over half a turn.
LATENESS = (0.004, 0.011, 0.002, 0.6 * INTERVAL, 0.007, 0.0, 0.019)
#: Float slack on loop times (sums of many small steps).
EPSILON = 1e-9


class _ClockSelector(selectors.BaseSelector):
    """Polls the real selector and, where the loop would block for *timeout*, moves the clock on instead."""

    def __init__(self, loop: VirtualClockLoop) -> None:
        self._inner = selectors.DefaultSelector()
        self._loop = loop

    def register(self, fileobj: Any, events: int, data: object = None) -> selectors.SelectorKey:
        return self._inner.register(fileobj, events, data)

    def unregister(self, fileobj: Any) -> selectors.SelectorKey:
        return self._inner.unregister(fileobj)

    def modify(self, fileobj: Any, events: int, data: object = None) -> selectors.SelectorKey:
        return self._inner.modify(fileobj, events, data)

    def select(self, timeout: float | None = None) -> list[tuple[selectors.SelectorKey, int]]:
        ready = self._inner.select(0)
        if ready or timeout == 0:
            return ready
        if timeout is None:
            raise RuntimeError("the virtual clock's loop has nothing scheduled: it would wait forever")
        self._loop.now += timeout + self._loop.lateness()
        return []

    def get_map(self) -> Mapping[Any, selectors.SelectorKey]:
        return self._inner.get_map()

    def close(self) -> None:
        self._inner.close()


class VirtualClockLoop(asyncio.SelectorEventLoop):
    """An event loop on the test's clock: ``now`` moves only when the loop would wait (by the wait, plus
    *lateness()* for the wake) or when :meth:`stall` jumps it."""

    def __init__(self, lateness: Callable[[], float]) -> None:
        self.now = 1000.0
        self.lateness = lateness
        super().__init__(_ClockSelector(self))

    def time(self) -> float:
        return self.now

    def stall(self, seconds: float) -> None:
        """The loop is blocked *seconds* (a callback that ran long, the machine busy elsewhere)."""
        self.now += seconds


def capped_gate() -> SendGate:
    audit = Audit(io.StringIO())
    return SendGate(PolicyGuard(parse_policy({"publish": {"max_rate_hz": RATE}}, where="test.toml"), audit))


def stream_act() -> Act:
    return Act("publish_topic", "topic", "/cmd_vel", "geometry_msgs/msg/Twist", {"linear": {"x": 0.1}})


def yes_times(
    messages: int, lateness: tuple[float, ...], stall: tuple[int, float] | None = None
) -> tuple[list[float], float]:
    """Run *messages* sends of one always-ready sender through a capped gate on a virtual clock; the loop time
    of each yes, and the ``latest`` the stream gave (its planned end plus a turn, as a stream does).

    *stall* is ``(after, seconds)``: the loop is blocked *seconds* right after the yes of message *after*."""
    late = cycle(lateness)
    loop = VirtualClockLoop(lambda: next(late))
    gate = capped_gate()
    act = stream_act()
    latest = loop.now + messages / RATE

    async def send() -> list[float]:
        ticket = gate.ticket()
        times: list[float] = []
        for index in range(messages):
            if not await gate.pace(ticket, act, latest=latest):
                break
            times.append(loop.time())
            if stall is not None and index == stall[0]:
                loop.stall(stall[1])
            await asyncio.sleep(0)  # the frame is written; the sender comes back for its next turn
        return times

    try:
        return loop.run_until_complete(send()), latest
    finally:
        loop.close()


def grid_errors(times: list[float]) -> Iterator[float]:
    """How far each yes is from the grid the first one starts (``first + k * interval``)."""
    return (time - (times[0] + index * INTERVAL) for index, time in enumerate(times))


def busiest_window(times: list[float]) -> tuple[int, float]:
    """The window of yeses furthest over ``2 + T / interval``: (how many, T)."""
    windows = [(j - i + 1, times[j] - times[i]) for i in range(len(times)) for j in range(i, len(times))]
    return max(windows, key=lambda window: window[0] - window[1] / INTERVAL)


def over_the_cap(times: list[float]) -> bool:
    count, span = busiest_window(times)
    return count > 2 + span / INTERVAL + EPSILON


def test_a_stream_at_the_cap_keeps_the_grid_through_late_wakes() -> None:
    """40 messages at exactly 20 Hz, each wake late by up to 0.6 of a turn: every one is sent, each within a
    turn of its place on the grid, and never more than the cap allows."""
    times, latest = yes_times(40, LATENESS)
    assert len(times) == 40, f"{len(times)} of 40 sent before the stream's end ({latest - times[0]:.3f} s)"
    errors = list(grid_errors(times))
    # The wakes did come late (else re-anchoring at each send could not be told from keeping the grid) ...
    assert max(errors) >= 0.5 * INTERVAL, errors
    # ... and no lateness was carried into the turns after it.
    assert all(-EPSILON <= error < INTERVAL for error in errors), [round(e, 4) for e in errors]
    assert not over_the_cap(times), busiest_window(times)


@pytest.mark.parametrize("stall_turns", [2.5, 3.2, 7.5])
def test_a_stall_longer_than_a_turn_costs_its_turns_and_is_not_caught_up(stall_turns: float) -> None:
    """The loop blocked for over a turn mid-stream: the turns it spanned are gone, not sent in a burst after
    it; the grid starts again from the yes after the stall."""
    stall = stall_turns * INTERVAL
    times, _ = yes_times(40, LATENESS, stall=(10, stall))
    assert not over_the_cap(times), busiest_window(times)
    after = times[11:]
    assert after[0] - times[10] >= stall - EPSILON  # the stall did happen between these two yeses
    assert all(-EPSILON <= error < INTERVAL for error in grid_errors(after)), list(grid_errors(after))
    # The stream lost about the turns the stall spanned, no more: the rest went at the cap.
    assert len(times) >= 40 - int(stall_turns) - 2, len(times)


# --- the checks above can fail ------------------------------------------------------------------------------


def test_the_grid_check_sees_a_grid_re_anchored_at_each_send() -> None:
    """Turns one interval after each (late) yes drift by the lateness at every turn: off the grid."""
    times = [0.0]
    late = cycle(LATENESS)
    for _ in range(39):
        times.append(times[-1] + INTERVAL + next(late))
    assert max(grid_errors(times)) >= INTERVAL


def test_the_cap_check_sees_missed_turns_sent_at_once() -> None:
    """A gate that keeps the grid through a 3.2-turn stall hands the three passed turns out together."""
    times = [index * INTERVAL for index in range(11)]
    resumed = times[-1] + 3.2 * INTERVAL
    times += [resumed, resumed, resumed, *(times[0] + k * INTERVAL for k in range(14, 30))]
    assert over_the_cap(times)
    assert not over_the_cap([index * INTERVAL for index in range(30)])
