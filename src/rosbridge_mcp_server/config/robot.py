"""The robot's settings: read once from flags, the environment and the policy file into a frozen
:class:`Config`.

Each setting is chosen by the one rule of :mod:`.sources` (flag > environment > file > default):

* where rosbridge is: ``--url`` / ``ROSBRIDGE_URL``, or ``--host`` / ``ROSBRIDGE_HOST`` and ``--port`` /
  ``ROSBRIDGE_PORT``, default ``ws://localhost:9090``. A URL beats host and port given in the same source or a
  lower one; a host or port flag beats ``ROSBRIDGE_URL``, and its missing half comes from the environment;
* ``--timeout`` / ``ROSBRIDGE_TIMEOUT``, ``--log-level`` / ``ROSBRIDGE_MCP_LOG_LEVEL``, ``--tools`` /
  ``ROSBRIDGE_MCP_TOOLS``, ``--record-dir`` / ``ROSBRIDGE_MCP_RECORD_DIR``;
* safety: ``--policy`` / ``ROSBRIDGE_MCP_POLICY`` (a TOML file), ``--read-only`` /
  ``ROSBRIDGE_MCP_READ_ONLY=1`` / the policy file's ``read_only = true`` (an on-only switch: any of them makes
  the server read-only), ``--audit-log`` / ``ROSBRIDGE_MCP_AUDIT_LOG``;
* connection security: ``--ca-file`` / ``ROSBRIDGE_CA_FILE``, ``--client-cert`` / ``ROSBRIDGE_CLIENT_CERT``,
  ``--client-key`` / ``ROSBRIDGE_CLIENT_KEY``, ``--header`` (repeatable) / ``ROSBRIDGE_HEADERS`` (one
  ``Name: value`` per line). Header values are secrets: they are never logged.

The CLI calls :func:`load_config` once, with its environment; the platform's folders are read from it here too
(``XDG_DATA_HOME`` for the default recording folder, :func:`default_record_dir`). No module outside
``config/`` and ``cli/`` reads the environment (``tests/safety/test_layering.py`` holds it).
"""

from __future__ import annotations

import ipaddress
import math
import os
import re
import ssl
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal
from urllib.parse import urlsplit

from rosbridge_mcp_server.catalogue import ALL_TOOL_NAMES, select_tools
from rosbridge_mcp_server.config.addresses import is_loopback
from rosbridge_mcp_server.config.sources import FLAG, ConfigError, Setting, Sources
from rosbridge_mcp_server.safety.policy import Policy, PolicyError, load_policy

__all__ = [
    "DEFAULT_HOST",
    "DEFAULT_PORT",
    "DEFAULT_REQUEST_TIMEOUT",
    "LOG_LEVELS",
    "MAX_TIMEOUT",
    "Config",
    "ConfigError",
    "LogLevel",
    "default_record_dir",
    "load_config",
    "plain_text_warning",
]

DEFAULT_HOST = "localhost"
DEFAULT_PORT = 9090
DEFAULT_REQUEST_TIMEOUT = 10.0
DEFAULT_CONNECT_TIMEOUT = 5.0
MAX_TIMEOUT = 300.0

LogLevel = Literal["DEBUG", "INFO", "WARNING", "ERROR", "CRITICAL"]
LOG_LEVELS: tuple[LogLevel, ...] = ("DEBUG", "INFO", "WARNING", "ERROR", "CRITICAL")


@dataclass(frozen=True)
class Config:
    """Everything the server needs to know, validated.

    ``url`` is the rosbridge WebSocket URL. With ``--demo`` the CLI starts a simulated robot and replaces
    ``url`` with the simulator's own address before anything connects (the demo's settings are the CLI's).
    """

    url: str = f"ws://{DEFAULT_HOST}:{DEFAULT_PORT}"
    request_timeout: float = DEFAULT_REQUEST_TIMEOUT
    connect_timeout: float = DEFAULT_CONNECT_TIMEOUT
    log_level: LogLevel = "INFO"
    policy: Policy = field(default_factory=Policy)
    audit_log: str | None = None
    ca_file: str | None = None
    client_cert: str | None = None
    client_key: str | None = None
    headers: tuple[tuple[str, str], ...] = field(default=(), repr=False)
    #: Names of the tools a host sees; ``None`` is every tool.
    tools: tuple[str, ...] | None = None
    #: Where ``record`` writes and ``read_recording`` reads: ``--record-dir`` (``~`` expanded), else
    #: :func:`default_record_dir` of the environment the configuration was read from (of this process's
    #: environment for a :class:`Config` built directly).
    record_dir: Path = field(default_factory=lambda: default_record_dir(os.environ))
    #: The robot's namespace on a bridge shared by several robots (``/robot2``; ``""`` none), from its
    #: fleet file entry; ``None``: not said (the navigation, transform, picture and diagnose tools find it).
    namespace: str | None = None
    #: Where a fleet robot's URL was set (``[robots.base] in --robots fleet.toml``, ``--robot base=URL``),
    #: named when it cannot be reached; ``None``: the server's own settings (ROSBRIDGE_HOST/PORT/URL).
    url_source: str | None = None

    def ssl_context(self) -> ssl.SSLContext | None:
        """The TLS context for wss:// with a private CA or a client certificate; ``None`` for the default.

        Raises :class:`ConfigError` when a file cannot be loaded (``load_config`` has tried it once already).
        """
        if self.ca_file is None and self.client_cert is None:
            return None
        try:
            context = ssl.create_default_context(cafile=self.ca_file)
        except (OSError, ssl.SSLError) as exc:
            raise ConfigError(f"CA file {self.ca_file!r} cannot be loaded: {_reason(exc)}") from None
        if self.client_cert is not None:
            try:
                context.load_cert_chain(self.client_cert, self.client_key)
            except (OSError, ssl.SSLError) as exc:
                raise ConfigError(
                    f"client certificate {self.client_cert!r}"
                    f"{f' with key {self.client_key!r}' if self.client_key else ''} cannot be loaded: "
                    f"{_reason(exc)}"
                ) from None
        return context


