"""Item 10: ``list_topics`` over Streamable HTTP against stdio, and N HTTP sessions at once."""

from __future__ import annotations

import asyncio
import contextlib
import os
import time
from collections.abc import AsyncIterator
from typing import IO

import httpx2
import psutil
from mcp.client.session import ClientSession
from mcp.client.streamable_http import streamable_http_client

from benchmarks.harness import (
    REPO,
    Context,
    Row,
    Subject,
    interleave,
    log,
    ms,
    our_server_command,
    timing_row,
    verdict,
)

__all__: list[str] = []

# ------------------------------------------------------------------------------- item 10: Streamable HTTP

HTTP_TOKEN = "bench-token-0123456789abcdef0123"


@contextlib.asynccontextmanager
async def http_server(url: str, errlog: IO[str]) -> AsyncIterator[tuple[str, psutil.Process]]:
    """Our console script on Streamable HTTP (loopback, a free port, a bearer token): its URL and process."""
    command = [*our_server_command(url), "--transport", "http", "--bind", "127.0.0.1:0"]
    env = {**os.environ, "ROSBRIDGE_MCP_AUTH_TOKENS": f"bench {HTTP_TOKEN}"}
    process = await asyncio.create_subprocess_exec(
        *command, cwd=str(REPO), env=env, stdin=asyncio.subprocess.DEVNULL, stderr=asyncio.subprocess.PIPE
    )
    assert process.stderr is not None
    draining: asyncio.Task[None] | None = None
    try:
        async with asyncio.timeout(60):
            while True:
                line = (await process.stderr.readline()).decode(errors="replace")
                if not line:
                    raise RuntimeError("the HTTP server exited before it listened")
                errlog.write(line)
                if "serving MCP on " in line:
                    served_at = line.split("serving MCP on ", 1)[1].split()[0]
                    break

        async def drain() -> None:
            assert process.stderr is not None
            while chunk := await process.stderr.readline():
                errlog.write(chunk.decode(errors="replace"))

        draining = asyncio.get_running_loop().create_task(drain())
        yield served_at, psutil.Process(process.pid)
    finally:
        if process.returncode is None:
            process.terminate()
        await asyncio.wait_for(process.wait(), 30)
        if draining is not None:
            await draining


@contextlib.asynccontextmanager
async def http_session(url: str) -> AsyncIterator[ClientSession]:
    """An initialized MCP session over the SDK's Streamable HTTP client, with the bench token."""
    headers = {"Authorization": f"Bearer {HTTP_TOKEN}"}
    async with (
        httpx2.AsyncClient(headers=headers, timeout=httpx2.Timeout(60, read=300)) as http,
        streamable_http_client(url, http_client=http) as (read, write),
        ClientSession(read, write) as session,
    ):
        await session.initialize()
        yield session


async def measure_http(ctx: Context) -> list[Row]:
    """Item 10: ``list_topics`` over Streamable HTTP against stdio (interleaved); N HTTP sessions at once."""
    ours, plan = ctx.ours, ctx.plan
    async with http_server(ctx.bridge.url, ctx.errlog) as (url, process), http_session(url) as session:

        async def over_http() -> None:
            result = await session.call_tool("list_topics", {})
            if result.is_error:
                raise RuntimeError(f"list_topics over HTTP failed: {result.content}")

        subjects = [
            Subject("list_topics_stdio", lambda: ours.tool("list_topics", {}), ours.process),
            Subject("list_topics_http", over_http, process),
        ]
        await interleave(subjects, plan, ctx.bridge_process)
        n = plan.parallel_calls
        errors: list[str] = []

        async def one_session() -> None:
            try:
                async with http_session(url) as own:
                    result = await own.call_tool("list_topics", {})
                    if result.is_error:
                        errors.append("list_topics answered with an error")
            except Exception as error:
                errors.append(f"{type(error).__name__}: {error}")

        began = time.perf_counter()
        await asyncio.gather(*(one_session() for _ in range(n)))
        sessions_s = time.perf_counter() - began
    ctx.samples.update({subject.key: subject.samples for subject in subjects})
    ctx.cpu_per_call.update({subject.key: subject.cpu_per_call() for subject in subjects})
    stdio, http = subjects[0].stats, subjects[1].stats
    per_call = timing_row(
        "10a",
        "`list_topics` over Streamable HTTP (SDK client, bearer token, loopback)",
        http,
        versus=f"{(http.median - stdio.median) * 1e3:+.2f} ms over stdio ({ms(stdio.median)})",
        verdict="info",
    )
    per_call.figures["over_stdio_s"] = http.median - stdio.median
    stdio_row = timing_row(
        "10·", "`list_topics` over stdio, same run", stdio, versus="reference", verdict="info"
    )
    if errors:
        log.error("HTTP sessions failed: %s", "; ".join(sorted(set(errors))[:5]))
    sessions = Row(
        "10b",
        f"{n} HTTP sessions at once: initialize + `list_topics` each",
        n=n,
        median=ms(sessions_s),
        versus=f"{len(errors)} errors",
        target="0 errors",
        verdict=verdict(not errors) if n >= 100 else f"n/a ({n} sessions); {len(errors)} errors",
        figures={"errors": len(errors), "wall_s": sessions_s},
    )
    return [per_call, stdio_row, sessions]
