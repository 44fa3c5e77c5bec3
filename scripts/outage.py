"""How soon the MCP server is usable again after its bridge was down for 1, 3, 8 and 30 seconds.

    uv run python scripts/outage.py                       # the simulated robot, as a process of its own
    uv run python scripts/outage.py --outages 1 3         # other outage lengths (seconds)
    uv run python scripts/outage.py --url ws://127.0.0.1:9090 --outages 3 \\
        --lab-restart '<command that stops the bridge>' --lab-start '<command that starts it>'

The console script runs over stdio (``--log-level DEBUG``, so every attempt shows on its stderr). Each outage
is run twice:

* **idle**: no tool call while the bridge is down; after it is back (its port accepts TCP again) we wait for
  the server's "Reconnected" line, so the figure is the background reconnect alone. A ``list_topics`` then
  confirms the session works.
* **busy**: a ``list_topics`` every 0.5 s while the bridge is down (each must fail, and fail fast), then
  every 50 ms from its return: the figure is the first success after the return. A call between attempts
  prompts one.

Printed per run: the outage, the figure, the connection attempts the server made while the bridge was down
(its effort), and the slowest failed call during the outage. Exit status 0 when every figure is under 1 s.
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
from typing import Any

TARGET_SECONDS = 1.0


class Server:
    """The MCP server on stdio; stderr lines are kept with the time they arrived."""

    def __init__(self, url: str) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "rosbridge_mcp_server", "--url", url, "--log-level", "DEBUG"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        self.answers: queue.Queue[dict[str, Any]] = queue.Queue()
        self.stderr: list[tuple[float, str]] = []
        self.ids = 0
        threading.Thread(target=self._read_stdout, daemon=True).start()
        threading.Thread(target=self._read_stderr, daemon=True).start()

    def _read_stdout(self) -> None:
        assert self.process.stdout is not None
        for raw in self.process.stdout:
            self.answers.put(json.loads(raw))

    def _read_stderr(self) -> None:
        assert self.process.stderr is not None
        for raw in self.process.stderr:
            self.stderr.append((time.monotonic(), raw.decode(errors="replace")))

    def send(self, message: dict[str, Any]) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write((json.dumps(message) + "\n").encode())
        self.process.stdin.flush()

    def request(self, method: str, params: dict[str, Any], timeout: float = 30.0) -> dict[str, Any]:
        self.ids += 1
        self.send({"jsonrpc": "2.0", "id": self.ids, "method": method, "params": params})
        deadline = time.monotonic() + timeout
        while True:
            message = self.answers.get(timeout=max(deadline - time.monotonic(), 0.001))
            if message.get("id") == self.ids:
                return message

    def list_topics_ok(self) -> bool:
        answer = self.request("tools/call", {"name": "list_topics", "arguments": {}})
        return "result" in answer and not answer["result"].get("isError")

    def lines_since(self, since: float, text: str) -> list[float]:
        return [at for at, line in list(self.stderr) if at >= since and text in line]

    def close(self) -> None:
        assert self.process.stdin is not None
        self.process.stdin.close()
        try:
            self.process.wait(20)
        except subprocess.TimeoutExpired:
            self.process.kill()


class Bridge:
    """The bridge to stop and start: the simulated robot as a process, or shell commands for a lab."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.process: subprocess.Popen[bytes] | None = None
        self.starting: subprocess.Popen[bytes] | None = None
        if args.url:
            self.url = args.url
        else:
            with socket.socket() as sock:
                sock.bind(("127.0.0.1", 0))
                self.port = sock.getsockname()[1]
            self.url = f"ws://127.0.0.1:{self.port}"
        self.host, port = self.url.split("//", 1)[1].split("/")[0].rsplit(":", 1)
        self.port = int(port)

    def start(self) -> float:
        """Start the bridge; returns when its port accepts TCP (monotonic time)."""
        if self.args.lab_start:
            # In the background: the moment its port accepts is what counts, not when the script returns.
            self.starting = subprocess.Popen(self.args.lab_start, shell=True, stdout=subprocess.DEVNULL)
        else:
            self.process = subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "rosbridge_mcp_server.sim",
                    "--port",
                    str(self.port),
                    "--log-level",
                    "WARNING",
                    "--action-step",
                    "0.05",
                ],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
        while True:
            try:
                with socket.create_connection((self.host, self.port), timeout=0.05):
                    return time.monotonic()
            except OSError:
                time.sleep(0.002)

    def finish_starting(self) -> None:
        """Wait for a lab's start script to finish."""
        if self.starting is not None:
            self.starting.wait()
            self.starting = None

    def stop(self) -> None:
        self.finish_starting()
        if self.args.lab_restart:
            subprocess.run(self.args.lab_restart, shell=True, check=True, stdout=subprocess.DEVNULL)
        elif self.process is not None:
            self.process.send_signal(signal.SIGKILL)  # a crash, not a polite shutdown
            self.process.wait()
            self.process = None