# Each setting's flag, environment variable and (where a file has it) key: the one rule in
# :mod:`.sources` chooses among them.
HOST = Setting("--host", "ROSBRIDGE_HOST")
PORT = Setting("--port", "ROSBRIDGE_PORT")
URL = Setting("--url", "ROSBRIDGE_URL")
TIMEOUT = Setting("--timeout", "ROSBRIDGE_TIMEOUT")
LOG_LEVEL = Setting("--log-level", "ROSBRIDGE_MCP_LOG_LEVEL")
TOOLS = Setting("--tools", "ROSBRIDGE_MCP_TOOLS")
POLICY = Setting("--policy", "ROSBRIDGE_MCP_POLICY")
#: An on-only switch; its file is the policy file (``read_only = true``).
READ_ONLY = Setting("--read-only", "ROSBRIDGE_MCP_READ_ONLY", key="read_only")
AUDIT_LOG = Setting("--audit-log", "ROSBRIDGE_MCP_AUDIT_LOG")
CA_FILE = Setting("--ca-file", "ROSBRIDGE_CA_FILE")
CLIENT_CERT = Setting("--client-cert", "ROSBRIDGE_CLIENT_CERT")
CLIENT_KEY = Setting("--client-key", "ROSBRIDGE_CLIENT_KEY")
#: Repeatable flag; the variable holds one ``Name: value`` per line.
HEADERS = Setting("--header", "ROSBRIDGE_HEADERS")
RECORD_DIR = Setting("--record-dir", "ROSBRIDGE_MCP_RECORD_DIR")


def load_config(
    environ: Mapping[str, str],
    *,
    host: str | None = None,
    port: str | int | None = None,
    url: str | None = None,
    timeout: str | float | None = None,
    log_level: str | None = None,
    policy: str | None = None,
    read_only: bool = False,
    audit_log: str | None = None,
    ca_file: str | None = None,
    client_cert: str | None = None,
    client_key: str | None = None,
    headers: Sequence[str] | None = None,
    tools: str | None = None,
    record_dir: str | None = None,
    simulated: bool = False,
) -> Config:
    """Build a :class:`Config` from command-line values (``None`` = not given) and the environment.

    *simulated*: the URL will be replaced by a simulated robot's (``--demo``), so it need not be
    ``wss://`` for TLS files. Raises :class:`ConfigError` with a one-line message naming the bad value and
    its source.
    """
    sources = Sources(
        {
            HOST.flag: host,
            PORT.flag: port,
            URL.flag: url,
            TIMEOUT.flag: timeout,
            LOG_LEVEL.flag: log_level,
            POLICY.flag: policy,
            READ_ONLY.flag: read_only,
            AUDIT_LOG.flag: audit_log,
            CA_FILE.flag: ca_file,
            CLIENT_CERT.flag: client_cert,
            CLIENT_KEY.flag: client_key,
            HEADERS.flag: list(headers) if headers else None,
            TOOLS.flag: tools,
            RECORD_DIR.flag: record_dir,
        },
        environ,
    )
    config = _chosen(sources, environ)
    _check_tls(config, simulated=simulated)
    return config


