"""Item 18: hostile recordings (issue 36) refused by ``read_recording`` within ≤ 2 s and ≤ 50 MiB of peak RSS.

Each class of bomb is written at the size the issue found it (``tests/recording_bombs.py``, the tests' own
writer) into the recording folder of the console script run as Claude Desktop runs it; ``read_recording``
is called on it in every mode, and each call is timed and the server's peak RSS (``VmHWM``, reset before
each call) compared with its RSS before. A class's row holds its slowest call and its largest growth.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.harness import (
    MIB,
    REPO,
    Context,
    Row,
    log,
    ms,
    our_server_command,
    peak_reset,
    peak_resettable,
    peak_rss,
    serve_mcp,
    verdict,
)

__all__: list[str] = []

sys.path.insert(0, str(REPO / "tests"))
import recording_bombs as bombs

#: Every mode of read_recording, with the arguments it needs.
MODES: tuple[dict[str, Any], ...] = (
    {},
    {"mode": "stats", "fields": ["/data data"]},
    {"mode": "plot", "fields": ["/data data"]},
    {"mode": "messages", "at": 0.0},
    {"mode": "map", "topics": ["/data", "/data"]},
)
SECONDS_TARGET = 2.0
GROWTH_TARGET = 50 * MIB


async def measure_recording_bombs(ctx: Context) -> list[Row]:
    """Item 18: each class of hostile MCAP file, every read_recording mode: time and peak RSS growth."""
    rows: list[Row] = []
    with tempfile.TemporaryDirectory(prefix="bench-bombs-") as folder:
        written = {name: write(Path(folder)) for name, (write, _) in bombs.BOMBS.items()}
        command = [*our_server_command(ctx.bridge.url), "--record-dir", folder]
        async with serve_mcp(command, ctx.errlog) as served:
            resettable = peak_resettable(served.process)
            for index, (name, path) in enumerate(written.items()):
                slowest, growth, refused = 0.0, 0, True
                for arguments in MODES:
                    before = served.rss()
                    if resettable:
                        peak_reset(served.process)
                    began = time.perf_counter()
                    result = await served.session.call_tool(
                        "read_recording", {"file": path.name, **arguments}
                    )
                    slowest = max(slowest, time.perf_counter() - began)
                    peak = peak_rss(served.process) if resettable else served.rss()
                    growth = max(growth, peak - before)
                    text = " ".join(getattr(block, "text", "") for block in result.content)
                    # A file whose trouble is in its messages (a schema, a JSON body) has a summary to give.
                    answered = not result.is_error and not arguments
                    worded = result.is_error and "Error executing tool" not in text
                    if not (answered or worded):
                        log.warning("item 18: %s %s answered %s", name, arguments, text[:300])
                        refused = False
                met = refused and slowest <= SECONDS_TARGET and growth <= GROWTH_TARGET
                rows.append(
                    Row(
                        f"18{chr(ord('a') + index)}",
                        f"`read_recording`, every mode, on {name} ({path.stat().st_size / 1024:.1f} kB)",
                        n=len(MODES),
                        median=ms(slowest),
                        versus=f"peak RSS {growth / MIB:+.1f} MiB; "
                        + ("refused, worded" if refused else "NOT refused"),
                        target="refused, ≤ 2 s, ≤ +50 MiB",
                        verdict=verdict(met),
                        figures={"seconds": slowest, "rss_growth": growth, "refused": refused},
                    )
                )
    return rows
