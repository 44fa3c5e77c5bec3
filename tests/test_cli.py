"""The command line: bad values exit 2 with one line; `check` diagnoses a bridge, or its absence."""

from __future__ import annotations

import asyncio
import io
import logging
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from rosbridge_mcp_server.catalogue import TOOL_GROUPS
from rosbridge_mcp_server.cli import PROG, run
from rosbridge_mcp_server.cli.check import run_check, unreachable_advice
from rosbridge_mcp_server.cli.commands import configure_logging
from rosbridge_mcp_server.client.ordering import call_ordering
from rosbridge_mcp_server.config import Config
from rosbridge_mcp_server.safety.policy import NameRules, Policy
from rosbridge_mcp_server.sim import SimulatedRobot


@pytest.fixture(autouse=True)
def _restore_logging() -> Iterator[None]:
    """run() installs its stderr handler on the root logger; take it away again after each test."""
    root = logging.getLogger()
    handlers, level = list(root.handlers), root.level
    package = logging.getLogger("rosbridge_mcp_server")
    package_level = package.level
    yield
    root.handlers[:] = handlers
    root.setLevel(level)
    package.setLevel(package_level)


def _free_port() -> int:
    """A loopback port with nothing listening on it (bound, then released)."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
    return port


@pytest.mark.parametrize(
    ("argv", "env", "fragment"),
    [
        (["--port", "abc"], {}, "--port must be a port number between 1 and 65535, not 'abc'"),
        (["--port", "0"], {}, "--port must be a port number between 1 and 65535, not 0"),
        (["--port", "70000"], {}, "not 70000"),
        (["--url", "http://x"], {}, "--url must start with ws:// or wss://"),
        ([], {"ROSBRIDGE_PORT": "abc"}, "ROSBRIDGE_PORT must be a port number"),
        (["--timeout", "-3"], {}, "--timeout must be more than 0"),
        (["--no-such-flag"], {}, "unrecognized arguments: --no-such-flag"),
        (["--demo-dialect", "ros3"], {}, "invalid choice: 'ros3'"),
        (["--demo-world", "mars"], {}, "invalid choice: 'mars'"),
        (["--demo-robots", "2"], {}, "--demo-robots must be 1-100 and more than 1 needs --demo-world nav2"),
        (["--demo", "--demo-fault", "scan-stopped"], {}, "--demo-fault needs --demo-world nav2"),
        (
            ["--demo", "--demo-world", "nav2", "--demo-fault", "wheels-off"],
            {},
            "--demo-fault: unknown fault wheels-off; the faults are scan-stopped, tf-stale",
        ),
        (
            [
                "--demo",
                "--demo-world",
                "nav2",
                "--demo-dialect",
                "ros1",
                "--demo-fault",
                "controller-inactive",
            ],
            {},
            "--demo-fault: controller-inactive needs ROS 2",
        ),
        (
            ["--demo", "--demo-world", "arm", "--demo-fault", "scan-stopped"],
            {},
            "--demo-fault: unknown arm fault scan-stopped; choose from arm-controller-inactive",
        ),
        (["check", "--port", "abc"], {}, "--port must be a port number"),
    ],
)
def test_bad_command_lines_exit_2_with_one_line_on_stderr(
    argv: list[str], env: dict[str, str], fragment: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A bad flag or environment value is one line on stderr, exit code 2, and nothing on stdout."""
    assert run(argv, env) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"{PROG}: error: ")
    assert fragment in captured.err
    assert captured.err.count("\n") == 1


def test_the_console_module_reports_a_bad_port_without_a_traceback() -> None:
    """`python -m rosbridge_mcp_server --port abc` exits 2 with one line, not a traceback."""
    done = subprocess.run(
        [sys.executable, "-m", "rosbridge_mcp_server", "--port", "abc"],
        capture_output=True,
        text=True,
        timeout=30,
        check=False,
    )
    assert done.returncode == 2
    assert done.stdout == ""
    assert (
        done.stderr.strip() == f"{PROG}: error: --port must be a port number between 1 and 65535, not 'abc'"
    )


