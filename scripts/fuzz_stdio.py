"""Fuzz the MCP server over stdio: thousands of generated tool calls, counting hangs and dead sessions.

    uv run python scripts/fuzz_stdio.py                        # 2,000 calls against a simulated robot
    uv run python scripts/fuzz_stdio.py --calls 500 --dialect ros1
    uv run python scripts/fuzz_stdio.py --url ws://127.0.0.1:9090  # any rosbridge (it acts on that robot!)

The console script runs as a subprocess, spoken to by hand: one JSON-RPC line per request. Arguments come from
the Hypothesis strategies of the property tests (``tests/mcp/argument_strategies.py``), built from the input
schemas the server lists, so every tool is covered; about one line in ten is a raw line instead: JSON nested
hundreds to thousands of levels deep, broken JSON, or JSON that is not JSON-RPC, each carrying an id.

After every call a ``list_topics`` must succeed. Counted and printed: calls per tool, results and error
results, JSON-RPC error replies, hangs (no answer within the call's own timeout plus slack), dead sessions
(the follow-up failed or the process ended), stdout lines that are not JSON-RPC, tracebacks on stderr,
reconnects, and the latency of the answers. Exit status 0 when there were no hangs and no dead sessions.
"""

from __future__ import annotations

import argparse
import asyncio
import itertools
import json
import logging
import os
import queue
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "mcp"))
from argument_strategies import Vocabulary, call_deadline, tool_calls

from rosbridge_mcp_server.sim import SimulatedRobot

#: How long a follow-up list_topics may take before the session counts as dead.
FOLLOW_UP_SECONDS = 10.0
#: Raw lines get an answer at once (they never reach a tool).
RAW_SECONDS = 5.0


class StdioPeer:
    """The server process; a thread reads its stdout and files every answer by id."""

    def __init__(self, url: str, stderr_path: Path) -> None:
        self.stderr_file = stderr_path.open("wb")
        self.process = subprocess.Popen(
            [sys.executable, "-m", "rosbridge_mcp_server", "--url", url],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self.stderr_file,
        )
        self.answers: dict[Any, queue.Queue[dict[str, Any]]] = {}
        self.lock = threading.Lock()
        self.not_json_rpc = 0
        self.null_id_errors = 0
        self.ids = itertools.count(1)
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for raw in self.process.stdout:
            try:
                message = json.loads(raw)
            except ValueError:
                self.not_json_rpc += 1
                continue
            if not isinstance(message, dict) or message.get("jsonrpc") != "2.0":
                self.not_json_rpc += 1
                continue
            if "id" in message and ("result" in message or "error" in message):
                if message["id"] is None:
                    self.null_id_errors += 1
                    continue
                self._box(message["id"]).put(message)

    def _box(self, request_id: Any) -> queue.Queue[dict[str, Any]]:
        with self.lock:
            return self.answers.setdefault(request_id, queue.Queue())

    def send_line(self, text: str) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write(text.encode("utf-8", errors="surrogatepass") + b"\n")
        self.process.stdin.flush()

    def request(self, method: str, params: dict[str, Any], timeout: float) -> dict[str, Any] | None:
        request_id = next(self.ids)
        line = json.dumps({"jsonrpc": "2.0", "id": request_id, "method": method, "params": params})
        return self.raw(line, request_id, timeout)

    def raw(self, line: str, request_id: Any, timeout: float) -> dict[str, Any] | None:
        box = self._box(request_id)
        self.send_line(line)
        try:
            return box.get(timeout=timeout)
        except queue.Empty:
            return None
        finally:
            with self.lock:
                self.answers.pop(request_id, None)

    def alive(self) -> bool:
        return self.process.poll() is None

    def close(self) -> int:
        assert self.process.stdin is not None
        self.process.stdin.close()
        try:
            code = self.process.wait(30)
        except subprocess.TimeoutExpired:
            self.process.kill()
            code = -9
        self.stderr_file.close()
        return code


