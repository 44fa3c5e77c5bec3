"""The sample policy, examples/robot-policy.toml, is the README's policy block word for word (the Japanese
block the same policy), and the command loads it: the README's examples use a file that cannot rot."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

from rosbridge_mcp_server.cli import run

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "examples" / "robot-policy.toml"


def policy_block(readme: str) -> str:
    """The README's ```toml block that is the sample policy."""
    text = (ROOT / readme).read_text(encoding="utf-8")
    [block] = re.findall(r"```toml\n(# examples/robot-policy\.toml.*?)```", text, flags=re.DOTALL)
    return block


def test_the_readme_shows_the_sample_policy_file_as_it_is() -> None:
    """README.md's block is the file; README_ja.md's (comments in Japanese) is the same policy."""
    sample = SAMPLE.read_text(encoding="utf-8")
    assert policy_block("README.md") == sample
    assert tomllib.loads(policy_block("README_ja.md")) == tomllib.loads(sample)


def test_check_loads_the_sample_policy_and_names_its_rules(capsys: pytest.CaptureFixture[str]) -> None:
    """`check --policy examples/robot-policy.toml` on the Nav2 demo reads every section and is healthy."""
    assert run(["check", "--demo", "--demo-world", "nav2", "--policy", str(SAMPLE)], {}) == 0
    out = capsys.readouterr().out
    assert f"safety policy (from {SAMPLE})" in out
    for section in ("confirm = motion", "[topics]", "[velocity]", "[navigation]", "[places] dock"):
        assert section in out, (section, out)
