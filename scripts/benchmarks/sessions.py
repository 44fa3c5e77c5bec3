"""MCP sessions: our server, the bare reference server, the SDK's client on stdio and JSON-RPC lines on the
pipes."""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import json
import os
import shutil
import sys
import time
from collections.abc import AsyncIterator
from pathlib import Path
from typing import IO, Any

import mcp_types
import psutil
from mcp.client.session import ClientSession
from mcp.client.stdio import StdioServerParameters, stdio_client

from benchmarks.bridge import tail
from benchmarks.constants import BARE_SERVER, CONSOLE_SCRIPT, OURS_SDK_STDIO, REPO


@dataclasses.dataclass
class Served:
    """An MCP server process on stdio with an initialized session."""

    session: ClientSession
    process: psutil.Process
    initialize_s: float  # spawn -> initialize answered
    tools_list_s: float  # spawn -> tools/list answered
    tools: dict[str, mcp_types.Tool]
    cpu_s: float  # the server's CPU time (user + system) when tools/list was answered

    def rss(self) -> int:
        rss: int = self.process.memory_info().rss
        return rss

    async def tool(self, name: str, arguments: dict[str, Any]) -> mcp_types.CallToolResult:
        result = await self.session.call_tool(name, arguments)
        if result.is_error:
            text = " ".join(getattr(block, "text", "") for block in result.content)
            raise RuntimeError(f"tool {name} answered with an error: {text}")
        return result


def our_server_command(url: str) -> list[str]:
    """The console script, as an MCP client such as Claude Desktop starts it."""
    script = Path(sys.executable).parent / CONSOLE_SCRIPT
    found = str(script) if script.exists() else shutil.which(CONSOLE_SCRIPT)
    if found is None:
        raise FileNotFoundError(f"the console script {CONSOLE_SCRIPT} is not installed (run `uv sync`)")
    return [found, "--url", url]


def bare_server_command(*, reference_tools: bool = False, our_stdio: bool = False) -> list[str]:
    flags = [
        flag
        for flag, wanted in (("--reference-tools", reference_tools), ("--our-stdio", our_stdio))
        if wanted
    ]
    return [sys.executable, str(BARE_SERVER), *flags]


def our_server_on_sdk_stdio_command(url: str) -> list[str]:
    """Our server on the MCP SDK's stdio transport instead of its own (``servers/ours_sdk_stdio.py``)."""
    return [sys.executable, str(OURS_SDK_STDIO), "--url", url]


@contextlib.asynccontextmanager
async def serve_mcp(
    command: list[str], errlog: IO[str], env: dict[str, str] | None = None
) -> AsyncIterator[Served]:
    """Spawn an MCP server, run ``initialize`` and ``tools/list``, and time both from the spawn."""
    me = psutil.Process()
    before = {child.pid for child in me.children()}
    params = StdioServerParameters(command=command[0], args=command[1:], cwd=str(REPO), env=env)
    started = time.perf_counter()
    async with stdio_client(params, errlog=errlog) as (read, write), ClientSession(read, write) as session:
        try:
            async with asyncio.timeout(60):
                await session.initialize()
                initialized = time.perf_counter()
                listed = await session.list_tools()
                tools_listed = time.perf_counter()
        except Exception as error:
            raise RuntimeError(
                f"{' '.join(command)} did not start ({type(error).__name__}: {error}); "
                f"the end of its stderr:\n{tail(errlog)}"
            ) from error
        spawned = [child for child in me.children() if child.pid not in before]
        if len(spawned) != 1:
            raise RuntimeError(f"expected one new server process, found {[p.pid for p in spawned]}")
        cpu_s = cpu_seconds(spawned[0])
        yield Served(
            session=session,
            process=spawned[0],
            initialize_s=initialized - started,
            tools_list_s=tools_listed - started,
            tools={tool.name: tool for tool in listed.tools},
            cpu_s=cpu_s,
        )


def cpu_seconds(process: psutil.Process) -> float:
    """The CPU time *process* has run, all its threads: Linux's scheduler figures in nanoseconds where there
    are some (the clock-tick figure psutil reads moves in 10 ms steps), else psutil's user + system."""
    with contextlib.suppress(OSError, ValueError, IndexError):
        tasks = Path(f"/proc/{process.pid}/task").glob("*/schedstat")
        return sum(int(task.read_text().split()[0]) for task in tasks) / 1e9
    times = process.cpu_times()
    return float(times.user + times.system)


class RawPipeClient:
    """An MCP client reduced to JSON-RPC lines on the server's pipes: no SDK, no validation on this side."""

    def __init__(self, process: asyncio.subprocess.Process, *, lenient: bool = False) -> None:
        self._process = process
        self._ids = 0
        self._lenient = lenient  # a peer's stray non-JSON lines on stdout are skipped; never ours

    async def request(self, method: str, params: dict[str, Any]) -> dict[str, Any]:
        assert self._process.stdin is not None
        assert self._process.stdout is not None
        self._ids += 1
        line = {"jsonrpc": "2.0", "id": self._ids, "method": method, "params": params}
        self._process.stdin.write(json.dumps(line).encode() + b"\n")
        while True:
            line = await self._process.stdout.readline()
            if not line:
                raise RuntimeError(f"the server closed its stdout before answering {method}")
            try:
                answer: dict[str, Any] = json.loads(line)
            except ValueError:
                if self._lenient:
                    continue
                raise
            if answer.get("id") == self._ids:
                return answer  # notifications (progress, logging) are skipped

    async def tool(self, name: str, arguments: dict[str, Any]) -> dict[str, Any]:
        answer = await self.request("tools/call", {"name": name, "arguments": arguments})
        if "error" in answer or answer["result"].get("isError"):
            raise RuntimeError(f"tool {name} failed: {answer}")
        return answer


@contextlib.asynccontextmanager
async def raw_pipe_client(
    command: list[str], errlog: Any, env: dict[str, str], *, lenient: bool = False
) -> AsyncIterator[RawPipeClient]:
    """Spawn the server and do the initialize handshake by hand."""
    process = await asyncio.create_subprocess_exec(
        *command,
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
        stderr=errlog,
        env={**os.environ, **env},
        limit=64 * 1024 * 1024,
    )
    client = RawPipeClient(process, lenient=lenient)
    try:
        info = {"name": "bench", "version": "0"}
        hello = {"protocolVersion": "2025-06-18", "capabilities": {}, "clientInfo": info}
        await client.request("initialize", hello)
        assert process.stdin is not None
        process.stdin.write(b'{"jsonrpc": "2.0", "method": "notifications/initialized"}\n')
        yield client
    finally:
        if process.stdin is not None:
            process.stdin.close()
        try:
            await asyncio.wait_for(process.wait(), 5)
        except TimeoutError:
            process.kill()
            await process.wait()


async def ctx_graph_has(served: Served, topic: str) -> None:
    """Wait (at most 10 s) until list_topics shows ``topic``."""
    async with asyncio.timeout(10):
        # The graph has no event to wait on: it is asked again until it shows the topic, within the timeout.
        while topic not in str((await served.tool("list_topics", {})).content):  # noqa: ASYNC110
            await asyncio.sleep(0.05)


def publish_service_arguments(
    served: Served, service: str, service_type: str, request: dict[str, Any]
) -> dict[str, Any]:
    """Arguments for the ``publish_service`` tool; optional fields are left to the tool's defaults."""
    arguments: dict[str, Any] = {"service": service, "service_type": service_type, "request": request}
    schema = served.tools["publish_service"].input_schema
    return {key: value for key, value in arguments.items() if key in schema.get("properties", arguments)}