def _chosen(sources: Sources, environ: Mapping[str, str]) -> Config:
    """Each setting as *sources* choose it (flag > environment > default), checked."""
    given_timeout = sources.pick(TIMEOUT)
    level = sources.pick(LOG_LEVEL)
    chosen_tools = sources.pick(TOOLS)
    return Config(
        url=_resolve_url(sources),
        request_timeout=(
            parse_timeout(given_timeout.value, source=given_timeout.source)
            if given_timeout is not None
            else DEFAULT_REQUEST_TIMEOUT
        ),
        log_level=_parse_log_level(level.value, source=level.source) if level is not None else "INFO",
        policy=_load_policy(sources),
        audit_log=_path(sources, AUDIT_LOG),
        ca_file=_path(sources, CA_FILE),
        client_cert=_path(sources, CLIENT_CERT),
        client_key=_path(sources, CLIENT_KEY),
        headers=_headers(sources),
        tools=_parse_tools(chosen_tools.value, source=chosen_tools.source) if chosen_tools else None,
        record_dir=_record_dir(sources, environ),
    )


def _load_policy(sources: Sources) -> Policy:
    chosen = sources.pick(POLICY)
    if chosen is not None and not str(chosen.value).strip():
        raise ConfigError(f"{chosen.source} is empty; give a policy file (TOML, docs/safety.md)")
    try:
        loaded = load_policy(chosen.value, source=chosen.source) if chosen is not None else Policy()
    except PolicyError as exc:
        raise ConfigError(str(exc)) from None
    # The switch's file is the policy file: --read-only or ROSBRIDGE_MCP_READ_ONLY=1 make it read-only, and
    # ROSBRIDGE_MCP_READ_ONLY=0 (off, so not given) leaves the file's own read_only = true in force.
    with_file = sources.with_file(
        {"read_only": loaded.read_only}, chosen.source if chosen is not None else ""
    )
    return loaded.with_read_only() if with_file.switch(READ_ONLY) else loaded


def default_record_dir(environ: Mapping[str, str]) -> Path:
    """``$XDG_DATA_HOME/rosbridge-mcp-server/recordings`` (``~/.local/share/...`` when unset or relative)."""
    base = environ.get("XDG_DATA_HOME", "").strip()
    root = Path(base) if base and Path(base).is_absolute() else Path.home() / ".local" / "share"
    return root / "rosbridge-mcp-server" / "recordings"


def _record_dir(sources: Sources, environ: Mapping[str, str]) -> Path:
    given = _path(sources, RECORD_DIR)
    return Path(given).expanduser() if given is not None else default_record_dir(environ)


def _path(sources: Sources, setting: Setting) -> str | None:
    chosen = sources.pick(setting)
    if chosen is None:
        return None
    if not str(chosen.value).strip():
        raise ConfigError(f"{chosen.source} is empty; give a file path")
    return str(chosen.value)


# An HTTP header name is a token (RFC 9110); values must not break the request line by line.
_HEADER_NAME = re.compile(r"^[!#$%&'*+.^_`|~0-9A-Za-z-]+$")


def _headers(sources: Sources) -> tuple[tuple[str, str], ...]:
    chosen = sources.pick(HEADERS)
    if chosen is None:
        return ()
    source = chosen.source
    lines = list(chosen.value) if chosen.rank == FLAG else chosen.value.splitlines()
    lines = [line for line in lines if chosen.rank == FLAG or line.strip()]
    headers = []
    for line in lines:
        name, colon, value = line.partition(":")
        name, value = name.strip(), value.strip()
        # The value is a secret (a token): the error names the header, never its value.
        if not colon or not _HEADER_NAME.match(name):
            shown = name if _HEADER_NAME.match(name) else "(not a header name)"
            raise ConfigError(f"{source} must be 'Name: value', e.g. 'Authorization: Bearer …'; got {shown}")
        if not value or "\r" in value or "\n" in value:
            raise ConfigError(f"{source}: header {name} has an empty or multi-line value")
        headers.append((name, value))
    return tuple(headers)


def _check_tls(config: Config, *, simulated: bool) -> None:
    uses_tls = config.ca_file is not None or config.client_cert is not None
    if config.client_key is not None and config.client_cert is None:
        raise ConfigError("--client-key / ROSBRIDGE_CLIENT_KEY needs --client-cert / ROSBRIDGE_CLIENT_CERT")
    if uses_tls and not simulated and urlsplit(config.url).scheme != "wss":
        raise ConfigError(
            f"a CA file or client certificate is for TLS, but the URL is {config.url}; use a wss:// URL"
        )
    for file in (config.ca_file, config.client_cert, config.client_key):
        if file is not None and not Path(file).is_file():
            raise ConfigError(f"TLS file {file!r} does not exist or is not a file")
    config.ssl_context()


def _reason(exc: OSError) -> str:
    # ssl.SSLError is an OSError whose strerror is unset; its reason ("PEM_LIB", ...) is the useful part.
    return str(exc.strerror or getattr(exc, "reason", None) or exc)


