"""How the MCP server is reached: stdio, or Streamable HTTP with its address, authentication and TLS.

Read once by the CLI; each setting chosen by the one rule of :mod:`.sources` (a flag beats the environment,
which beats the default):

* ``--transport stdio|http`` / ``ROSBRIDGE_MCP_TRANSPORT`` (default stdio);
* ``--bind HOST:PORT`` / ``ROSBRIDGE_MCP_BIND`` (default ``127.0.0.1:8765``; the path is ``/mcp``);
* ``--auth-tokens FILE`` (one ``name token`` per line, ``#`` comments) / ``ROSBRIDGE_MCP_AUTH_TOKENS`` (the
  same pairs, separated by newlines or commas, for hosts that pass secrets in the environment);
* ``--oauth-issuer URL``, ``--oauth-audience``, ``--oauth-jwks URL|FILE``, ``--oauth-resource URL``,
  ``--oauth-scopes a,b`` / ``ROSBRIDGE_MCP_OAUTH_*``: JWT access tokens from an OAuth 2.1 server;
* ``--allow-host NAME[:PORT]`` / ``--allow-origin URL`` (repeatable) / ``ROSBRIDGE_MCP_ALLOWED_HOSTS``,
  ``ROSBRIDGE_MCP_ALLOWED_ORIGINS`` (comma lists): the DNS-rebinding protection's extra names (a reverse
  proxy's, the robot's DNS name);
* ``--tls-cert FILE`` / ``--tls-key FILE`` / ``ROSBRIDGE_MCP_TLS_CERT``, ``ROSBRIDGE_MCP_TLS_KEY``;
* ``--behind-tls-proxy`` / ``ROSBRIDGE_MCP_BEHIND_TLS_PROXY=1``: a proxy in front terminates TLS.

The server refuses to listen beyond loopback without authentication, and without TLS (its own, or a proxy's
that ``--behind-tls-proxy`` states): bearer tokens must not cross a network in clear. Either is a
:class:`ConfigError` (exit 2).
Tokens are secrets: they are kept as given only to compare with, and never shown (``repr`` hides them).
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import socket
import stat
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal
from urllib.parse import urlsplit

from rosbridge_mcp_server.config.addresses import is_loopback
from rosbridge_mcp_server.config.sources import FLAG, ConfigError, Given, Setting, Sources

__all__ = [
    "DEFAULT_BIND",
    "MCP_PATH",
    "MIN_TOKEN_LENGTH",
    "HttpSettings",
    "OAuthSettings",
    "Transport",
    "load_http_settings",
    "parse_tokens",
]

_log = logging.getLogger(__name__)

Transport = Literal["stdio", "http"]
DEFAULT_BIND = "127.0.0.1:8765"
MCP_PATH = "/mcp"
#: Shortest bearer token accepted: a guessable token on a robot's network is no authentication.
MIN_TOKEN_LENGTH = 16
_NAME = re.compile(r"^[A-Za-z0-9_.@-]{1,64}$")

# Each setting's flag and environment variable: the one rule in :mod:`.sources` chooses among them.
TRANSPORT = Setting("--transport", "ROSBRIDGE_MCP_TRANSPORT")
BIND = Setting("--bind", "ROSBRIDGE_MCP_BIND")
#: The flag names a file of ``name token`` lines; the variable holds the pairs themselves.
AUTH_TOKENS = Setting("--auth-tokens", "ROSBRIDGE_MCP_AUTH_TOKENS")
#: Repeatable flags; the variables hold comma lists.
ALLOWED_HOSTS = Setting("--allow-host", "ROSBRIDGE_MCP_ALLOWED_HOSTS")
ALLOWED_ORIGINS = Setting("--allow-origin", "ROSBRIDGE_MCP_ALLOWED_ORIGINS")
TLS_CERT = Setting("--tls-cert", "ROSBRIDGE_MCP_TLS_CERT")
TLS_KEY = Setting("--tls-key", "ROSBRIDGE_MCP_TLS_KEY")
OAUTH_ISSUER = Setting("--oauth-issuer", "ROSBRIDGE_MCP_OAUTH_ISSUER")
OAUTH_AUDIENCE = Setting("--oauth-audience", "ROSBRIDGE_MCP_OAUTH_AUDIENCE")
OAUTH_JWKS = Setting("--oauth-jwks", "ROSBRIDGE_MCP_OAUTH_JWKS")
OAUTH_RESOURCE = Setting("--oauth-resource", "ROSBRIDGE_MCP_OAUTH_RESOURCE")
OAUTH_SCOPES = Setting("--oauth-scopes", "ROSBRIDGE_MCP_OAUTH_SCOPES")
#: An on-only switch: a proxy in front terminates TLS.
BEHIND_TLS_PROXY = Setting("--behind-tls-proxy", "ROSBRIDGE_MCP_BEHIND_TLS_PROXY")


@dataclass(frozen=True)
class OAuthSettings:
    """JWT access tokens checked against an issuer's keys (``jwks``: a URL or a file) and an audience."""

    issuer: str
    audience: str
    jwks: str
    resource: str
    scopes: tuple[str, ...] = ()


