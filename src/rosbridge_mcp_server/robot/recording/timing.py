"""Rates and gaps of one topic from its message times (nanoseconds). Pure."""

from __future__ import annotations

import itertools
import statistics
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["Gap", "TopicTiming", "timing_of"]

#: A pause counts as a gap when it is this many typical periods long, and at least MIN_GAP seconds.
GAP_PERIODS = 3.0
MIN_GAP = 0.25
MAX_GAPS = 3


@dataclass(frozen=True)
class Gap:
    """A pause: when it began (seconds from the recording's start) and how long it lasted."""

    at: float
    seconds: float


@dataclass(frozen=True)
class TopicTiming:
    """Count, span, mean rate and the longest pauses of one topic."""

    count: int
    first: float | None  # seconds from the recording's start
    last: float | None
    rate_hz: float | None
    gaps: tuple[Gap, ...]


def timing_of(times_ns: Sequence[int], start_ns: int) -> TopicTiming:
    """``times_ns`` in order of arrival; gaps are pauses of over 3 typical periods (and 0.25 s), longest
    first, at most 3."""
    count = len(times_ns)
    if count == 0:
        return TopicTiming(0, None, None, None, ())
    ordered = sorted(times_ns)
    first = (ordered[0] - start_ns) / 1e9
    last = (ordered[-1] - start_ns) / 1e9
    span = last - first
    rate = (count - 1) / span if count > 1 and span > 0 else None
    gaps: list[Gap] = []
    if count > 2:
        intervals = [(b - a) / 1e9 for a, b in itertools.pairwise(ordered)]
        typical = statistics.median(intervals)
        limit = max(MIN_GAP, GAP_PERIODS * typical)
        found = [
            Gap(round((ordered[i] - start_ns) / 1e9, 3), round(d, 3))
            for i, d in enumerate(intervals)
            if d > limit
        ]
        gaps = sorted(found, key=lambda gap: gap.seconds, reverse=True)[:MAX_GAPS]
    return TopicTiming(
        count, round(first, 3), round(last, 3), None if rate is None else round(rate, 2), tuple(gaps)
    )
