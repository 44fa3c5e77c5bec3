"""The safety seam, the acting layer and the safety package each import first, in a fresh interpreter."""

from __future__ import annotations

import subprocess
import sys

import pytest


@pytest.mark.parametrize(
    "module",
    [
        "rosbridge_mcp_server.robot.acting",
        "rosbridge_mcp_server.robot.seam",
        "rosbridge_mcp_server.safety",
        "rosbridge_mcp_server.safety.guard",
    ],
)
def test_the_module_imports_first_in_a_fresh_interpreter(module: str) -> None:
    """No import cycle bites whichever of them a program imports first."""
    done = subprocess.run(
        [sys.executable, "-c", f"import {module}"], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 0, done.stderr