def _raw_lines() -> st.SearchStrategy[tuple[str, str]]:
    """(kind, line-with-{id}) for lines no tool ever sees."""
    call = (
        '{{"jsonrpc": "2.0", "id": {{id}}, "method": "tools/call", "params": {{"name": "publish_service", '
        '"arguments": {{"service": "/add_two_ints", "service_type": "example_interfaces/srv/AddTwoInts", '
        '"request": {deep}}}}}}}'
    )
    deep = st.integers(150, 5000).map(lambda n: ("deep", call.format(deep="[" * n + "]" * n)))
    broken = st.sampled_from(
        [
            ("broken", '{"jsonrpc": "2.0", "id": {id}, "method": "tools/call", "params": {'),
            ("broken", '{"jsonrpc": "2.0", "id": {id}, "method": "tools/list", "params": NaNx}'),
            ("not-rpc", '{"jsonrpc": "2.0", "id": {id}, "method": 7}'),
            ("not-rpc", '{"jsonrpc": "1.0", "id": {id}, "method": "tools/list"}'),
        ]
    )
    return st.one_of(deep, broken)


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--calls", type=int, default=2000, help="generated calls (default 2000)")
    parser.add_argument("--url", help="a rosbridge to use instead of a simulated robot")
    parser.add_argument("--dialect", choices=["ros2", "ros1"], default="ros2", help="the simulated robot's")
    parser.add_argument(
        "--seed", type=int, help="a Hypothesis seed (default: derandomized, the same every run)"
    )
    args = parser.parse_args()

    # The simulated robot runs in this process; its per-request log lines are not what this run is about.
    logging.getLogger("rosbridge_mcp_server.sim").setLevel(logging.ERROR)
    loop = asyncio.new_event_loop()
    threading.Thread(target=loop.run_forever, daemon=True).start()
    robot: SimulatedRobot | None = None
    url = args.url
    if url is None:
        robot = SimulatedRobot(args.dialect, action_step=0.01, slow_service_seconds=0.2)
        asyncio.run_coroutine_threadsafe(robot.start(), loop).result(30)
        url = robot.url
    stderr_path = Path(tempfile.mkstemp(prefix="fuzz-stdio-", suffix=".stderr")[1])
    peer = StdioPeer(url, stderr_path)
    try:
        return _run(peer, args, url)
    finally:
        code = peer.close()
        print(f"server exit code: {code}; its stderr: {stderr_path}", file=sys.stderr)
        if robot is not None:
            asyncio.run_coroutine_threadsafe(robot.stop(), loop).result(30)


