"""End to end: the real command on stdio with --demo; stdout carries JSON-RPC and nothing else."""

from __future__ import annotations

import asyncio
import json
import os
import signal
import socket
import sys
from collections.abc import Awaitable, Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from e2e_transports import INITIALIZE

from rosbridge_mcp_server.catalogue import ALL_TOOL_NAMES
from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 90.0  # a bound on an event, not a pause: a busy machine (load 10 on 2 cores) still passes


class StdioServer:
    """The server process, spoken to by hand: one JSON-RPC message per line on stdin and stdout."""

    def __init__(self, process: asyncio.subprocess.Process) -> None:
        self.process = process
        self.stdout_lines: list[str] = []
        self._next_id = 0

    async def send(self, message: dict[str, Any]) -> None:
        await self.send_line(json.dumps(message))

    async def send_line(self, text: str) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write((text + "\n").encode())
        await self.process.stdin.drain()

    async def request(self, method: str, params: dict[str, Any] | None = None) -> dict[str, Any]:
        """Send a request and read lines until its response; every line read must be JSON-RPC."""
        self._next_id += 1
        request_id = self._next_id
        await self.send({"jsonrpc": "2.0", "id": request_id, "method": method, "params": params or {}})
        while True:
            message = await self.read_message()
            if message.get("id") == request_id and ("result" in message or "error" in message):
                return message

    async def read_message(self) -> dict[str, Any]:
        assert self.process.stdout is not None
        raw = await asyncio.wait_for(self.process.stdout.readline(), WAIT)
        assert raw, "the server closed stdout"
        line = raw.decode()
        self.stdout_lines.append(line)
        message = json.loads(line)
        assert isinstance(message, dict)
        assert message.get("jsonrpc") == "2.0", line
        return message


async def _start(*args: str) -> StdioServer:
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosbridge_mcp_server",
        *args,
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    return StdioServer(process)


async def _answers_to_file(
    tmp_path: Path, lines: list[str]
) -> tuple[list[dict[str, Any]], bytes, int | None]:
    """Run the server (no bridge) with stdin a regular file of *lines*: its answers, stderr and exit code."""
    requests = tmp_path / "requests.jsonl"
    requests.write_text("\n".join(lines) + "\n")
    with requests.open("rb") as stdin:
        process = await asyncio.create_subprocess_exec(
            sys.executable,
            "-m",
            "rosbridge_mcp_server",
            "--url",
            _closed_port_url(),
            stdin=stdin,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
        )
        stdout, stderr = await asyncio.wait_for(process.communicate(), WAIT)
    return [json.loads(line) for line in stdout.decode().splitlines()], stderr, process.returncode


async def _finish(server: StdioServer) -> tuple[bytes, bytes, int]:
    """Close stdin (the client going away) and collect the rest of the output and the exit code."""
    assert server.process.stdin is not None
    server.process.stdin.close()
    stdout, stderr = await asyncio.wait_for(server.process.communicate(), WAIT)
    code = await server.process.wait()
    return stdout, stderr, code


async def test_demo_server_over_stdio_speaks_only_json_rpc_on_stdout() -> None:
    """initialize, tools/list and tools/call against --demo; every stdout line is JSON-RPC; exit code 0."""
    server = await _start("--demo", "--log-level", "DEBUG")
    try:
        init = await server.request(
            "initialize",
            {
                "protocolVersion": "2025-06-18",
                "capabilities": {},
                "clientInfo": {"name": "e2e-test", "version": "0"},
            },
        )
        assert init["result"]["serverInfo"]["name"] == "rosbridge"
        assert "list_topics" in init["result"]["instructions"]
        await server.send({"jsonrpc": "2.0", "method": "notifications/initialized"})

        tools = await server.request("tools/list")
        assert [tool["name"] for tool in tools["result"]["tools"]] == list(ALL_TOOL_NAMES)

        topics = await server.request("tools/call", {"name": "list_topics", "arguments": {}})
        assert topics["result"]["isError"] is False
        names = [row["name"] for row in topics["result"]["structuredContent"]["topics"]]
        assert "/turtle1/pose" in names

        published = await server.request(
            "tools/call",
            {
                "name": "publish_topic",
                "arguments": {
                    "topic": "/turtle1/cmd_vel",
                    "message_type": "geometry_msgs/msg/Twist",
                    "message": {"linear": {"x": 0.5}, "angular": {"z": 0.3}},
                },
            },
        )
        assert published["result"]["isError"] is False

        goal = await server.request(
            "tools/call",
            {
                "name": "publish_action",
                "arguments": {
                    "action_name": "/fibonacci",
                    "action_type": "example_interfaces/action/Fibonacci",
                    "goal": {"order": 3},
                },
                "_meta": {"progressToken": "goal-1"},
            },
        )
        assert goal["result"]["structuredContent"]["succeeded"] is True
        progress = [json.loads(line) for line in server.stdout_lines if '"notifications/progress"' in line]
        assert progress, "feedback should arrive as progress notifications"
        assert all(p["params"]["progressToken"] == "goal-1" for p in progress)

        failed = await server.request(
            "tools/call", {"name": "get_topic_info", "arguments": {"topic": "/no_such_topic"}}
        )
        assert failed["result"]["isError"] is True

        await _watch_the_robot(server)
    finally:
        rest, stderr, code = await _finish(server)

    for line in rest.decode().splitlines():
        assert json.loads(line)["jsonrpc"] == "2.0", line
    assert code == 0, stderr.decode()
    assert b"demo mode" in stderr
    assert b"Connected to rosbridge" in stderr


