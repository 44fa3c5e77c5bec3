"""MCP over Streamable HTTP (the SDK's transport), with bearer-token or OAuth 2.1 authentication.

Everything here is the SDK's documented surface: ``Server.streamable_http_app(auth=AuthSettings,
token_verifier=...)`` puts its bearer middleware in front of ``/mcp`` (401 with ``WWW-Authenticate: Bearer
...`` for a missing or bad token, 403 for a missing scope) and, in OAuth mode, serves the protected-resource
metadata (RFC 9728) the MCP spec asks for at ``/.well-known/oauth-protected-resource/mcp``;
``streamable_http_app`` checks ``Host`` and ``Origin`` against the allowed lists (DNS-rebinding protection);
uvicorn serves the app, with TLS when given a certificate.

Two verifiers: :class:`StaticTokens` (``name token`` pairs; the caller is the token's name) and
:class:`JwtVerifier` (signature against the issuer's JWKS, ``iss``, ``aud``, ``exp``; the caller is the
subject). A token is compared in constant time and is never logged; neither is an ``Authorization`` header.
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import hmac
import json
import logging
import math
import signal
import socket
import threading
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Any

import jwt
import uvicorn
from mcp.server import Server
from mcp.server.auth.provider import AccessToken
from mcp.server.auth.settings import AuthSettings
from mcp.server.transport_security import TransportSecuritySettings

from rosbridge_mcp_server.config import ConfigError
from rosbridge_mcp_server.config.http import MCP_PATH, HttpSettings, OAuthSettings
from rosbridge_mcp_server.robot.text import NAME_CHARS, shown
from rosbridge_mcp_server.server.shutdown import stop_robots

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.session import RobotSession

__all__ = ["JwtVerifier", "StaticTokens", "auth_options", "listen_http", "serve_http"]

_log = logging.getLogger(__name__)

#: Algorithms accepted for JWT access tokens: asymmetric only (a shared secret lets the server mint them).
JWT_ALGORITHMS = ["RS256", "RS384", "RS512", "PS256", "PS384", "PS512", "ES256", "ES384", "ES512", "EdDSA"]


class StaticTokens:
    """``TokenVerifier`` for named bearer tokens; the caller is the name."""

    def __init__(self, tokens: tuple[tuple[str, str], ...]) -> None:
        # Digests, compared in constant time: neither the token's length nor its prefix leaks.
        self._digests = [(name, hashlib.sha256(token.encode()).digest()) for name, token in tokens]

    async def verify_token(self, token: str) -> AccessToken | None:
        digest = hashlib.sha256(token.encode("utf-8", errors="replace")).digest()
        found = None
        for name, known in self._digests:
            if hmac.compare_digest(digest, known):
                found = name
        if found is None:
            return None
        return AccessToken(token=token, client_id=found, scopes=[])


class JwtVerifier:
    """``TokenVerifier`` for JWT access tokens: signed by a key of the issuer's JWKS, for this audience, not
    expired. The caller is the token's subject (``sub``), else its client (``client_id`` / ``azp``)."""

    def __init__(self, settings: OAuthSettings) -> None:
        self._settings = settings
        self._jwks_client: jwt.PyJWKClient | None = None
        self._keys: jwt.PyJWKSet | None = None
        if settings.jwks.startswith(("http://", "https://")):
            self._jwks_client = jwt.PyJWKClient(settings.jwks, cache_keys=True, lifespan=300)
        else:
            self._keys = jwt.PyJWKSet.from_dict(json.loads(Path(settings.jwks).read_text(encoding="utf-8")))

    async def verify_token(self, token: str) -> AccessToken | None:
        try:
            key = await self._signing_key(token)
            claims: dict[str, Any] = jwt.decode(
                token,
                key,
                algorithms=JWT_ALGORITHMS,
                audience=self._settings.audience,
                issuer=self._settings.issuer,
                options={"require": ["exp", "iss", "aud"]},
                leeway=30,
            )
        except (jwt.PyJWTError, ValueError, KeyError, TypeError, OverflowError) as exc:
            # (PyJWT reads exp with int(): an infinite one overflows.)
            # The reason, never the token.
            _log.info("refused a JWT access token: %s", type(exc).__name__)
            return None
        problem = _claim_problem(claims)
        if problem is not None:
            _log.info("refused a JWT access token: %s", problem)
            return None
        scope = claims.get("scope", claims.get("scp", ""))
        scopes = scope.split() if isinstance(scope, str) else list(scope)
        client = claims.get("client_id") or claims.get("azp") or claims.get("sub") or "unknown"
        subject = claims.get("sub")
        # The caller is named in the audit (stderr, the file, the console): shown escaped, so a subject with a
        # newline cannot write a line of its own.
        return AccessToken(
            token=token,
            client_id=shown(client, NAME_CHARS),
            scopes=scopes,
            expires_at=int(claims["exp"]),
            resource=self._settings.resource,
            subject=shown(subject, NAME_CHARS) if subject is not None else None,
            claims={"iss": claims.get("iss")},
        )

    async def _signing_key(self, token: str) -> Any:
        if self._jwks_client is not None:
            # PyJWKClient fetches (and caches) the JWKS with urllib: off the event loop.
            signing = await asyncio.to_thread(self._jwks_client.get_signing_key_from_jwt, token)
            return signing.key
        assert self._keys is not None
        kid = jwt.get_unverified_header(token).get("kid")
        for candidate in self._keys.keys:
            if kid is None or candidate.key_id == kid:
                return candidate.key
        raise KeyError("no key with the token's kid")


