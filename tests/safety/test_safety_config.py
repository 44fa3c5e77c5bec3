"""Safety and connection-security settings from flags and environment; bad ones stop the start with exit 2."""

from __future__ import annotations

import io
import logging
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from rosbridge_mcp_server.cli import PROG, run
from rosbridge_mcp_server.cli.check import run_check
from rosbridge_mcp_server.config import Config, ConfigError, load_config, plain_text_warning
from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot


@pytest.fixture(autouse=True)
def _restore_logging() -> Iterator[None]:
    """run() installs its stderr handler on the root logger; take it away again after each test."""
    root = logging.getLogger()
    handlers, level = list(root.handlers), root.level
    yield
    root.handlers[:] = handlers
    root.setLevel(level)


def policy_file(tmp_path: Path, text: str) -> str:
    path = tmp_path / "policy.toml"
    path.write_text(text, encoding="utf-8")
    return str(path)


def test_the_policy_comes_from_the_flag_before_the_environment(tmp_path: Path) -> None:
    """--policy beats ROSBRIDGE_MCP_POLICY, like every other flag."""
    flag = policy_file(tmp_path, 'confirm = "always"')
    other = tmp_path / "other.toml"
    other.write_text('confirm = "motion"', encoding="utf-8")
    assert load_config({"ROSBRIDGE_MCP_POLICY": str(other)}, policy=flag).policy.confirm == "always"
    assert load_config({"ROSBRIDGE_MCP_POLICY": str(other)}).policy.confirm == "motion"
    assert not load_config({}).policy.restricts


@pytest.mark.parametrize(("env", "flag"), [({"ROSBRIDGE_MCP_READ_ONLY": "1"}, False), ({}, True)])
def test_read_only_from_flag_or_environment_overrides_the_policy_file(
    tmp_path: Path, env: dict[str, str], flag: bool
) -> None:
    """--read-only / ROSBRIDGE_MCP_READ_ONLY=1 make even a permissive policy read-only."""
    env = {**env, "ROSBRIDGE_MCP_POLICY": policy_file(tmp_path, "read_only = false")}
    assert load_config(env, read_only=flag).policy.read_only


def test_a_read_only_value_that_is_not_a_boolean_is_an_error() -> None:
    """ROSBRIDGE_MCP_READ_ONLY=maybe is not quietly false."""
    with pytest.raises(ConfigError, match=r"ROSBRIDGE_MCP_READ_ONLY must be 1 or 0"):
        load_config({"ROSBRIDGE_MCP_READ_ONLY": "maybe"})


def test_headers_come_from_flags_or_one_per_line_from_the_environment() -> None:
    """Extra handshake headers, e.g. Authorization for a bridge behind a proxy."""
    env = {"ROSBRIDGE_HEADERS": "Authorization: Bearer abc\nX-Robot:  r2 \n"}
    assert load_config(env).headers == (("Authorization", "Bearer abc"), ("X-Robot", "r2"))
    assert load_config(env, headers=["X-Only: 1"]).headers == (("X-Only", "1"),)


def test_a_bad_header_is_an_error_that_does_not_repeat_its_value() -> None:
    """Header values are secrets: the error names the header, never the token."""
    with pytest.raises(ConfigError) as caught:
        load_config({}, headers=["Authorization Bearer secret-token"])
    assert "secret-token" not in str(caught.value)
    assert "'Name: value'" in str(caught.value)
    with pytest.raises(ConfigError, match=r"header Authorization has an empty"):
        load_config({}, headers=["Authorization:"])


def test_the_headers_never_show_in_the_configs_repr() -> None:
    """A Config logged for debugging does not leak a token."""
    config = load_config({}, headers=["Authorization: Bearer secret-token"])
    assert "secret-token" not in repr(config)


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"url": "ws://robot:9090", "ca_file": "CA"}, "use a wss:// URL"),
        ({"url": "wss://robot:9090", "ca_file": "/nonexistent/ca.pem"}, "does not exist"),
        ({"url": "wss://robot:9090", "client_key": "KEY"}, "needs --client-cert"),
    ],
)
def test_tls_files_are_checked_at_start(tmp_path: Path, kwargs: dict[str, str], fragment: str) -> None:
    """A CA file for a ws:// URL, a missing file or a key without its certificate stop the start."""
    existing = tmp_path / "file.pem"
    existing.write_text("not a certificate", encoding="utf-8")
    resolved = {k: (str(existing) if v in ("CA", "KEY") else v) for k, v in kwargs.items()}
    with pytest.raises(ConfigError, match=fragment):
        load_config({}, **resolved)


