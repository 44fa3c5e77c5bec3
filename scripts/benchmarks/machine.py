"""This machine and its processes: the speed probe, what it is, CPU seconds and peak RSS of a process."""

from __future__ import annotations

import contextlib
import importlib.metadata
import math
import os
import platform
import subprocess
import time
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import psutil

from benchmarks.constants import REPO


def cpu_speed_probe() -> float:
    """Seconds for a fixed pure-Python loop (best of 5): how fast this shared machine runs right now.

    The same machine runs everything up to ~1.5x slower at some moments than at others (neighbours on the
    host); absolute figures from two runs compare only when their probes agree.
    """
    best = math.inf
    for _ in range(5):
        began = time.perf_counter()
        total = 0
        for number in range(1_000_000):
            total += number & 7
        best = min(best, time.perf_counter() - began)
    return best


def describe_machine() -> dict[str, Any]:
    """CPU model, cores, memory, OS, Python and the versions of what is being measured."""
    cpu = platform.processor()
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    versions = {}
    for package in ("mcp", "websockets", "roslibpy", "pydantic", "rosbridge-mcp-server"):
        try:
            versions[package] = importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            versions[package] = "not installed"
    commit = "unknown"
    with contextlib.suppress(OSError, subprocess.SubprocessError):
        found = subprocess.run(
            ["git", "-C", str(REPO), "describe", "--always", "--dirty"],
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        )
        commit = found.stdout.strip()
    return {
        "cpu": cpu or "unknown",
        "cores": os.cpu_count(),
        "memory_gib": round(psutil.virtual_memory().total / 2**30, 1),
        "os": platform.platform(),
        "python": f"{platform.python_implementation()} {platform.python_version()}",
        "load_average_at_start": [round(load, 2) for load in os.getloadavg()],
        "speed_probe_ms_at_start": round(cpu_speed_probe() * 1e3, 1),
        "versions": versions,
        "commit": commit,
    }


def cpu_seconds(process: psutil.Process | None) -> float:
    """CPU time a process has had so far, every thread summed (0 for one we cannot see, e.g. a remote bridge).

    Linux's per-thread schedstat counts nanoseconds; elsewhere psutil's user + system time, which the kernel
    counts in 10 ms ticks (good enough over many blocks for the slow subjects, not for the floor).
    """
    if process is None:
        return 0.0
    try:
        nanoseconds = 0
        for task in os.scandir(f"/proc/{process.pid}/task"):
            with open(f"{task.path}/schedstat") as stat:
                nanoseconds += int(stat.read().split()[0])
        return nanoseconds / 1e9
    except (OSError, ValueError, IndexError):
        times = process.cpu_times()
        return float(times.user + times.system)


async def wall_time(action: Callable[[], Awaitable[object]]) -> float:
    began = time.perf_counter()
    await action()
    return time.perf_counter() - began


def peak_resettable(process: psutil.Process) -> bool:
    return Path(f"/proc/{process.pid}/clear_refs").exists() and Path(f"/proc/{process.pid}/status").exists()


def peak_reset(process: psutil.Process) -> None:
    """Reset the process's peak RSS to its current RSS (Linux ≥ 4.0: ``5`` into ``clear_refs``)."""
    Path(f"/proc/{process.pid}/clear_refs").write_text("5")


def peak_rss(process: psutil.Process) -> int:
    """The process's peak RSS since the last reset (``VmHWM``), in bytes."""
    for line in Path(f"/proc/{process.pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
    raise RuntimeError("no VmHWM in /proc/PID/status")
