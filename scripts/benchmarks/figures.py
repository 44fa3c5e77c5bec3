"""The plan (how many of everything), figures and rows: medians and p90, milliseconds and MiB, verdicts."""

from __future__ import annotations

import dataclasses
import math
import statistics
from collections.abc import Sequence
from typing import Any

from benchmarks.constants import MIB

# ----------------------------------------------------------------------------------------------- the plan


@dataclasses.dataclass(frozen=True)
class Plan:
    """How many repetitions of everything; ``FULL`` stays under ~2 minutes on a 2-core machine."""

    name: str
    warmup: int  # calls per latency subject before any is timed
    rounds: int  # interleaved rounds of the latency subjects
    block: int  # calls per subject per round
    parallel_calls: int  # item 4
    concurrency_rounds: int
    messages: int  # item 5
    startup_warmup: int  # item 6: untimed spawns of each server first (page cache, .pyc files)
    startup_rounds: int  # item 6: timed spawns of each server
    memory_calls: int  # item 7
    memory_batch: int  # tool calls in flight at once while churning through memory_calls


FULL = Plan(
    name="full",
    warmup=50,
    rounds=20,
    block=20,
    parallel_calls=100,
    concurrency_rounds=2,
    messages=1000,
    startup_warmup=1,
    startup_rounds=8,
    memory_calls=10_000,
    memory_batch=50,
)
QUICK = Plan(
    name="quick",
    warmup=3,
    rounds=2,
    block=5,
    parallel_calls=10,
    concurrency_rounds=1,
    messages=100,
    startup_warmup=0,
    startup_rounds=1,
    memory_calls=200,
    memory_batch=20,
)


# -------------------------------------------------------------------------------------- figures and rows


@dataclasses.dataclass(frozen=True)
class Stats:
    """Median and p90 (nearest rank) of a set of samples, in the samples' unit."""

    n: int
    median: float
    p90: float

    @classmethod
    def of(cls, samples: Sequence[float]) -> Stats:
        if not samples:
            raise ValueError("no samples")
        ordered = sorted(samples)
        rank = max(1, math.ceil(0.9 * len(ordered)))
        return cls(n=len(ordered), median=statistics.median(ordered), p90=ordered[rank - 1])


@dataclasses.dataclass
class Row:
    """One line of the table; ``figures`` holds the raw numbers for --json."""

    item: str
    what: str
    n: int | None = None
    median: str = ""
    p90: str = ""
    versus: str = ""
    target: str = ""
    verdict: str = ""
    figures: dict[str, Any] = dataclasses.field(default_factory=dict)


def ms(seconds: float) -> str:
    """A duration for the table: two decimals of ms below 10 ms, one below 1 s, then seconds."""
    if seconds >= 10:
        return f"{seconds:.1f} s"
    if seconds >= 1:
        return f"{seconds:.2f} s"
    if seconds >= 0.01:
        return f"{seconds * 1e3:.1f} ms"
    return f"{seconds * 1e3:.2f} ms"


def mib(size: float) -> str:
    return f"{size / MIB:.1f} MiB"


def verdict(met: bool) -> str:
    return "met" if met else "**MISSED**"


def timing_row(item: str, what: str, stats: Stats, **extra: Any) -> Row:
    row = Row(item=item, what=what, n=stats.n, median=ms(stats.median), p90=ms(stats.p90), **extra)
    row.figures.update(median_s=stats.median, p90_s=stats.p90, n=stats.n)
    return row


def ratio_row(item: str, what: str, stats: Stats, floor: Stats, limit: float) -> Row:
    ratio = stats.median / floor.median
    row = timing_row(
        item,
        what,
        stats,
        versus=f"{ratio:.2f}× raw ({ms(floor.median)})",
        target=f"≤ {limit:g}× raw",
        verdict=verdict(ratio <= limit),
    )
    row.figures.update(floor_median_s=floor.median, ratio=ratio)
    return row