def test_a_ca_file_that_is_not_a_certificate_is_an_error_naming_it(tmp_path: Path) -> None:
    """A file that exists but holds no certificate is a start-up error, not a failed handshake later."""
    bad = tmp_path / "ca.pem"
    bad.write_text("not a certificate", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"CA file .*ca\.pem.* cannot be loaded"):
        load_config({"ROSBRIDGE_CA_FILE": str(bad), "ROSBRIDGE_URL": "wss://robot:9090"})


@pytest.mark.parametrize(
    ("url", "warns"),
    [
        ("ws://192.168.1.20:9090", True),
        ("ws://robot.local:9090", True),
        ("wss://192.168.1.20:9090", False),
        ("ws://localhost:9090", False),
        ("ws://127.0.0.1:9090", False),
        ("ws://[::1]:9090", False),
    ],
)
def test_plain_ws_to_another_machine_is_warned_about(url: str, warns: bool) -> None:
    """Unencrypted robot commands over a network deserve one warning; loopback and wss do not."""
    assert (plain_text_warning(url) is not None) is warns


def test_serving_plain_ws_to_another_machine_logs_one_warning(capsys: pytest.CaptureFixture[str]) -> None:
    """At start, with stdin already closed, the server warns once about ws:// to a non-loopback host."""
    done = subprocess.run(
        [sys.executable, "-m", "rosbridge_mcp_server", "--url", "ws://192.0.2.1:9090"],
        input="",
        capture_output=True,
        text=True,
        timeout=90,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stderr.count("plain ws://") == 1
    assert done.stdout == ""


def test_a_misspelt_policy_key_is_exit_2_with_one_line_naming_it(tmp_path: Path) -> None:
    """The server does not start with a policy it cannot read fully; the line names the key and the fix."""
    path = policy_file(tmp_path, "[velocity]\nmax_linaer = 0.5\n")
    done = subprocess.run(
        [sys.executable, "-m", "rosbridge_mcp_server", "--policy", path],
        capture_output=True,
        text=True,
        timeout=90,
        check=False,
    )
    assert done.returncode == 2
    assert done.stdout == ""
    assert done.stderr.count("\n") == 1
    assert done.stderr.startswith(f"{PROG}: error: ")
    assert "unknown key [velocity] 'max_linaer'; did you mean 'max_linear'?" in done.stderr


def test_an_audit_log_that_cannot_be_opened_is_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A missing directory for the audit file stops the start: auditing was asked for."""
    assert run(["--demo", "--audit-log", str(tmp_path / "no" / "such" / "audit.jsonl")], {}) == 2
    assert "cannot open" in capsys.readouterr().err


async def test_check_prints_the_policy_in_force(sim_ros2: SimulatedRobot) -> None:
    """`check` shows which safety policy the server would run with."""
    policy = parse_policy(
        {"confirm": "motion", "velocity": {"max_linear": 0.3}, "topics": {"deny": ["/rosout"]}},
        where="robot.toml",
    )
    out = io.StringIO()
    assert await run_check(Config(url=sim_ros2.url, policy=policy), out) == 0
    text = out.getvalue()
    assert "safety policy (from robot.toml):" in text
    assert "confirm = motion" in text
    assert "linear ≤ 0.3 m/s" in text
    assert "[topics] allow everything; deny /rosout" in text


def test_check_shows_read_only_and_the_absence_of_a_policy(capsys: pytest.CaptureFixture[str]) -> None:
    """An operator sees at a glance whether anything is restricted."""
    assert run(["check", "--demo", "--read-only"], {}) == 0
    assert "read_only: only reading tools" in capsys.readouterr().out
    assert run(["check", "--demo"], {}) == 0
    assert "safety no restrictions" in capsys.readouterr().out


def test_a_header_value_never_reaches_the_log_even_at_debug(capsys: pytest.CaptureFixture[str]) -> None:
    """websockets logs every handshake header at DEBUG; the token is replaced by *** in those lines."""
    env = {"ROSBRIDGE_HEADERS": "Authorization: Bearer s3cret-t0ken"}
    assert run(["check", "--demo", "--log-level", "DEBUG"], env) == 0
    captured = capsys.readouterr()
    assert "s3cret-t0ken" not in captured.err + captured.out
    assert "Authorization: ***" in captured.err