def _run(peer: StdioPeer, args: argparse.Namespace, url: str) -> int:
    init = peer.request(
        "initialize",
        {"protocolVersion": "2025-06-18", "capabilities": {}, "clientInfo": {"name": "fuzz", "version": "0"}},
        30,
    )
    assert init is not None, "no answer to initialize"
    assert "result" in init, init
    peer.send_line(json.dumps({"jsonrpc": "2.0", "method": "notifications/initialized"}))
    listed = peer.request("tools/list", {}, 30)
    assert listed is not None
    schemas = {tool["name"]: tool["inputSchema"] for tool in listed["result"]["tools"]}
    vocabulary = Vocabulary()
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        answer = peer.request("tools/call", {"name": "list_topics", "arguments": {}}, 10)
        if answer and not answer["result"].get("isError"):
            break
        time.sleep(0.2)  # the server connects in the background; poll until it has
    for tool in ("list_topics", "list_services", "list_actions"):
        answer = peer.request("tools/call", {"name": tool, "arguments": {}}, 30)
        for rows in ((answer or {}).get("result", {}).get("structuredContent") or {}).values():
            if isinstance(rows, list):
                for row in rows:
                    if isinstance(row, dict):
                        vocabulary.add(row.get("name", ""), row.get("type") or "")

    calls: Counter[str] = Counter()
    tool_errors: Counter[str] = Counter()
    rpc_errors: Counter[str] = Counter()
    rpc_texts: Counter[str] = Counter()
    hangs: list[str] = []
    dead: list[str] = []
    latencies: list[float] = []
    started = time.monotonic()
    kinds = st.one_of(
        tool_calls(schemas, vocabulary).map(lambda call: ("tool", call)),
        _raw_lines().map(lambda raw: ("raw", raw)),
    )

    @settings(
        max_examples=args.calls,
        derandomize=args.seed is None,
        database=None,
        deadline=None,
        phases=[Phase.generate],
        suppress_health_check=list(HealthCheck),
    )
    @given(kinds)
    def one(item: tuple[str, Any]) -> None:
        if dead:
            return
        kind, payload = item
        begin = time.monotonic()
        if kind == "tool":
            name, arguments = payload
            limit = call_deadline(arguments, schemas[name])
            label = name
            try:
                line = json.dumps({"name": name, "arguments": arguments})
            except ValueError:
                return
            request_id = next(peer.ids)
            answer = peer.raw(
                f'{{"jsonrpc": "2.0", "id": {request_id}, "method": "tools/call", "params": {line}}}',
                request_id,
                limit,
            )
        else:
            label, template = payload
            limit = RAW_SECONDS
            request_id = next(peer.ids)
            answer = peer.raw(template.replace("{id}", str(request_id)), request_id, limit)
            label = f"raw:{label}"
        calls[label] += 1
        if answer is None:
            hangs.append(f"{label} ({limit:g} s)")
        else:
            latencies.append(time.monotonic() - begin)
            if "error" in answer:
                rpc_errors[label] += 1
                rpc_texts[
                    f"{label}: {answer['error'].get('code')} {str(answer['error'].get('message'))[:150]}"
                ] += 1
            elif answer["result"].get("isError"):
                tool_errors[label] += 1
        follow = peer.request("tools/call", {"name": "list_topics", "arguments": {}}, FOLLOW_UP_SECONDS)
        if follow is None or "error" in follow or follow["result"].get("isError") or not peer.alive():
            dead.append(label)

    one()
    elapsed = time.monotonic() - started
    stderr = Path(peer.stderr_file.name).read_text(errors="replace") if peer.stderr_file.name else ""
    _report(
        url,
        calls,
        tool_errors,
        rpc_errors,
        hangs,
        dead,
        latencies,
        elapsed,
        peer,
        stderr.count("Traceback"),
        stderr.count("Reconnected to rosbridge"),
    )
    for text, count in rpc_texts.most_common(8):
        print(f"JSON-RPC error x{count}: {text}")
    return 0 if not hangs and not dead else 1


def _report(  # noqa: PLR0917
    url: str,
    calls: Counter[str],
    tool_errors: Counter[str],
    rpc_errors: Counter[str],
    hangs: list[str],
    dead: list[str],
    latencies: list[float],
    elapsed: float,
    peer: StdioPeer,
    tracebacks: int,
    reconnects: int,
) -> None:
    total = sum(calls.values())
    print(f"# stdio fuzz against {url}: {total} calls in {elapsed:.1f} s\n")
    print("| call | sent | result ok | isError | JSON-RPC error |")
    print("|---|---:|---:|---:|---:|")
    for label in sorted(calls):
        ok = calls[label] - tool_errors[label] - rpc_errors[label]
        print(f"| {label} | {calls[label]} | {ok} | {tool_errors[label]} | {rpc_errors[label]} |")
    latencies.sort()
    if latencies:
        p50 = latencies[len(latencies) // 2] * 1000
        p99 = latencies[min(len(latencies) - 1, int(len(latencies) * 0.99))] * 1000
        print(f"\nlatency of answers: p50 {p50:.1f} ms, p99 {p99:.1f} ms, max {latencies[-1] * 1000:.0f} ms")
    print(f"hangs: {len(hangs)} {hangs[:10] if hangs else ''}")
    print(f"dead sessions: {len(dead)} {dead[:3] if dead else ''}")
    print(f"stdout lines that are not JSON-RPC: {peer.not_json_rpc}")
    print(f"error replies with a null id: {peer.null_id_errors}")
    print(f"tracebacks on the server's stderr: {tracebacks}")
    print(f"reconnects to rosbridge: {reconnects}")
    print(f"server process alive at the end: {peer.alive()}")


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