@dataclass(frozen=True)
class HttpSettings:
    """The transport and, for HTTP, where it listens and whom it lets in."""

    transport: Transport = "stdio"
    host: str = "127.0.0.1"
    port: int = 8765
    #: ``(name, token)`` pairs: the name is what the audit shows for the caller.
    tokens: tuple[tuple[str, str], ...] = field(default=(), repr=False)
    oauth: OAuthSettings | None = None
    allowed_hosts: tuple[str, ...] = ()
    allowed_origins: tuple[str, ...] = ()
    tls_cert: str | None = None
    tls_key: str | None = None
    #: The person said a proxy in front terminates TLS (the server itself then speaks plain HTTP).
    behind_tls_proxy: bool = False

    @property
    def authenticated(self) -> bool:
        """Whether every HTTP request must carry a valid bearer token."""
        return bool(self.tokens) or self.oauth is not None

    @property
    def scheme(self) -> str:
        return "https" if self.tls_cert else "http"

    @property
    def url(self) -> str:
        """Where a client on this machine reaches the server (the bind address, path included)."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{self.scheme}://{host}:{self.port}{MCP_PATH}"


def load_http_settings(
    environ: Mapping[str, str],
    *,
    transport: str | None = None,
    bind: str | None = None,
    auth_tokens: str | None = None,
    allow_hosts: Sequence[str] | None = None,
    allow_origins: Sequence[str] | None = None,
    tls_cert: str | None = None,
    tls_key: str | None = None,
    oauth_issuer: str | None = None,
    oauth_audience: str | None = None,
    oauth_jwks: str | None = None,
    oauth_resource: str | None = None,
    oauth_scopes: str | None = None,
    behind_tls_proxy: bool = False,
) -> HttpSettings:
    """:class:`HttpSettings` from flags (``None``: not given) and the environment, or :class:`ConfigError`."""
    sources = Sources(
        {
            TRANSPORT.flag: transport,
            BIND.flag: bind,
            AUTH_TOKENS.flag: auth_tokens,
            ALLOWED_HOSTS.flag: list(allow_hosts) if allow_hosts else None,
            ALLOWED_ORIGINS.flag: list(allow_origins) if allow_origins else None,
            TLS_CERT.flag: tls_cert,
            TLS_KEY.flag: tls_key,
            OAUTH_ISSUER.flag: oauth_issuer,
            OAUTH_AUDIENCE.flag: oauth_audience,
            OAUTH_JWKS.flag: oauth_jwks,
            OAUTH_RESOURCE.flag: oauth_resource,
            OAUTH_SCOPES.flag: oauth_scopes,
            BEHIND_TLS_PROXY.flag: behind_tls_proxy,
        },
        environ,
    )
    given_transport, transport_source = sources.text(TRANSPORT)
    chosen = (given_transport or "stdio").lower()
    if chosen not in ("stdio", "http"):
        raise ConfigError(f"{transport_source}: {chosen!r} is not a transport; use stdio or http")
    if chosen == "stdio":
        flags = (bind, auth_tokens, tls_cert, oauth_issuer, behind_tls_proxy)
        given = [name for name, value in zip(_HTTP_ONLY, flags, strict=True) if value]
        if given:
            raise ConfigError(f"{given[0]} needs --transport http (stdio has no address and no tokens)")
        return HttpSettings()
    settings = _http(sources)
    _refuse_exposed(settings)
    return settings


def _http(sources: Sources) -> HttpSettings:
    """The HTTP transport's settings as *sources* choose them (address, tokens or OAuth, TLS, allowed hosts
    and origins)."""
    bind_value, bind_source = sources.text(BIND)
    host, port = parse_bind(bind_value if bind_value is not None else DEFAULT_BIND, source=bind_source)
    tokens = _tokens(sources.pick(AUTH_TOKENS))
    cert, key = _tls_files(sources)
    oauth = _oauth(sources, HttpSettings(transport="http", host=host, port=port, tls_cert=cert))
    if oauth is not None and tokens:
        raise ConfigError("give either --auth-tokens or --oauth-issuer, not both")
    proxied = sources.switch(BEHIND_TLS_PROXY) is not None
    hosts = _list(sources.pick(ALLOWED_HOSTS))
    origins = _list(sources.pick(ALLOWED_ORIGINS))
    return HttpSettings(
        transport="http",
        host=host,
        port=port,
        tokens=tokens,
        oauth=oauth,
        allowed_hosts=allowed_hosts(host, port, hosts),
        allowed_origins=allowed_origins(host, port, hosts, origins),
        tls_cert=cert,
        tls_key=key,
        behind_tls_proxy=proxied,
    )


#: The flags only the HTTP transport takes, in load_http_settings' order.
_HTTP_ONLY = ("--bind", "--auth-tokens", "--tls-cert", "--oauth-issuer", "--behind-tls-proxy")


def _tls_files(sources: Sources) -> tuple[str | None, str | None]:
    """The HTTPS certificate and key files, checked: not empty, a key only with a certificate, both there."""
    cert, cert_source = sources.text(TLS_CERT)
    key, key_source = sources.text(TLS_KEY)
    for path, name in ((cert, cert_source), (key, key_source)):
        if path is not None and not path.strip():
            raise ConfigError(f"{name} is empty; give a file path")
    if key and not cert:
        raise ConfigError(f"{key_source} needs --tls-cert")
    for path, name in ((cert, cert_source), (key, key_source)):
        if path and not Path(path).is_file():
            raise ConfigError(f"{name}: {path!r} is not a readable file")
    return cert, key


def _refuse_exposed(settings: HttpSettings) -> None:
    """Beyond loopback: no listening without authentication, nor in plain HTTP without a TLS proxy."""
    host, port = settings.host, settings.port
    if not settings.authenticated and not is_loopback(host):
        raise ConfigError(
            f"refusing to listen on {host}:{port} without authentication: anyone on the network could drive "
            "the robot. Give --auth-tokens FILE (or ROSBRIDGE_MCP_AUTH_TOKENS) or --oauth-issuer URL, or "
            "bind to 127.0.0.1"
        )
    if not settings.tls_cert and not settings.behind_tls_proxy and not is_loopback(host):
        raise ConfigError(
            f"refusing to listen on {host}:{port} in plain HTTP: the bearer tokens would cross the network "
            "in clear text. Give --tls-cert FILE and --tls-key FILE (HTTPS), or --behind-tls-proxy when a "
            "reverse proxy in front terminates TLS, or bind to 127.0.0.1 (docs/deployment.md)"
        )


def _list(chosen: Given | None) -> list[str]:
    # Repeated flags, or one comma list in the variable.
    if chosen is None:
        return []
    items = chosen.value if chosen.rank == FLAG else chosen.value.split(",")
    return [item.strip() for item in items if item.strip()]


def parse_bind(value: str, *, source: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[::1]:8765`` for IPv6) as a host and a port."""
    match = re.fullmatch(r"\[([0-9A-Fa-f:.]+)\]:(\d+)|([^:\[\]\s]+):(\d+)", value.strip())
    if match is None:
        raise ConfigError(f"{source}: {value!r} is not HOST:PORT (e.g. 127.0.0.1:8765 or [::1]:8765)")
    host = match.group(1) or match.group(3)
    port = int(match.group(2) or match.group(4))
    if not 0 <= port < 65536:
        raise ConfigError(f"{source}: port {port} is not between 0 (any free port) and 65535")
    return host, port


