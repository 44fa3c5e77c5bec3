"""``python -m benchmarks`` (from ``scripts/``): the same as ``scripts/bench.py``."""

from __future__ import annotations

import sys

from benchmarks.run import main

sys.exit(main())