async def _watch_the_robot(server: StdioServer) -> None:
    """The tools that watch: a scan, a camera frame and a map as images, a transform, parameters, a type."""

    async def call(name: str, arguments: dict[str, Any]) -> dict[str, Any]:
        answer = await server.request("tools/call", {"name": name, "arguments": arguments})
        result: dict[str, Any] = answer["result"]
        assert result["isError"] is False, result["content"]
        return result

    scan = await call("subscribe_topic", {"topic": "/scan"})
    assert scan["structuredContent"]["messages"][0]["message"]["ranges"]["length"] == 360
    image = await call("get_image", {"topic": "/camera/image_raw"})
    assert [block["type"] for block in image["content"]] == ["text", "image"]
    assert image["content"][1]["mimeType"] == "image/jpeg"
    drawn = await call("view_map", {"scan_topic": "/scan"})
    assert [block["type"] for block in drawn["content"]] == ["text", "image"]
    assert drawn["content"][1]["mimeType"] == "image/png"
    assert drawn["structuredContent"]["scan_hits"] > 0
    frame = await call("get_transform", {"target_frame": "world", "source_frame": "base_link"})
    assert frame["structuredContent"]["chain"] == ["world", "odom", "base_link"]
    parameters = await call("list_parameters", {"node": "/turtlesim"})
    assert parameters["structuredContent"]["nodes"][0]["node"] == "/turtlesim"
    assert "background_r" in parameters["structuredContent"]["nodes"][0]["names"]
    described = await call("describe_type", {"type_name": "sensor_msgs/msg/LaserScan"})
    assert "ranges: float32[]" in described["structuredContent"]["parts"][0]["outline"]
    streamed = await call(
        "publish_topic",
        {
            "topic": "/turtle1/cmd_vel",
            "message_type": "geometry_msgs/msg/Twist",
            "message": {"linear": {"x": 0.2}},
            "rate_hz": 10,
            "duration": 0.3,
        },
    )
    assert streamed["structuredContent"]["zero_sent"] is True


#: Ports held bound (never listened on) while this module's tests run: a connection there is refused, and no
#: other test of a parallel run can take the port in the meantime, as it could a port bound and let go.
_HELD: list[socket.socket] = []


@pytest.fixture(autouse=True, scope="module")
def _release_held_ports() -> Iterator[None]:
    yield
    while _HELD:
        _HELD.pop().close()


def _closed_port_url() -> str:
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    _HELD.append(sock)
    return f"ws://127.0.0.1:{sock.getsockname()[1]}"


async def test_a_server_with_no_bridge_still_answers_and_reports_the_url() -> None:
    """Pointed at a closed port, it lists its tools (--tools original: eight) and a call names the URL."""
    url = _closed_port_url()
    server = await _start("--url", url, "--tools", "original")
    try:
        await server.request(
            "initialize",
            {
                "protocolVersion": "2025-06-18",
                "capabilities": {},
                "clientInfo": {"name": "e2e-test", "version": "0"},
            },
        )
        await server.send({"jsonrpc": "2.0", "method": "notifications/initialized"})
        assert len((await server.request("tools/list"))["result"]["tools"]) == 9
        answer = await server.request("tools/call", {"name": "list_actions", "arguments": {}})
        assert answer["result"]["isError"] is True
        assert f"Not connected to rosbridge at {url}" in answer["result"]["content"][0]["text"]
    finally:
        rest, stderr, code = await _finish(server)
    assert rest.strip() == b""
    assert code == 0, stderr.decode()