#: The claims read besides those PyJWT checks, each with the JSON type it must have when present.
_STRING_CLAIMS = ("sub", "client_id", "azp")


def _claim_problem(claims: dict[str, Any]) -> str | None:
    """Why a validly signed token's claims cannot be read (a claim of the wrong JSON type), or ``None``.

    A signature says who wrote a token, not that it is well formed: ``"scope": null`` once raised inside the
    verifier, and the caller got HTTP 500 instead of 401.
    """
    for name in _STRING_CLAIMS:
        if name in claims and not isinstance(claims[name], str):
            return f"its {name} claim is not a string"
    for name in ("scope", "scp"):
        value = claims.get(name, "")
        if not isinstance(value, str) and not (
            isinstance(value, list) and all(isinstance(item, str) for item in value)
        ):
            return f"its {name} claim is neither a string nor a list of strings"
    exp = claims.get("exp")
    if isinstance(exp, bool) or not isinstance(exp, int | float) or not math.isfinite(exp):
        return "its exp claim is not a number"
    return None


def auth_options(settings: HttpSettings) -> dict[str, Any]:
    """``Server.streamable_http_app`` keyword arguments for the settings' authentication (none without tokens
    or OAuth)."""
    if settings.oauth is not None:
        oauth = settings.oauth
        return {
            "auth": AuthSettings(
                issuer_url=oauth.issuer,  # type: ignore[arg-type]
                resource_server_url=oauth.resource,  # type: ignore[arg-type]
                required_scopes=list(oauth.scopes) or None,
                # JwtVerifier checks the audience itself.
                validate_token_resource=False,
            ),
            "token_verifier": JwtVerifier(oauth),
        }
    if settings.tokens:
        return {
            "auth": AuthSettings(
                # Required by the settings, used only in OAuth metadata, which static tokens do not serve.
                issuer_url=settings.url,  # type: ignore[arg-type]
                resource_server_url=None,
            ),
            "token_verifier": StaticTokens(settings.tokens),
        }
    return {}


def http_app(server: Server[Any], settings: HttpSettings) -> Any:
    """The Starlette app serving *server* at ``/mcp`` with the authentication and the DNS-rebinding protection
    of *settings*."""
    return server.streamable_http_app(
        streamable_http_path=MCP_PATH,
        transport_security=TransportSecuritySettings(
            enable_dns_rebinding_protection=True,
            allowed_hosts=list(settings.allowed_hosts),
            allowed_origins=list(settings.allowed_origins),
        ),
        host=settings.host,
        **auth_options(settings),
    )


