"""The console script on stdio or on Streamable HTTP, with the SDK's own client connected to it.

``serving(transport, *flags)`` starts ``python -m rosbridge_mcp_server`` with the flags (``--transport http
--bind 127.0.0.1:0`` added for HTTP) and yields a :class:`Served`: ``connect()`` opens an MCP session (the
SDK's stdio client, or its Streamable HTTP client with an optional bearer token), and for HTTP ``url`` and the
server's stderr as it logs. HTTP readiness is the server's own "serving MCP on <url>" line, written once the
socket listens.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
import sys
from collections.abc import AsyncIterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import httpx2
from mcp.client.stdio import StdioServerParameters
from mcp.client.streamable_http import streamable_http_client

from mcp import Client

WAIT = 90.0  # a bound on an event, not a pause: a busy machine (load 10 on 2 cores) still passes
#: The handshake's first request as a client writes it by hand (id 1, the 2025 era).
INITIALIZE = {
    "jsonrpc": "2.0",
    "id": 1,
    "method": "initialize",
    "params": {
        "protocolVersion": "2025-06-18",
        "capabilities": {},
        "clientInfo": {"name": "e2e-test", "version": "0"},
    },
}
TOKEN = "operator-token-0123456789abcdef"
TOKENS = f"operator {TOKEN}\nci second-token-0123456789abcdef"


@dataclass
class Served:
    """A running server: how to connect to it, and (HTTP) where it listens and what it logged."""

    transport: str
    flags: tuple[str, ...]
    env: dict[str, str]
    url: str = ""
    process: asyncio.subprocess.Process | None = None
    stderr: list[str] = field(default_factory=list)
    drain: asyncio.Task[None] | None = None

    @contextlib.asynccontextmanager
    async def connect(
        self, token: str | None = TOKEN, mode: str = "legacy", **client: Any
    ) -> AsyncIterator[Client]:
        """An initialized MCP session: the handshake, as Claude Desktop and Inspector connect, or with
        ``mode="auto"`` the 2026-07-28 protocol (``server/discover``, no session)."""
        if self.transport == "stdio":
            parameters = StdioServerParameters(
                command=sys.executable, args=["-m", "rosbridge_mcp_server", *self.flags], env=self.env
            )
            async with Client(parameters, mode=mode, **client) as session:
                yield session
            return
        headers = {"Authorization": f"Bearer {token}"} if token else {}
        async with (
            httpx2.AsyncClient(headers=headers, timeout=httpx2.Timeout(WAIT, read=300)) as http,
            Client(streamable_http_client(self.url, http_client=http), mode=mode, **client) as session,
        ):
            yield session


def _env(extra: Mapping[str, str] | None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROSBRIDGE_")}
    return {**env, **(extra or {})}


@contextlib.asynccontextmanager
async def serving(
    transport: str, *flags: str, env: Mapping[str, str] | None = None, tokens: bool = True
) -> AsyncIterator[Served]:
    """The server on *transport* with *flags*; HTTP servers get the test tokens unless ``tokens=False``."""
    environment = _env(env)
    if transport == "stdio":
        yield Served("stdio", flags, environment)
        return
    if tokens:
        environment.setdefault("ROSBRIDGE_MCP_AUTH_TOKENS", TOKENS)
    served = await start_http(*flags, env=environment)
    try:
        yield served
    finally:
        await stop(served)


async def start_http(*flags: str, env: dict[str, str], new_group: bool = False) -> Served:
    """``--transport http --bind 127.0.0.1:0`` plus *flags*; returns once the server said where it listens.
    ``new_group``: in a process group of its own (a test may then signal the group, as a terminal does)."""
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosbridge_mcp_server",
        "--transport",
        "http",
        "--bind",
        "127.0.0.1:0",
        *flags,
        stdin=asyncio.subprocess.DEVNULL,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
        env=env,
        start_new_session=new_group,
    )
    served = Served("http", flags, env, process=process)
    assert process.stderr is not None
    try:
        async with asyncio.timeout(WAIT):
            while True:
                raw = await process.stderr.readline()
                assert raw, f"the server exited: {''.join(served.stderr)}"
                line = raw.decode(errors="replace")
                served.stderr.append(line)
                if "serving MCP on " in line:
                    served.url = line.split("serving MCP on ", 1)[1].split()[0]
                    break
    except BaseException:
        # A server that did not come up in time must not outlive the test (it would keep its port and robot).
        if process.returncode is None:
            process.kill()
        await process.wait()
        raise
    served.drain = asyncio.get_running_loop().create_task(_drain(process, served.stderr))
    return served


async def _drain(process: asyncio.subprocess.Process, lines: list[str]) -> None:
    assert process.stderr is not None
    while raw := await process.stderr.readline():
        lines.append(raw.decode(errors="replace"))


async def stop(served: Served) -> tuple[int, str]:
    """SIGTERM, then the exit code and everything the server logged."""
    process = served.process
    assert process is not None
    if process.returncode is None:
        process.send_signal(signal.SIGTERM)
    stdout = await asyncio.wait_for(process.stdout.read(), WAIT) if process.stdout else b""
    code = await asyncio.wait_for(process.wait(), WAIT)
    if served.drain is not None:
        await asyncio.wait_for(served.drain, WAIT)
    assert stdout == b"", stdout[:500]
    return code, "".join(served.stderr)
