"""Serving the console next to the MCP server: uvicorn on the same event loop, and the one-time URL.

The URL (``http://HOST:PORT/#secret=...``) is written once on stderr, which the person starting the server
sees and the model does not. The secret travels in the URL's fragment, which the browser never sends to any
server; the page keeps it for the tab and takes it out of the address bar.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import secrets
import socket
from collections.abc import AsyncIterator, Generator
from dataclasses import dataclass

import uvicorn

from rosbridge_mcp_server.config.console import ConsoleSettings
from rosbridge_mcp_server.console.hub import ConsoleHub
from rosbridge_mcp_server.console.web import console_app

__all__ = ["RunningConsole", "open_console"]

_log = logging.getLogger("rosbridge_mcp_server.console")

#: How long closing waits for open event streams before it drops them.
CLOSE_GRACE = 1


@dataclass(frozen=True)
class RunningConsole:
    """A console being served: its hub, its address and the one-time URL with the secret."""

    hub: ConsoleHub
    base_url: str  #: http(s)://HOST:PORT/
    secret: str

    @property
    def url(self) -> str:
        return f"{self.base_url}#secret={self.secret}"


class _Server(uvicorn.Server):
    """uvicorn without its signal handlers: the MCP server owns SIGTERM and Ctrl-C."""

    @contextlib.contextmanager
    def capture_signals(self) -> Generator[None, None, None]:
        yield


@contextlib.asynccontextmanager
async def open_console(settings: ConsoleSettings, hub: ConsoleHub) -> AsyncIterator[RunningConsole]:
    """Serve the console of ``hub`` until the block ends; yields where it is and its URL."""
    secret = secrets.token_urlsafe(32)
    sock = _bind(settings.host, settings.port)
    port = sock.getsockname()[1]
    shown_host = f"[{settings.host}]" if ":" in settings.host else settings.host
    allowed = {f"{shown_host}:{port}".lower()}
    if settings.loopback:
        allowed |= {f"localhost:{port}", f"127.0.0.1:{port}", f"[::1]:{port}"}
    config = uvicorn.Config(
        console_app(hub, secret, allowed),
        log_config=None,
        log_level="warning",
        access_log=False,
        lifespan="off",
        ssl_certfile=settings.cert,
        ssl_keyfile=settings.key,
        timeout_graceful_shutdown=CLOSE_GRACE,
    )
    server = _Server(config)
    serving = asyncio.create_task(server.serve(sockets=[sock]), name="console")
    looking = asyncio.create_task(hub.look(), name="console look")
    running = RunningConsole(hub, f"{settings.scheme}://{shown_host}:{port}/", secret)
    # Confirmations by link (URL-mode elicitation) send the person here.
    hub.operator.link_base = running.base_url
    try:
        yield running
    finally:
        hub.operator.link_base = None
        hub.close()
        server.should_exit = True
        looking.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await looking
        await serving
        sock.close()


def _bind(host: str, port: int) -> socket.socket:
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    info = socket.getaddrinfo(host, port, family, socket.SOCK_STREAM)
    sock = socket.socket(info[0][0], socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind(info[0][4])
        sock.listen(128)
    except OSError:
        sock.close()
        raise
    sock.setblocking(False)
    return sock
