"""Benchmark rosbridge-mcp-server: a thin entry that runs the ``benchmarks`` package next to this file.

    uv run python scripts/bench.py [--url ws://…] [--quick] [--only ITEMS] [--json FILE]

The measurements, the harness and what each row means are in ``scripts/benchmarks/`` (its ``__init__``
lists the items); ``docs/performance.md`` holds the figures.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from benchmarks.run import main

if __name__ == "__main__":
    sys.exit(main())