def one_run(server: Server, bridge: Bridge, outage: float, busy: bool) -> dict[str, Any]:
    bridge.stop()
    down = time.monotonic()
    slowest_failure = 0.0
    failed_calls = 0
    while time.monotonic() - down < outage:
        if busy:
            begin = time.monotonic()
            if server.list_topics_ok():
                raise RuntimeError("a call succeeded while the bridge was down")
            slowest_failure = max(slowest_failure, time.monotonic() - begin)
            failed_calls += 1
            time.sleep(max(0.0, 0.5 - (time.monotonic() - begin)))
        else:
            time.sleep(0.05)
    up = bridge.start()
    attempts = len(server.lines_since(down, "still unreachable")) + len(
        server.lines_since(down, "Cannot reach")
    )
    if busy:
        while not server.list_topics_ok():
            time.sleep(0.05)
        figure = time.monotonic() - up
    else:
        deadline = time.monotonic() + 30
        while not server.lines_since(up, "Reconnected to rosbridge") and time.monotonic() < deadline:
            time.sleep(0.005)
        seen = server.lines_since(up, "Reconnected to rosbridge")
        figure = (seen[0] - up) if seen else float("inf")
        if not server.list_topics_ok():
            raise RuntimeError("list_topics failed after the reconnect")
    return {
        "outage": outage,
        "mode": "busy" if busy else "idle",
        "figure": figure,
        "attempts": attempts,
        "failed_calls": failed_calls,
        "slowest_failure": slowest_failure,
    }


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--outages", type=float, nargs="+", default=[1, 3, 8, 30], help="seconds down")
    parser.add_argument("--url", help="the bridge's URL (with --lab-restart/--lab-start)")
    parser.add_argument("--lab-restart", help="shell command that stops the bridge")
    parser.add_argument("--lab-start", help="shell command that starts the bridge")
    args = parser.parse_args()
    if bool(args.url) != bool(args.lab_start) or bool(args.lab_start) != bool(args.lab_restart):
        parser.error("--url, --lab-restart and --lab-start go together")
    bridge = Bridge(args)
    if not args.url:
        bridge.start()
    server = Server(bridge.url)
    rows: list[dict[str, Any]] = []
    try:
        server.request(
            "initialize",
            {
                "protocolVersion": "2025-06-18",
                "capabilities": {},
                "clientInfo": {"name": "outage", "version": "0"},
            },
        )
        server.send({"jsonrpc": "2.0", "method": "notifications/initialized"})
        while not server.list_topics_ok():
            time.sleep(0.1)
        for outage in args.outages:
            for busy in (False, True):
                row = one_run(server, bridge, outage, busy)
                rows.append(row)
                print(f"{row['mode']} {outage:g} s: {row['figure'] * 1000:.0f} ms", file=sys.stderr)
    finally:
        server.close()
        if args.url:
            bridge.finish_starting()  # a lab is left running, as it was found
        else:
            bridge.stop()
    print(f"# outages of {bridge.url} ({'simulated robot process' if not args.url else 'lab'})\n")
    print(
        "| down | mode | usable again after its return | attempts while down | calls while down (slowest) |"
    )
    print("|---:|---|---:|---:|---:|")
    for row in rows:
        calls = (
            f"{row['failed_calls']} ({row['slowest_failure'] * 1000:.0f} ms)"
            if row["mode"] == "busy"
            else "-"
        )
        figure = f"{row['figure'] * 1000:.0f} ms"
        print(f"| {row['outage']:g} s | {row['mode']} | {figure} | {row['attempts']} | {calls} |")
    return 0 if all(row["figure"] < TARGET_SECONDS for row in rows) else 1


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