#: The console script's start, reporting at exit what the collector and the start left (``cli/collector.py``).
_REPORTING_START = """
import atexit, gc, json, sys
def report():
    state = {"on": gc.isenabled(), "frozen": gc.get_freeze_count(), "loaded": sorted(sys.modules)}
    print(json.dumps(state), file=sys.stderr)
atexit.register(report)
from rosbridge_mcp_server.cli import main
main()
"""
#: What a session that calls no tool never needs (each package with its modules): imported by the call, the
#: command or the transport that needs it.
_NOT_AT_START = (
    "PIL",
    "mcap",
    "rosbridge_mcp_server.cli.check",
    "rosbridge_mcp_server.console.serve",
    "rosbridge_mcp_server.mcapfile",
    "rosbridge_mcp_server.pictures.drawing",
    "rosbridge_mcp_server.robot.acting",
    "rosbridge_mcp_server.robot.arm",
    "rosbridge_mcp_server.robot.arm_scene",
    "rosbridge_mcp_server.robot.describing",
    "rosbridge_mcp_server.robot.recording.recorder",
    "rosbridge_mcp_server.server.http",
)
_NOT_AT_START_PACKAGES = tuple(f"{name}." for name in _NOT_AT_START)


async def test_the_start_pauses_the_collector_and_loads_no_code_before_its_first_use() -> None:
    """The console script pauses the collector while it starts (no collection walks the ~150 000 objects it
    makes to keep), then freezes what it made and turns the collector back on before it serves; a session
    that calls no tool imports no acting, drawing, recording, arm, console or HTTP code, nor the ``check``
    command."""
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-c",
        _REPORTING_START,
        "--url",
        _closed_port_url(),
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    server = StdioServer(process)
    try:
        await server.request("initialize", INITIALIZE["params"])
        assert len((await server.request("tools/list"))["result"]["tools"]) == len(ALL_TOOL_NAMES)
    finally:
        _, stderr, code = await _finish(server)
    assert code == 0, stderr.decode()
    report = json.loads(stderr.decode().strip().splitlines()[-1])
    assert report["on"] is True
    assert report["frozen"] > 50_000  # the SDK's modules and ours, the tools' models: the start's objects
    assert [m for m in report["loaded"] if m in _NOT_AT_START or m.startswith(_NOT_AT_START_PACKAGES)] == []


async def test_a_request_read_from_a_file_is_answered_through_the_sdk_transport(tmp_path: Path) -> None:
    """stdin a regular file, not a pipe: the SDK's own transport answers, then the server exits at EOF."""
    # Only initialize: the SDK ends the session at EOF and cancels requests still being handled, so a file
    # that ends right after a tools/list would race it.
    answers, stderr, code = await _answers_to_file(tmp_path, [json.dumps(INITIALIZE)])
    assert len(answers) == 1, stderr.decode()
    assert answers[0]["result"]["serverInfo"]["name"] == "rosbridge"
    assert code == 0, stderr.decode()


async def test_a_host_giving_one_socket_for_stdin_and_stdout_is_served_and_gets_it_back_blocking() -> None:
    """Node's child_process (what Electron hosts run on) gives a socket pair, not pipes. One socket as both
    stdin and stdout, the demo robot: the handshake, a tool call and an unreadable line are answered on it;
    at the end of input the server exits 0 and the socket's file description, shared with us, is blocking
    again (the event loop had made it non-blocking)."""
    ours, theirs = socket.socketpair()
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosbridge_mcp_server",
        "--demo",
        stdin=theirs,
        stdout=theirs,
        stderr=asyncio.subprocess.PIPE,
    )
    reader, writer = await asyncio.open_connection(sock=ours)
    lines = [
        json.dumps(INITIALIZE),
        json.dumps({"jsonrpc": "2.0", "method": "notifications/initialized"}),
        "not json",
        json.dumps(
            {
                "jsonrpc": "2.0",
                "id": 2,
                "method": "tools/call",
                "params": {"name": "list_topics", "arguments": {}},
            }
        ),
    ]
    answers: dict[object, dict[str, Any]] = {}
    try:
        writer.write(("\n".join(lines) + "\n").encode())
        while len(answers) < 3:
            raw = await asyncio.wait_for(reader.readline(), WAIT)
            assert raw, "the server closed its end"
            message = json.loads(raw)
            if "id" in message:
                answers[message["id"]] = message
        writer.write_eof()
        code = await asyncio.wait_for(process.wait(), WAIT)
        blocking = os.get_blocking(theirs.fileno())
    finally:
        writer.close()
        theirs.close()
        if process.returncode is None:
            process.kill()
        _out, stderr = await process.communicate()
    assert answers[1]["result"]["serverInfo"]["name"] == "rosbridge"
    assert answers[None]["error"]["code"] == -32700
    assert "/turtle1/pose" in answers[2]["result"]["content"][0]["text"]
    assert code == 0, stderr.decode()
    assert blocking