def _tokens(chosen: Given | None) -> tuple[tuple[str, str], ...]:
    # The flag names a file of pairs; the variable holds the pairs themselves (hosts pass secrets that way).
    if chosen is None:
        return ()
    if chosen.rank != FLAG:
        return parse_tokens(re.split(r"[\n,]", chosen.value), source=chosen.source)
    path = chosen.value
    try:
        info = os.stat(path)
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"--auth-tokens: cannot read {path!r}: {exc}") from None
    if info.st_mode & (stat.S_IRWXG | stat.S_IRWXO):
        # Not fatal (a container may mount it so), but worth a line: it holds the keys to the robot.
        _log.warning("the token file %s can be read by other users (chmod 600 it)", path)
    return parse_tokens(text.splitlines(), source=f"--auth-tokens {path}")


def parse_tokens(lines: Sequence[str], *, source: str) -> tuple[tuple[str, str], ...]:
    """``name token`` pairs, one per entry (blank entries and ``#`` comments skipped); the error never shows
    a token."""
    pairs: list[tuple[str, str]] = []
    for number, raw in enumerate(lines, 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split()
        if len(parts) != 2:
            raise ConfigError(f"{source}: entry {number} is not 'name token' (two words)")
        name, token = parts
        if not _NAME.match(name):
            raise ConfigError(f"{source}: entry {number}: the name may use letters, digits and _.@- only")
        if len(token) < MIN_TOKEN_LENGTH:
            raise ConfigError(
                f"{source}: the token of {name!r} is shorter than {MIN_TOKEN_LENGTH} characters; make "
                "one with `openssl rand -hex 32`"
            )
        if any(name == seen for seen, _ in pairs):
            raise ConfigError(f"{source}: the name {name!r} is given twice")
        if any(token == seen for _, seen in pairs):
            raise ConfigError(f"{source}: {name!r} has the same token as another name")
        pairs.append((name, token))
    if not pairs:
        raise ConfigError(f"{source}: no tokens in it")
    return tuple(pairs)


def _oauth(sources: Sources, settings: HttpSettings) -> OAuthSettings | None:
    issuer, issuer_source = sources.text(OAUTH_ISSUER)
    audience, _ = sources.text(OAUTH_AUDIENCE)
    jwks, jwks_source = sources.text(OAUTH_JWKS)
    resource, resource_source = sources.text(OAUTH_RESOURCE)
    scopes, _ = sources.text(OAUTH_SCOPES)
    if issuer is None:
        others = [
            name for name, value in (("audience", audience), ("jwks", jwks), ("resource", resource)) if value
        ]
        if others:
            raise ConfigError(f"--oauth-{others[0]} needs --oauth-issuer")
        return None
    _check_http_url(issuer, issuer_source)
    if resource is None and settings.port == 0:
        raise ConfigError("--oauth-issuer with --bind on port 0 needs --oauth-resource (this server's URL)")
    resource_url = resource or settings.url
    _check_http_url(resource_url, resource_source)
    if jwks is None:
        jwks = issuer.rstrip("/") + "/.well-known/jwks.json"
    elif not jwks.startswith(("https://", "http://")) and not Path(jwks).is_file():
        raise ConfigError(f"{jwks_source}: {jwks!r} is neither an http(s) URL nor a readable file")
    return OAuthSettings(
        issuer=issuer,
        audience=audience or resource_url,
        jwks=jwks,
        resource=resource_url,
        scopes=tuple(s.strip() for s in (scopes or "").split(",") if s.strip()),
    )


def _check_http_url(value: str, source: str) -> None:
    parts = urlsplit(value)
    if parts.scheme not in ("http", "https") or not parts.hostname:
        raise ConfigError(f"{source}: {value!r} is not an http(s) URL")


def allowed_hosts(host: str, port: int, extra: Sequence[str]) -> tuple[str, ...]:
    """``Host`` header values the server answers (DNS-rebinding protection): loopback, the bound address,
    the machine's own names when bound to every interface, and *extra* (a bare name allows any port)."""
    # Any port on loopback names (as the SDK's own default): a rebinding attack needs a name of its own.
    out = ["127.0.0.1:*", "localhost:*", "[::1]:*"]
    names: list[str] = []
    if host in ("0.0.0.0", "::"):
        names += _own_names()
    elif not is_loopback(host):
        names.append(f"[{host}]" if ":" in host else host)
    out += [f"{name}:{port or '*'}" for name in names]
    for item in extra:
        out.append(item if re.search(r":(\d+|\*)$", item) and not item.endswith("]") else f"{item}:*")
        if not re.search(r":(\d+|\*)$", item):
            # Behind a reverse proxy on the default port, Host carries no port at all.
            out.append(item)
    return tuple(dict.fromkeys(out))


def allowed_origins(host: str, port: int, hosts: Sequence[str], extra: Sequence[str]) -> tuple[str, ...]:
    """``Origin`` values accepted from browsers: the allowed hosts' own, over http and https, and *extra*."""
    out: list[str] = []
    for entry in allowed_hosts(host, port, hosts):
        out += [f"http://{entry}", f"https://{entry}"]
    out += [item.rstrip("/") for item in extra]
    return tuple(dict.fromkeys(out))


def _own_names() -> list[str]:
    names = [socket.gethostname()]
    with contextlib.suppress(OSError):
        names += socket.gethostbyname_ex(socket.gethostname())[2]
    return names
