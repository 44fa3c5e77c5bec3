"""Numbers from topics over time: dotted-path fields of each message, with receive times and units.

A field path is dotted, array elements by index (``twist.twist.linear.x``, ``ranges.0``). The first message
of each topic checks its paths, so a misspelt field is an error within one message, not after the whole
duration. Values are kept as they arrive (floats, booleans as 0/1); ``null`` (a NaN sent as JSON) is a gap.
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Awaitable, Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import RequestTimeoutError

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient

__all__ = ["FieldError", "Series", "TopicFields", "collect", "unit_of", "value_at"]

#: Samples kept per series (a 1 kHz topic for 60 s); later ones are dropped and counted.
MAX_SAMPLES = 60_000
#: Seconds between progress reports.
PROGRESS_EVERY = 1.0


class FieldError(ValueError):
    """A path that does not lead to a number; ``str()`` names it and what is there."""


@dataclass(frozen=True)
class TopicFields:
    """One topic, its type, and the paths to plot from it."""

    topic: str
    msg_type: str
    paths: tuple[str, ...]


@dataclass
class Series:
    """One field of one topic over time: seconds since the start and values (NaN for a gap)."""

    topic: str
    path: str
    unit: str
    times: list[float] = field(default_factory=list)
    values: list[float] = field(default_factory=list)
    dropped: int = 0

    @property
    def label(self) -> str:
        return f"{self.topic} {self.path}"


def value_at(message: Any, path: str) -> float:
    """The number at a dotted path; :class:`FieldError` when the path is not there or not a number."""
    current = message
    walked: list[str] = []
    for part in path.split("."):
        if isinstance(current, Mapping):
            if part not in current:
                where = f" in {'.'.join(walked)}" if walked else ""
                raise FieldError(
                    f"Field {path!r}: there is no {part!r}{where}; the fields there are: "
                    f"{', '.join(current)}."
                )
            current = current[part]
        elif isinstance(current, list):
            if not part.isdigit() or int(part) >= len(current):
                raise FieldError(
                    f"Field {path!r}: {'.'.join(walked) or 'the message'} is an array of {len(current)}; "
                    f"use an index 0-{max(0, len(current) - 1)}, e.g. {'.'.join([*walked, '0'])}."
                )
            current = current[int(part)]
        else:
            kind = type(current).__name__
            raise FieldError(f"Field {path!r}: {'.'.join(walked)} is a {kind}, not a message.")
        walked.append(part)
    if current is None:
        return math.nan
    if isinstance(current, bool):
        return 1.0 if current else 0.0
    if isinstance(current, int | float):
        return float(current)
    kind = "a message" if isinstance(current, Mapping) else f"a {type(current).__name__}"
    inside = f"; its fields: {', '.join(current)}" if isinstance(current, Mapping) else ""
    raise FieldError(f"Field {path!r} is {kind}, not a number{inside}.")


_UNIT_BY_PARENT = {
    "linear": "m/s",
    "angular": "rad/s",
    "position": "m",
    "translation": "m",
    "linear_acceleration": "m/s²",
    "angular_velocity": "rad/s",
    "magnetic_field": "T",
}
_UNIT_BY_NAME = {
    "linear_velocity": "m/s",
    "angular_velocity": "rad/s",
    "theta": "rad",
    "range": "m",
    "ranges": "m",
    "temperature": "°C",
    "voltage": "V",
    "current": "A",
    "percentage": "",
    "fluid_pressure": "Pa",
    "illuminance": "lx",
}


def unit_of(msg_type: str, path: str) -> str:
    """The unit of a field where the message type tells it (REP 103: SI units), else ``""``."""
    parts = [p for p in path.split(".") if not p.isdigit()]
    if not parts:
        return ""
    name = parts[-1]
    parent = parts[-2] if len(parts) > 1 else ""
    if parent in ("linear", "angular") and "accel" in ".".join(parts[:-1]):
        return "m/s²" if parent == "linear" else "rad/s²"
    if parent in _UNIT_BY_PARENT and name in ("x", "y", "z"):
        return _UNIT_BY_PARENT[parent]
    if name in _UNIT_BY_NAME:
        return _UNIT_BY_NAME[name]
    if msg_type.endswith(("turtlesim/msg/Pose", "turtlesim/Pose", "Pose2D")):
        return "m" if name in ("x", "y") else ""
    return ""


async def collect(
    client: RosbridgeClient,
    topics: Sequence[TopicFields],
    duration: float,
    on_progress: Callable[[float], Awaitable[None]] | None = None,
) -> tuple[list[Series], dict[str, int]]:
    """Every path of every topic for ``duration`` seconds; also how many messages each topic sent.

    Raises :class:`FieldError` as soon as a topic's first message lacks one of its paths. ``on_progress`` is
    told the seconds listened so far, at most every :data:`PROGRESS_EVERY` seconds, as messages arrive.
    """
    start = time.monotonic()
    end = start + duration
    series = {(t.topic, p): Series(t.topic, p, unit_of(t.msg_type, p)) for t in topics for p in t.paths}
    counts = {t.topic: 0 for t in topics}
    reported = 0.0

    async def pump(spec: TopicFields) -> None:
        nonlocal reported
        async with client.subscribe(spec.topic, spec.msg_type, max_queue=MAX_SAMPLES) as sub:
            while True:
                left = end - time.monotonic()
                if left <= 0:
                    return
                try:
                    message = await sub.get(left)
                except RequestTimeoutError:
                    return
                now = time.monotonic() - start
                if now > duration:
                    return
                counts[spec.topic] += 1
                if on_progress is not None and now - reported >= PROGRESS_EVERY:
                    reported = now
                    await on_progress(now)
                for path in spec.paths:
                    value = value_at(message, path)
                    line = series[(spec.topic, path)]
                    if len(line.values) < MAX_SAMPLES:
                        line.times.append(now)
                        line.values.append(value)
                    else:
                        line.dropped += 1

    tasks = [asyncio.create_task(pump(spec)) for spec in topics]
    try:
        for done in asyncio.as_completed(tasks):
            await done  # the first FieldError ends the collection
    finally:
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
    return list(series.values()), counts