async def _initialized(server: StdioServer) -> None:
    await server.request(
        "initialize",
        {
            "protocolVersion": "2025-06-18",
            "capabilities": {},
            "clientInfo": {"name": "e2e-test", "version": "0"},
        },
    )
    await server.send({"jsonrpc": "2.0", "method": "notifications/initialized"})


async def _start_long_goal(server: StdioServer) -> None:
    """Send a long publish_action and read until its first progress notification."""
    await server.send(
        {
            "jsonrpc": "2.0",
            "id": 99,
            "method": "tools/call",
            "params": {
                "name": "publish_action",
                "arguments": {
                    "action_name": "/fibonacci",
                    "action_type": "example_interfaces/action/Fibonacci",
                    "goal": {"order": 45},
                    "timeout": 120,
                },
                "_meta": {"progressToken": "long-goal"},
            },
        }
    )
    while (await server.read_message()).get("method") != "notifications/progress":
        pass


@pytest.mark.parametrize("how", ["eof", "sigterm"])
async def test_a_running_goal_is_cancelled_when_the_server_is_stopped(
    make_sim: Callable[..., Awaitable[SimulatedRobot]], how: str
) -> None:
    """Closing stdin, or SIGTERM with stdin still open, cancels the goal on the robot and exits 0."""
    robot = await make_sim(dialect="ros2", action_step=0.2)
    server = await _start("--url", robot.url)
    try:
        await _initialized(server)
        await _start_long_goal(server)
        (goal,) = robot.world.goals.values()
        assert not goal.finished
        if how == "sigterm":
            server.process.send_signal(signal.SIGTERM)
            # stdin stays open: the process must end by itself.
            await asyncio.wait_for(server.process.wait(), WAIT)
    finally:
        _rest, stderr, code = await _finish(server)
    assert code == 0, stderr.decode()
    await robot.wait_for(lambda w: goal.finished, WAIT)
    assert goal.cancel_requested
    assert goal.status == 5  # CANCELED


async def test_every_unreadable_line_gets_a_json_rpc_error_and_the_session_goes_on() -> None:
    """Garbage, 300 deep, not JSON-RPC, bad UTF-8, a 65 MiB line: each gets an error, with its id if shown."""
    server = await _start("--demo")
    deep = "[" * 300 + "]" * 300
    try:
        await _initialized(server)
        await server.send_line("this is not json")
        await server.send_line(
            '{"jsonrpc": "2.0", "id": 41, "method": "tools/call", "params": {"name": "publish_service", '
            f'"arguments": {{"service": "/add_two_ints", "service_type": "x/srv/Y", "request": {deep}}}}}}}'
        )
        await server.send_line('{"jsonrpc": "2.0", "id": "forty-two", "method": 3}')
        await server.send_line("[1, 2]")
        await server.send_line("")
        assert server.process.stdin is not None
        server.process.stdin.write(b"\xff\xfe not utf-8\n")
        overlong = '{"jsonrpc": "2.0", "id": 43, "method": "tools/call", "params": {"x": "' + "y" * (
            65 * 2**20
        )
        await server.send_line(overlong + '"}}')
        answers = [await server.read_message() for _ in range(6)]
        topics = await server.request("tools/call", {"name": "list_topics", "arguments": {}})
    finally:
        _rest, stderr, code = await _finish(server)
    assert [(a["id"], a["error"]["code"]) for a in answers] == [
        (None, -32700),
        (41, -32700),
        ("forty-two", -32600),
        (None, -32600),
        (None, -32700),
        (43, -32600),  # over 64 MiB: skipped unread
    ]
    assert "nests deeper" in answers[1]["error"]["message"]
    assert "longer than the 64 MiB this server reads" in answers[5]["error"]["message"]
    assert topics["result"]["isError"] is False
    assert code == 0, stderr.decode()


