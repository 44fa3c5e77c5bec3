"""Timing subjects against each other: interleaved rotated blocks (items 1-3, 8, 12, 15), calls locked to a
publisher's ticks (item 9)."""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import json
import time
from collections.abc import Awaitable, Callable, Sequence

import psutil
from websockets.asyncio.client import ClientConnection

from benchmarks.bridge import RawBridge
from benchmarks.figures import Plan, Stats
from benchmarks.machine import cpu_seconds


@dataclasses.dataclass
class Subject:
    """One thing whose latency is sampled, call by call, with the CPU each process spent on it."""

    key: str
    call: Callable[[], Awaitable[object]]
    server: psutil.Process | None = None  # the MCP server process the calls go through, if any
    pause: float = 0.0  # idle seconds before each call, not timed (a tool call's rosapi request follows one)
    samples: list[float] = dataclasses.field(default_factory=list)
    cpu: dict[str, float] = dataclasses.field(
        default_factory=lambda: {"bench": 0.0, "server": 0.0, "bridge": 0.0}
    )

    @property
    def stats(self) -> Stats:
        return Stats.of(self.samples)

    def cpu_per_call(self) -> dict[str, float | None]:
        spent = {where: total / len(self.samples) for where, total in self.cpu.items()}
        return spent | ({} if self.server else {"server": None})


async def interleave(subjects: Sequence[Subject], plan: Plan, bridge: psutil.Process | None = None) -> None:
    """Warm every subject up, then time them in rotated A/B/C blocks so drift hits all of them alike.

    CPU time is read around each block: where the work of a call is done, as well as how long it takes.
    """
    for subject in subjects:
        for _ in range(plan.warmup):
            await subject.call()
    me = psutil.Process()
    clock = time.perf_counter
    for round_number in range(plan.rounds):
        shift = round_number % len(subjects)
        for subject in [*subjects[shift:], *subjects[:shift]]:
            call, samples = subject.call, subject.samples
            before = (cpu_seconds(me), cpu_seconds(subject.server), cpu_seconds(bridge))
            for _ in range(plan.block):
                if subject.pause:
                    await asyncio.sleep(subject.pause)
                began = clock()
                await call()
                samples.append(clock() - began)
            after = (cpu_seconds(me), cpu_seconds(subject.server), cpu_seconds(bridge))
            for where, start, end in zip(("bench", "server", "bridge"), before, after, strict=True):
                subject.cpu[where] += end - start


class Metronome:
    """A raw connection that only notes when each message of a topic arrives (frames are not parsed).

    Each trial of a subscribe-to-first-message comparison starts right after a tick, so the raw socket and
    the tool both wait one period of the publisher plus their own overhead, instead of a random part of it.
    """

    def __init__(self, ws: ClientConnection, topic: str, msg_type: str) -> None:
        self.ws, self.topic, self.msg_type = ws, topic, msg_type
        self.tick = asyncio.Event()
        self._task: asyncio.Task[None] | None = None

    async def __aenter__(self) -> Metronome:
        await self.ws.send(
            json.dumps({"op": "subscribe", "id": "metronome", "topic": self.topic, "type": self.msg_type})
        )
        self._task = asyncio.create_task(self._listen())
        return self

    async def __aexit__(self, *_: object) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
        await self.ws.send(json.dumps({"op": "unsubscribe", "id": "metronome", "topic": self.topic}))

    async def _listen(self) -> None:
        async for _ in self.ws:
            self.tick.set()

    async def next_tick(self) -> None:
        self.tick.clear()
        await asyncio.wait_for(self.tick.wait(), 10)


async def raw_first_message(raw: RawBridge, topic: str, msg_type: str) -> None:
    """subscribe → first message (parsed) → unsubscribe, on the raw connection."""
    await raw.collect(topic, msg_type, 1)


async def phase_locked(
    metronome: Metronome, trials: int, subjects: dict[str, Callable[[], Awaitable[object]]]
) -> dict[str, Stats]:
    """Each subject ``trials`` times, alternating, every call started right after a metronome tick."""
    samples: dict[str, list[float]] = {name: [] for name in subjects}
    for trial in range(trials + 1):
        order = list(subjects.items())
        if trial % 2:
            order.reverse()
        for name, call in order:
            await metronome.next_tick()
            began = time.perf_counter()
            await call()
            if trial:  # the first round warms up
                samples[name].append(time.perf_counter() - began)
    return {name: Stats.of(values) for name, values in samples.items()}