async def serve_http(
    server: Server[Any],
    settings: HttpSettings,
    *,
    sock: socket.socket | None = None,
    robots: Sequence[RobotSession] = (),
) -> None:
    """Serve *server* over Streamable HTTP until SIGTERM / Ctrl-C (or cancellation).

    ``sock``: an already listening socket to serve on instead of binding ``settings.host:port`` (tests bind
    port 0 themselves, so the port is known and connections wait in its backlog until the server accepts).
    On the first signal, what the server set going on *robots* is stopped before uvicorn shuts down.
    """
    config = uvicorn.Config(
        http_app(server, settings),
        host=settings.host,
        port=settings.port,
        ssl_certfile=settings.tls_cert,
        ssl_keyfile=settings.tls_key,
        # Our logging (stderr, our format and redaction) stays; uvicorn logs through it.
        log_config=None,
        access_log=False,
        lifespan="on",
        ws="none",
        server_header=False,
        timeout_graceful_shutdown=2,
    )
    http = _StoppingFirst(config, robots)
    if sock is None:
        sock = listen_http(settings)
    auth = "bearer tokens" if settings.tokens else "OAuth JWTs" if settings.oauth else "no authentication"
    _log.info("serving MCP on %s (%s)", _sock_url(sock, settings), auth)
    started = time.monotonic()
    serving = asyncio.ensure_future(http.serve(sockets=[sock]))
    try:
        await asyncio.shield(serving)
    except asyncio.CancelledError:
        # Cancelled (a test, an embedding program): shut down as on SIGTERM, so the sessions' tool calls are
        # cancelled and the lifespan closes the robot's client.
        http.should_exit = True
        await serving
        raise
    _log.info("HTTP server stopped after %.0f s", time.monotonic() - started)


class _StoppingFirst(uvicorn.Server):
    """uvicorn's server, stopping the robots before it shuts down, and only once.

    uvicorn takes a second Ctrl-C as "force quit": it skips the wait for the sessions (whose tool calls
    cancel their goals as they unwind) and the lifespan (which stops the robots and closes the clients), and
    a goal went on driving after the process had gone. Here the first signal stops the robots
    (``shutdown.py``) and then hands the signal to uvicorn's graceful shutdown; later ones are only logged.
    """

    def __init__(self, config: uvicorn.Config, robots: Sequence[RobotSession]) -> None:
        super().__init__(config)
        self._robots = robots
        self._signalled = False
        self._stopping: set[asyncio.Task[None]] = set()

    def handle_exit(self, sig: int, frame: FrameType | None) -> None:
        # A signal handler (signal.signal): only hand the work to the event loop.
        if self._signalled:
            _log.info("signal %d: already stopping the robot and shutting down", sig)
            return
        self._signalled = True
        _log.info("signal %d: stopping the robot, then shutting down", sig)
        asyncio.get_running_loop().call_soon_threadsafe(self._stop_first, sig)

    @contextlib.contextmanager
    def capture_signals(self) -> Iterator[None]:
        """uvicorn's signals and SIGHUP (the terminal the server runs in closed: a window, an ssh session),
        whose default ended the process at once, goals running."""
        hangup = getattr(signal, "SIGHUP", None)
        if hangup is None or threading.current_thread() is not threading.main_thread():
            with super().capture_signals():
                yield
            return
        previous = signal.signal(hangup, self.handle_exit)
        try:
            with super().capture_signals():
                yield
        finally:
            signal.signal(hangup, previous)

    def _stop_first(self, sig: int) -> None:
        task = asyncio.get_running_loop().create_task(self._stop_then_exit(sig))
        self._stopping.add(task)
        task.add_done_callback(self._stopping.discard)

    async def _stop_then_exit(self, sig: int) -> None:
        try:
            await stop_robots(self._robots)
        finally:
            super().handle_exit(sig, None)


def listen_http(settings: HttpSettings, backlog: int = 2048) -> socket.socket:
    """The MCP HTTP listener's socket, bound and listening; :class:`ConfigError` naming ``--bind`` when not.

    Bound before serving, so the log can name the port (``--bind HOST:0`` picks a free one) and a client that
    read it finds the port open: connections wait in the backlog until uvicorn accepts. (uvicorn's own
    ``bind_socket`` would log the bare error and exit the process, without saying which listener failed.)
    """
    family = socket.AF_INET6 if ":" in settings.host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((settings.host, settings.port))
        sock.listen(backlog)
    except OSError as exc:
        sock.close()
        raise ConfigError(
            f"the MCP HTTP listener (--bind) cannot listen on {settings.host}:{settings.port}: "
            f"{exc.strerror or exc}; give it another address with --bind HOST:PORT (port 0: any free port)"
        ) from None
    sock.setblocking(False)
    return sock


def _sock_url(sock: socket.socket, settings: HttpSettings) -> str:
    host, port = sock.getsockname()[:2]
    shown = f"[{host}]" if ":" in host else host
    return f"{settings.scheme}://{shown}:{port}{MCP_PATH}"
