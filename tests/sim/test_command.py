"""The standalone command: serves until SIGTERM / Ctrl-C and exits 0; a bad flag is one line and exit 2."""

from __future__ import annotations

import asyncio
import re
import signal
import sys

import pytest
from rawclient import RawClient

from rosbridge_mcp_server.sim import SimulatedRobot

COMMAND = [sys.executable, "-m", "rosbridge_mcp_server.sim"]


async def _start(*args: str) -> tuple[asyncio.subprocess.Process, str]:
    process = await asyncio.create_subprocess_exec(
        *COMMAND, *args, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE
    )
    assert process.stderr is not None
    try:
        async with asyncio.timeout(20):
            while True:
                line = (await process.stderr.readline()).decode()
                assert line, "the command ended before serving"
                found = re.search(r"serving rosbridge v2 on (ws://\S+)", line)
                if found:
                    return process, found.group(1)
    except BaseException:
        # Never leave a server running behind a failed test.
        if process.returncode is None:
            process.kill()
            await process.wait()
        raise


@pytest.mark.parametrize(("sig", "dialect"), [(signal.SIGTERM, "ros1"), (signal.SIGINT, "ros2")])
async def test_command_serves_the_robot_and_stops_cleanly_on_a_signal(
    sig: signal.Signals, dialect: str
) -> None:
    """python -m rosbridge_mcp_server.sim --port 0 serves; SIGTERM or SIGINT ends it with exit code 0."""
    process, url = await _start("--port", "0", "--dialect", dialect, "--log-level", "INFO")
    try:
        async with await RawClient.open(url) as client:
            assert (await client.values("/add_two_ints", {"a": 1, "b": 2})) == {"sum": 3}
        process.send_signal(sig)
        stdout, _ = await asyncio.wait_for(process.communicate(), 20)
    finally:
        if process.returncode is None:
            process.kill()
            await process.wait()
    assert process.returncode == 0
    assert stdout == b""


@pytest.mark.parametrize(
    "args",
    [
        ["--port", "99999"],
        ["--dialect", "ros3"],
        ["--no-such-flag"],
        ["--dialect", "ros1", "--in-order"],
        ["--action-step", "0"],
        ["--slow-service-seconds", "-1"],
        ["--camera-size", "big"],
        ["--dialect", "ros1", "--rosapi", "2.1.0"],
        ["--dialect", "ros1", "--distro", "jazzy"],
        ["--distro", "iron-ish"],
        ["--rosapi", "1.0"],
        ["--rosapi-latency", "-1"],
        ["--rosapi-latency", "0.005,x"],
        ["--world", "mars"],
        ["--robots", "2"],
        ["--world", "nav2", "--robots", "0"],
        ["--dialect", "ros1", "--server", "rs"],
        ["--server", "rs", "--in-order"],
        ["--server", "rust"],
        ["--fault", "scan-stopped"],
        ["--world", "nav2", "--fault", "wheels-off"],
        ["--world", "nav2", "--dialect", "ros1", "--fault", "controller-inactive"],
    ],
)
async def test_a_bad_flag_is_one_line_on_stderr_and_exit_code_2(args: list[str]) -> None:
    """Bad flags never start a server: one line of explanation, exit status 2."""
    process = await asyncio.create_subprocess_exec(
        *COMMAND, *args, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE
    )
    stdout, stderr = await asyncio.wait_for(process.communicate(), 20)
    assert process.returncode == 2
    assert stdout == b""
    assert len(stderr.decode().strip().splitlines()) == 1
    assert "error" in stderr.decode()


async def test_a_port_in_use_is_one_line_and_exit_code_1(sim_ros2: SimulatedRobot) -> None:
    """Serving on a port that is taken fails with one line naming the address, not a traceback."""
    process = await asyncio.create_subprocess_exec(
        *COMMAND, "--port", str(sim_ros2.port), stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE
    )
    stdout, stderr = await asyncio.wait_for(process.communicate(), 20)
    assert process.returncode == 1
    assert stdout == b""
    assert f"cannot serve on 127.0.0.1:{sim_ros2.port}" in stderr.decode()
    assert "Traceback" not in stderr.decode()


async def test_command_serves_a_bridge_like_the_real_2_1_0_on_kilted() -> None:
    """--in-order --distro kilted --rosapi 2.1.0: the distro is kilted, TypeDef fields are underscored."""
    process, url = await _start(
        "--port",
        "0",
        "--in-order",
        "--distro",
        "kilted",
        "--rosapi",
        "2.1.0",
        "--rosapi-latency",
        "0.001,0.002",
    )
    try:
        async with await RawClient.open(url) as client:
            version = await client.values("/rosapi/get_ros_version")
            details = await client.values("/rosapi/message_details", {"type": "geometry_msgs/msg/Twist"})
            action_type = await client.call("/rosapi/action_type", {"action": "/fibonacci"})
        process.send_signal(signal.SIGTERM)
        await asyncio.wait_for(process.communicate(), 20)
    finally:
        if process.returncode is None:
            process.kill()
            await process.wait()
    assert version == {"version": 2, "distro": "kilted"}
    assert details["typedefs"][0]["fieldnames"] == ["_linear", "_angular"]
    assert action_type["result"] is False


async def test_command_serves_a_bridge_like_rosbridge_server_rs() -> None:
    """--server rs: an unknown op is answered with an error status naming it and carrying its id."""
    process, url = await _start("--port", "0", "--server", "rs")
    try:
        async with await RawClient.open(url) as client:
            await client.send({"op": "bogus_op", "id": "bg"})
            status = await client.reply("bg")
        process.send_signal(signal.SIGTERM)
        await asyncio.wait_for(process.communicate(), 20)
    finally:
        if process.returncode is None:
            process.kill()
            await process.wait()
    assert status == {"op": "status", "level": "error", "msg": "unknown operation: bogus_op", "id": "bg"}