async def test_arguments_that_are_no_object_are_a_tool_error_naming_it() -> None:
    """tools/call with arguments a list, a string or a number (the SDK's client cannot send them, a client
    written by hand can): a tool error saying they must be an object, with the tool's parameters."""
    server = await _start("--demo")
    try:
        await _initialized(server)
        answers = [
            await server.request("tools/call", {"name": "publish_service", "arguments": arguments})
            for arguments in ([1, 2], "/add_two_ints", 5)
        ]
    finally:
        _rest, stderr, code = await _finish(server)
    texts = [answer["result"]["content"][0]["text"] for answer in answers]
    assert all(answer["result"]["isError"] is True for answer in answers)
    for text, kind in zip(texts, ("a list", "a string", "a number"), strict=True):
        assert text.startswith(
            f"Invalid arguments for publish_service: the arguments must be a JSON object of named arguments, "
            f"not {kind}; nothing was sent. It takes: service, service_type"
        )
    assert code == 0, stderr.decode()


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads the peak RSS from Linux's /proc")
async def test_a_line_over_64_mib_is_refused_unread_and_memory_stays_bounded() -> None:
    """A 150 MiB line (a call with its id last): -32600 naming the limit under its id; the server's peak RSS
    grows by about the 64 MiB limit, not by the line (it is never held whole); the session goes on."""
    server = await _start("--demo")
    try:
        await _initialized(server)
        before = _peak_rss(server.process.pid)
        assert server.process.stdin is not None
        server.process.stdin.write(b'{"jsonrpc": "2.0", "method": "tools/list", "params": {"x": "')
        for _ in range(150):
            server.process.stdin.write(b"y" * 2**20)
            await server.process.stdin.drain()
        server.process.stdin.write(b'"}, "id": 77}\n')
        answer = await server.read_message()
        growth = _peak_rss(server.process.pid) - before
        topics = await server.request("tools/call", {"name": "list_topics", "arguments": {}})
    finally:
        _rest, stderr, code = await _finish(server)
    assert (answer["id"], answer["error"]["code"]) == (77, -32600)
    assert "the line is 157,286," in answer["error"]["message"]
    assert growth < 96 * 2**20, f"peak RSS grew by {growth / 2**20:.0f} MiB"
    assert topics["result"]["isError"] is False
    assert code == 0, stderr.decode()


def _peak_rss(pid: int) -> int:
    """The process's peak RSS (VmHWM), bytes."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
    raise AssertionError("no VmHWM")


async def test_unreadable_lines_read_from_a_file_are_answered_too(tmp_path: Path) -> None:
    """stdin a regular file (the SDK's transport): garbage and a too-deep request get their error replies."""
    deep = "[" * 300 + "]" * 300
    lines = [
        "not json",
        f'{{"jsonrpc": "2.0", "id": 5, "method": "tools/list", "params": {{"x": {deep}}}}}',
        '{"jsonrpc": "2.0", "id": 6, "method": 7}',
    ]
    answers, stderr, code = await _answers_to_file(tmp_path, lines)
    assert [(a["id"], a["error"]["code"]) for a in answers] == [(None, -32700), (5, -32700), (6, -32600)], (
        stderr.decode()
    )
    assert code == 0, stderr.decode()


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_nav2_demo_over_stdio_answers_every_graph_tool_within_the_budget(dialect: str) -> None:
    """--demo --demo-world nav2 over stdio: tools/list within 1 KB a tool; every graph tool's text within
    8,000 characters; a page that holds less says the offset of the next."""
    server = await _start("--demo", "--demo-dialect", dialect, "--demo-world", "nav2")
    try:
        hello = {
            "protocolVersion": "2025-06-18",
            "capabilities": {},
            "clientInfo": {"name": "e2e", "version": "0"},
        }
        await server.request("initialize", hello)
        await server.send({"jsonrpc": "2.0", "method": "notifications/initialized"})
        tools = (await server.request("tools/list"))["result"]["tools"]
        assert len(json.dumps(tools, separators=(",", ":"))) <= 1_024 * len(tools)
        sep = ":" if dialect == "ros2" else "/"
        calls: list[tuple[str, dict[str, Any]]] = [
            ("list_topics", {}),
            ("list_services", {}),
            ("list_actions", {}),
            ("list_nodes", {}),
            ("list_parameters", {}),
            ("get_node_info", {"node": "/controller_server"}),
            ("get_topic_info", {"topic": "/scan"}),
            ("get_parameter", {"name": f"/amcl{sep}max_particles"}),
        ]
        for name, arguments in calls:
            answer = (await server.request("tools/call", {"name": name, "arguments": arguments}))["result"]
            assert answer["isError"] is False, (name, answer)
            assert len(answer["content"][0]["text"]) <= 8_000, name
        paged = (await server.request("tools/call", {"name": "list_topics", "arguments": {"limit": 10}}))[
            "result"
        ]
        assert paged["structuredContent"]["more"] > 0
        assert "offset=10" in paged["content"][0]["text"]
    finally:
        _, _, code = await _finish(server)
    assert code == 0