def test_check_into_a_pipe_closed_early_ends_without_a_traceback() -> None:
    """`check --demo | head -1`: the first line arrives, then the command stops quietly as the pipe closes."""
    process = subprocess.Popen(
        [sys.executable, "-m", "rosbridge_mcp_server", "check", "--demo"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert process.stdout is not None
    assert process.stderr is not None
    first = process.stdout.readline()
    process.stdout.close()
    try:
        errors = process.stderr.read()
        code = process.wait(timeout=30)
    finally:
        process.kill()
        process.stderr.close()
    assert first.startswith(f"{PROG} ")
    assert "Traceback" not in errors, errors
    assert code == 1


def test_check_with_nothing_listening_says_what_to_try_and_exits_1(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """`check` against a closed port reports the failure, the fixes to try, and exit code 1."""
    port = _free_port()
    assert run(["check", "--host", "127.0.0.1", "--port", str(port)], {}) == 1
    out = capsys.readouterr().out
    assert f"cannot reach rosbridge at ws://127.0.0.1:{port}" in out
    assert f"Nothing listens on 127.0.0.1:{port}" in out
    assert "rosbridge_websocket_launch.xml" in out
    assert "firewall" in out
    assert "ws:// versus wss://" in out


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_check_against_a_robot_reports_version_features_and_counts(dialect: str) -> None:
    """`check` names the ROS version and distro, rosapi's answer and the graph's size, and exits 0."""
    async with SimulatedRobot(dialect=dialect, port=0) as robot:  # type: ignore[arg-type]
        out = io.StringIO()
        code = await run_check(Config(url=robot.url), out)
    text = out.getvalue()
    assert code == 0, text
    assert f"rosbridge reachable at {robot.url}" in text
    assert ("ROS 2 (jazzy)" if dialect == "ros2" else "ROS 1") in text
    assert "rosapi answers" in text
    if dialect == "ros2":
        assert "actions: native action ops" in text
        assert "[ok  ] messages: a geometry_msgs/msg/Twist is checked before it is published" in text
        assert "action types: known (/fibonacci is example_interfaces/action/Fibonacci)" in text
    else:
        assert "actions: over actionlib topics" in text
        assert "no timeout field" in text
        assert "[ok  ] messages: a geometry_msgs/Twist is checked before it is published" in text
    assert "[ok  ] concurrency: calls on one connection run side by side (measured" in text
    if dialect == "ros2":
        assert "implementation: answers like rosbridge_suite" in text
        assert "cancel path: a goal publish_action started is cancelled on the main connection" in text
    assert "Healthy" in text
    counts = next(line for line in text.splitlines() if "topics," in line)
    topics = int(counts.split("]", 1)[1].split()[0])
    assert topics > 0
    assert counts.endswith(", 1 action server")


async def test_check_notes_an_in_order_humble_bridge() -> None:
    """Against a Humble-like bridge, `check` says calls may block each other and how the server copes."""
    async with SimulatedRobot(dialect="ros2", in_order=True, port=0) as robot:
        out = io.StringIO()
        code = await run_check(Config(url=robot.url), out)
    assert code == 0
    assert "ROS 2 (humble)" in out.getvalue()
    assert "[ok  ] concurrency: a slow service call holds up later calls on its connection" in out.getvalue()


def test_check_demo_runs_against_the_built_in_robot(capsys: pytest.CaptureFixture[str]) -> None:
    """`check --demo` starts the simulated robot and finds it healthy."""
    assert run(["check", "--demo"], {}) == 0
    out = capsys.readouterr().out
    assert "demo mode: this is the built-in simulated ROS 2 robot" in out
    assert "Healthy" in out


def test_check_demo_runs_against_the_nav2_world(capsys: pytest.CaptureFixture[str]) -> None:
    """`check --demo --demo-world nav2` starts the Nav2-scale robot and finds it healthy."""
    assert run(["check", "--demo", "--demo-world", "nav2"], {}) == 0
    assert "Healthy" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("url", "reason", "first"),
    [
        (
            "ws://robot:9090",
            "[Errno 111] Connect call failed ('10.0.0.2', 9090)",
            "Nothing listens on robot:9090",
        ),
        ("ws://robt:9090", "[Errno -2] Name or service not known", "The host name 'robt' does not resolve"),
        ("ws://robot:9090", "timed out during opening handshake", "robot:9090 did not answer in time"),
        ("wss://robot:9090", "", "The TLS handshake failed: if rosbridge runs without TLS, use ws://"),
        (
            "ws://robot:9090/bridge",
            "InvalidStatus: server rejected WebSocket connection: HTTP 404",
            "Something at robot:9090 answers HTTP but refused the WebSocket upgrade",
        ),
    ],
)
def test_unreachable_advice_puts_the_likely_cause_first(url: str, reason: str, first: str) -> None:
    """The first suggestion matches the failure; the general checklist follows."""
    advice = unreachable_advice(url, reason)
    assert advice[0].startswith(first)
    assert any("firewall" in line for line in advice)


async def test_check_of_a_plain_bridge_over_wss_suggests_ws(sim_ros2: SimulatedRobot) -> None:
    """Asking a plain ws:// bridge for TLS fails, and check says to use ws:// instead."""
    out = io.StringIO()
    code = await run_check(Config(url=sim_ros2.url.replace("ws://", "wss://"), connect_timeout=3.0), out)
    assert code == 1
    assert "use ws:// instead of wss://" in out.getvalue()


async def test_check_does_not_believe_a_bridge_node_that_says_its_calls_are_threaded() -> None:
    """The ordering is measured: a /rosbridge_websocket node claiming threaded calls on an in-order bridge (it
    may be another bridge on the graph) changes nothing; each call keeps a connection of its own."""
    async with SimulatedRobot(dialect="ros2", in_order=True, port=0) as robot:
        robot.bridge.world.params["/rosbridge_websocket:call_services_in_new_thread"] = True
        out = io.StringIO()
        code = await run_check(Config(url=robot.url), out)
    assert code == 0, out.getvalue()
    assert "[ok  ] concurrency: a slow service call holds up later calls on its connection" in out.getvalue()


async def test_check_leaves_no_service_behind_on_a_busy_bridge() -> None:
    """check's probe service is gone after check, also where the bridge drops frames unhandled at a close."""
    robot = SimulatedRobot(dialect="ros2", in_order=True, distro="kilted", rosapi="2.1.0", port=0)
    async with robot:
        robot.bridge.incoming_delay = 0.05
        queued = await call_ordering(robot.url, 2, timeout=10.0)
        left = [name for name in robot.graph.services if name.startswith("/rosbridge_mcp_check_")]
    assert queued
    assert left == []


def test_help_names_both_commands_and_the_tool_groups(capsys: pytest.CaptureFixture[str]) -> None:
    """--help shows that `check` exists and what each --tools group holds (original comes with stop_robot):
    every group of the catalogue, navigation and safety too."""
    with pytest.raises(SystemExit) as exited:
        run(["--help"], {})
    assert exited.value.code == 0
    shown = " ".join(capsys.readouterr().out.split())
    assert f"{PROG} check [options]" in shown
    assert "check diagnoses the connection" in shown
    assert "original (the first eight, with stop_robot whenever a tool acts)" in shown
    assert "view (pictures: map, scan, charts)" in shown
    assert "navigation (navigate_to)" in shown
    assert "safety (stop_robot)" in shown
    for group in TOOL_GROUPS:
        assert f" {group} (" in shown, group


async def test_check_warns_about_policy_names_the_robot_does_not_have() -> None:
    """A policy allowing only /cmd_vel and /navigate_to_pose on the turtle: check says every motion would be
    refused and names what is there; a policy naming what exists gets no warning."""
    absent = Policy(topics=NameRules(allow=("/cmd_vel",)), actions=NameRules(allow=("/navigate_to_pose",)))
    present = Policy(topics=NameRules(allow=("/turtle1/*",)), actions=NameRules(allow=("/fibonacci",)))
    async with SimulatedRobot(port=0) as robot:
        warned, fine = io.StringIO(), io.StringIO()
        code = await run_check(Config(url=robot.url, policy=absent), warned)
        assert await run_check(Config(url=robot.url, policy=present), fine) == 0
    text = warned.getvalue()
    assert code == 0, text
    assert "[warn] policy [topics] allow '/cmd_vel' matches no topic on this robot" in text
    assert "Did you mean /turtle1/cmd_vel?" in text
    assert "[warn] policy [actions] allow '/navigate_to_pose' matches no action on this robot" in text
    assert "see the warn lines about the policy" in text
    assert "[warn]" not in fine.getvalue()


async def test_check_takes_the_fleet_flags_and_checks_every_robot(
    make_sim: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    """`check --robot a=... --robot b=...`: a section per robot, exit 0 when both are healthy, 1 when one is
    down (the healthy one still reported)."""
    first, second = await make_sim(dialect="ros2"), await make_sim(dialect="ros1")
    argv = ["check", "--robot", f"base={first.url}", "--robot", f"arm={second.url}", "--timeout", "5"]
    assert await asyncio.to_thread(run, argv, {}) == 0
    out = capsys.readouterr().out
    assert f"== robot base ({first.url}) ==" in out
    assert f"== robot arm ({second.url}) ==" in out
    assert out.count("Healthy") == 2
    assert "checked 2 robots\n" in out

    await second.stop()
    assert await asyncio.to_thread(run, argv, {}) == 1
    out = capsys.readouterr().out
    base, arm = out.split("== robot arm", 1)
    assert "Healthy" in base
    assert "Nothing listens on" in arm
    assert "at least one is not healthy" in arm


def test_check_takes_a_robots_file_and_the_servers_other_flags(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A server's whole command line, transport and console flags included, is a valid `check` command line;
    a fleet file's robots are each checked (here none answers: exit 1, both named)."""
    ports = []
    for _ in range(2):
        with socket.socket() as probe:
            probe.bind(("127.0.0.1", 0))
            ports.append(probe.getsockname()[1])
    fleet = tmp_path / "fleet.toml"
    fleet.write_text(
        f'[robots.base]\nurl = "ws://127.0.0.1:{ports[0]}"\n[robots.arm]\nurl = "ws://127.0.0.1:{ports[1]}"\n'
    )
    argv = ["check", "--robots", str(fleet), "--transport", "http", "--bind", "127.0.0.1:8765"]
    argv += ["--console", "8770", "--timeout", "2"]
    assert run(argv, {}) == 1
    out = capsys.readouterr().out
    assert "== robot base" in out
    assert "== robot arm" in out


def test_demo_with_robots_says_how_to_try_a_fleet_on_simulated_robots(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """--demo with --robot: exit 2, and the line says how to run a fleet of simulated robots instead."""
    assert run(["check", "--demo", "--robot", "a=ws://127.0.0.1:9091"], {}) == 2
    err = capsys.readouterr().err
    assert "rosbridge-sim-robot --port 9091" in err
    assert "--demo-robots 2" in err


def test_the_commands_that_do_not_serve_start_without_the_mcp_sdk() -> None:
    """`check`, `console-url`, `--help` and a refused command line import no MCP SDK (about a second of CPU at
    every start); the serving command imports it when it serves."""
    code = (
        "import sys, rosbridge_mcp_server.cli.commands;"
        "print(sorted(m for m in sys.modules if m.split('.')[0] == 'mcp'))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=30, check=True
    )
    assert done.stdout.strip() == "[]"


def test_the_console_script_pauses_the_collector_before_it_imports_the_command() -> None:
    """Importing the package whose ``main`` is the console script loads nothing else of ours, nor pydantic or
    the SDK: ``main`` turns the collector off before the start's imports (``cli/collector.py``)."""
    code = (
        "import sys, rosbridge_mcp_server.cli;"
        "print(sorted(m for m in sys.modules if m.startswith(('rosbridge_mcp_server', 'pydantic', 'mcp'))))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=30, check=True
    )
    assert done.stdout.split() == [
        "['rosbridge_mcp_server',",
        "'rosbridge_mcp_server.cli',",
        "'rosbridge_mcp_server.cli.collector']",
    ]


def test_a_log_message_quoting_robot_text_stays_one_line_of_ours() -> None:
    """A message quoting what a bridge or a caller wrote (a newline and a forged line, an ANSI sequence) is
    one escaped line on stderr, and a megabyte of it is cut with the cut said."""
    stream = io.StringIO()
    ours = logging.getLogger("rosbridge_mcp_server")
    root = logging.getLogger()
    levels = (root.level, ours.level)
    configure_logging("INFO", stream)
    try:
        log = logging.getLogger("rosbridge_mcp_server.client")
        log.warning("the bridge refused %s: %s", "publish:/x:1", "no\n2026-01-01 ERROR forged\x1b[2J")
        log.warning("bridge status: %s", "x" * 1_000_000)
    finally:
        for handler in [h for h in root.handlers if h.get_name() == PROG]:
            root.removeHandler(handler)
        root.setLevel(levels[0])
        ours.setLevel(levels[1])
    lines = stream.getvalue().splitlines()
    assert len(lines) == 2, lines
    assert lines[0].endswith("the bridge refused publish:/x:1: no\\n2026-01-01 ERROR forged\\x1b[2J")
    assert lines[1].endswith("… (1,000,015 characters)")
    assert len(lines[1]) < 10_200
