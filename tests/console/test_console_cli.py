"""``--console`` on the command line: the one-time URL on stderr, and the refusals before anything starts."""

from __future__ import annotations

import asyncio
import os
import re
import socket
import stat
import sys
from pathlib import Path

import pytest

from rosbridge_mcp_server.cli import run
from rosbridge_mcp_server.cli.commands import PROG
from rosbridge_mcp_server.console.address import ConsoleAddressFile

WAIT = 90.0  # a bound on an event, not a pause: a busy machine (load 20 on 2 cores) still passes


@pytest.mark.parametrize(
    ("argv", "env", "fragment"),
    [
        (["--console", "0.0.0.0:8765"], {}, "not a loopback address"),
        (["--console", "abc"], {}, "--console must be a port number"),
        ([], {"ROSBRIDGE_MCP_CONSOLE": "10.1.2.3:80"}, "ROSBRIDGE_MCP_CONSOLE: 10.1.2.3 is not a loopback"),
        (["--console-insecure"], {}, "need --console"),
        (["check", "--console", "10.1.2.3:8770"], {}, "10.1.2.3 is not a loopback address"),
        (["check", "--transport", "http", "--console", "8765"], {}, "name the same port"),
    ],
)
def test_a_bad_console_option_exits_2_with_one_line(
    argv: list[str], env: dict[str, str], fragment: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A console on a network without TLS, a bad port or a lone option: one line, exit code 2."""
    assert run(argv, env) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"{PROG}: error: ")
    assert fragment in captured.err


async def test_the_server_writes_the_console_url_on_stderr_and_serves_the_page() -> None:
    """`--demo --console 0`: a line http://127.0.0.1:PORT/#secret=..., and the page answers there."""
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosbridge_mcp_server",
        "--demo",
        "--console",
        "0",
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    assert process.stderr is not None
    assert process.stdin is not None
    try:
        url = None
        async with asyncio.timeout(WAIT):
            while url is None:
                line = (await process.stderr.readline()).decode()
                assert line, "the server ended before writing the console's URL"
                url = re.match(r"http://127\.0\.0\.1:(\d+)/#secret=[A-Za-z0-9_-]{40,}$", line.strip())
        port = int(url.group(1))
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        writer.write(f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n".encode())
        async with asyncio.timeout(WAIT):
            page = (await reader.read()).decode()
        writer.close()
        assert page.startswith("HTTP/1.1 200")
        assert "E-STOP" in page
    finally:
        process.stdin.close()
        async with asyncio.timeout(WAIT):
            stdout, _ = await process.communicate()
    assert stdout == b""
    assert process.returncode == 0


def test_a_console_on_the_mcp_listeners_port_is_refused_before_anything_listens(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """`--transport http --console 8765`: the HTTP default port twice; one line naming both flags, exit 2."""
    assert run(["--demo", "--transport", "http", "--console", "8765"], {}) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert "--console 127.0.0.1:8765 and the MCP HTTP listener (--bind 127.0.0.1:8765, the default)" in err
    assert "--console 8770" in err
    assert "#secret=" not in err


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (
            ["--transport", "http", "--console", "0", "--bind", "127.0.0.1:{port}"],
            "the MCP HTTP listener (--bind)",
        ),
        (["--console", "{port}"], "the operator console (--console)"),
    ],
)
def test_a_port_taken_by_another_program_names_the_listener_and_its_flag(
    argv: list[str], named: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A port already in use: the listener that failed and the flag that moves it, exit 2, no console URL."""
    taken = socket.socket()
    taken.bind(("127.0.0.1", 0))
    taken.listen(1)
    port = taken.getsockname()[1]
    try:
        code = run(["--demo", *(arg.format(port=port) for arg in argv)], {})
    finally:
        taken.close()
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"{named} cannot listen on 127.0.0.1:{port}" in err
    assert "#secret=" not in err


async def test_the_console_url_is_kept_in_a_file_only_the_user_can_read(tmp_path: Path) -> None:
    """Besides stderr, console-<pid>.url (0600, in a 0700 directory); `console-url` prints it while the server
    runs, and the file is gone once it stops."""
    runtime = tmp_path / "runtime"
    env = {**os.environ, "ROSBRIDGE_MCP_RUNTIME_DIR": str(runtime)}
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosbridge_mcp_server",
        "--demo",
        "--console",
        "0",
        env=env,
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    assert process.stderr is not None
    assert process.stdin is not None
    try:
        url = told = ""
        async with asyncio.timeout(WAIT):
            while not told:
                line = (await process.stderr.readline()).decode()
                assert line, "the server ended before writing the console's URL"
                if "#secret=" in line:
                    url = line.strip()
                elif line.startswith("operator console:"):
                    told = line
        kept = runtime / f"console-{process.pid}.url"
        assert str(kept) in told
        assert "console-url" in told
        kept_url, serves = kept.read_text().splitlines()
        assert kept_url == url
        assert serves.startswith("the robot at ws://127.0.0.1:"), serves
        assert stat.S_IMODE(kept.stat().st_mode) == 0o600
        assert stat.S_IMODE(runtime.stat().st_mode) == 0o700
        printed = await asyncio.create_subprocess_exec(
            sys.executable,
            "-m",
            "rosbridge_mcp_server",
            "console-url",
            env=env,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
        )
        out, _ = await asyncio.wait_for(printed.communicate(), WAIT)
        assert printed.returncode == 0
        assert out.decode().strip() == url
    finally:
        process.stdin.close()
        async with asyncio.timeout(WAIT):
            await process.communicate()
    assert process.returncode == 0
    assert not kept.exists()


def test_console_url_without_a_console_says_where_it_looked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """No console running (a stopped server's file is left behind): exit 1, the directory named, the old
    file removed."""
    runtime = tmp_path / "runtime"
    runtime.mkdir(mode=0o700)
    dead = runtime / "console-999999999.url"
    dead.write_text("http://127.0.0.1:1/#secret=old\n")
    assert run(["console-url"], {"ROSBRIDGE_MCP_RUNTIME_DIR": str(runtime)}) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    assert str(runtime) in captured.err
    assert "--console" in captured.err
    assert not dead.exists()


def test_console_url_with_two_consoles_says_which_robot_each_is_for(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two servers with consoles running (here this process and its parent, both alive): each URL is printed
    with its process and the robot it serves, so the person opens the right one."""
    runtime = tmp_path / "runtime"
    ConsoleAddressFile(runtime, os.getpid()).write(
        "http://127.0.0.1:8770/#secret=a", "the robot at ws://10.0.0.5:9090"
    )
    ConsoleAddressFile(runtime, os.getppid()).write(
        "http://127.0.0.1:8771/#secret=b", "robots arm at ws://10.0.0.6:9090, base at ws://10.0.0.7:9090"
    )
    assert run(["console-url"], {"ROSBRIDGE_MCP_RUNTIME_DIR": str(runtime)}) == 0
    lines = capsys.readouterr().out.splitlines()
    assert sorted(lines) == sorted(
        [
            f"http://127.0.0.1:8770/#secret=a  (process {os.getpid()}, the robot at ws://10.0.0.5:9090)",
            f"http://127.0.0.1:8771/#secret=b  (process {os.getppid()}, robots arm at ws://10.0.0.6:9090, "
            "base at ws://10.0.0.7:9090)",
        ]
    )