def plain_text_warning(url: str) -> str | None:
    """A warning for a plain ws:// URL to another machine: commands and any token travel unencrypted."""
    parts = urlsplit(url)
    host = parts.hostname or ""
    if parts.scheme != "ws" or is_loopback(host):
        return None
    return (
        f"rosbridge at {url} is reached over plain ws://: anyone on the network path can read and inject "
        "robot commands. Use wss:// (rosbridge's certfile/keyfile, or a TLS proxy) for a robot off this "
        "machine."
    )


def _parse_tools(value: str, *, source: str) -> tuple[str, ...] | None:
    try:
        chosen = select_tools(value)
    except ValueError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    return None if len(chosen) == len(ALL_TOOL_NAMES) else chosen


def _resolve_url(sources: Sources) -> str:
    # A URL beats host and port given in the same source or a lower one; a host or a port in a higher source
    # beats it, and the other half then comes from its own sources (``--host`` with ``ROSBRIDGE_PORT``).
    url, host, port = sources.pick(URL), sources.pick(HOST), sources.pick(PORT)
    parts = [given.rank for given in (host, port) if given is not None]
    if url is not None and (not parts or url.rank <= min(parts)):
        return parse_url(url.value, source=url.source)
    return _url_from(
        host.value if host is not None else DEFAULT_HOST,
        host.source if host is not None else HOST.env or HOST.flag,
        port.value if port is not None else DEFAULT_PORT,
        port.source if port is not None else PORT.env or PORT.flag,
    )


def _url_from(host: str, host_source: str, port: str | int, port_source: str) -> str:
    return f"ws://{_format_host(parse_host(host, source=host_source))}:{parse_port(port, source=port_source)}"


def parse_port(value: str | int, *, source: str) -> int:
    """A TCP port 1-65535."""
    text = str(value).strip()
    try:
        number = int(text)
    except ValueError:
        raise ConfigError(f"{source} must be a port number between 1 and 65535, not {text!r}") from None
    if not 1 <= number <= 65535:
        raise ConfigError(f"{source} must be a port number between 1 and 65535, not {number}")
    return number


def parse_host(value: str, *, source: str) -> str:
    """A host name or IP address, without scheme, port or path."""
    text = value.strip()
    if not text:
        raise ConfigError(f"{source} is empty; give a host name or IP address such as 192.168.1.100")
    if "://" in text:
        raise ConfigError(
            f"{source} must be a bare host name or IP address, not a URL ({text!r}); use --url / "
            "ROSBRIDGE_URL for a full ws:// or wss:// URL"
        )
    if text.startswith("[") and text.endswith("]"):
        text = text[1:-1]
    if any(ch.isspace() for ch in text) or "/" in text or "@" in text:
        raise ConfigError(f"{source} is not a valid host name or IP address: {value!r}")
    if text.count(":") == 1:
        raise ConfigError(
            f"{source} must not contain a port ({value!r}); put the port in --port / ROSBRIDGE_PORT"
        )
    if ":" in text:
        try:
            ipaddress.IPv6Address(text)
        except ValueError:
            raise ConfigError(f"{source} is not a valid host name or IP address: {value!r}") from None
    return text


def _format_host(host: str) -> str:
    return f"[{host}]" if ":" in host else host


def parse_url(value: str, *, source: str) -> str:
    """A ``ws://`` or ``wss://`` URL with a host; the path is kept (rosbridge may sit behind a proxy path)."""
    text = value.strip()
    try:
        parts = urlsplit(text)
        parsed_port = parts.port
    except ValueError as exc:
        raise ConfigError(f"{source} is not a valid URL ({text!r}): {exc}") from None
    if parts.scheme not in ("ws", "wss"):
        hint = " (rosbridge speaks WebSocket: use ws://, or wss:// behind TLS)"
        raise ConfigError(f"{source} must start with ws:// or wss://, not {text!r}{hint}")
    if not parts.hostname:
        raise ConfigError(f"{source} has no host: {text!r}; expected e.g. ws://192.168.1.100:9090")
    if parsed_port is not None and parsed_port == 0:
        raise ConfigError(f"{source} has port 0: {text!r}; the port must be between 1 and 65535")
    return text


def parse_timeout(value: str | float, *, source: str) -> float:
    """A number of seconds, 0 < t <= MAX_TIMEOUT."""
    text = str(value).strip()
    try:
        number = float(text)
    except ValueError:
        raise ConfigError(f"{source} must be a number of seconds, not {text!r}") from None
    if not math.isfinite(number) or not 0 < number <= MAX_TIMEOUT:
        raise ConfigError(f"{source} must be more than 0 and at most {MAX_TIMEOUT:g} seconds, not {text}")
    return number


def _parse_log_level(value: str, *, source: str) -> LogLevel:
    upper = value.strip().upper()
    for level in LOG_LEVELS:
        if level == upper:
            return level
    raise ConfigError(f"{source} must be one of {', '.join(LOG_LEVELS)}, not {value!r}")
