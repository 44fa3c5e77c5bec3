"""Configuration: read once from flags and the environment, validated into a frozen :class:`Config`.

Precedence, highest first:

1. ``--url``;
2. ``--host`` / ``--port`` (a missing half comes from ``ROSBRIDGE_HOST`` / ``ROSBRIDGE_PORT``);
3. ``ROSBRIDGE_URL``;
4. ``ROSBRIDGE_HOST`` / ``ROSBRIDGE_PORT``;
5. ``ws://localhost:9090``.

So a flag always beats the environment, and within one source a URL beats host and port. Nothing else in the
package reads the environment; :func:`load_config` is called once, from ``cli.run()``. The same rule holds for
every other pair:

* ``--timeout`` / ``ROSBRIDGE_TIMEOUT``, ``--log-level`` / ``ROSBRIDGE_MCP_LOG_LEVEL``, ``--tools`` /
  ``ROSBRIDGE_MCP_TOOLS``;
* safety: ``--policy`` / ``ROSBRIDGE_MCP_POLICY`` (a TOML file), ``--read-only`` /
  ``ROSBRIDGE_MCP_READ_ONLY=1`` (either one makes the server read-only), ``--audit-log`` /
  ``ROSBRIDGE_MCP_AUDIT_LOG``;
* connection security: ``--ca-file`` / ``ROSBRIDGE_CA_FILE``, ``--client-cert`` / ``ROSBRIDGE_CLIENT_CERT``,
  ``--client-key`` / ``ROSBRIDGE_CLIENT_KEY``, ``--header`` (repeatable) / ``ROSBRIDGE_HEADERS`` (one
  ``Name: value`` per line). Header values are secrets: they are never logged.
"""

from __future__ import annotations

import ipaddress
import math
import re
import ssl
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal
from urllib.parse import urlsplit

from rosbridge_mcp_server.catalogue import ALL_TOOL_NAMES, select_tools
from rosbridge_mcp_server.safety.policy import Policy, PolicyError, load_policy

__all__ = [
    "DEFAULT_HOST",
    "DEFAULT_PORT",
    "DEFAULT_REQUEST_TIMEOUT",
    "LOG_LEVELS",
    "MAX_TIMEOUT",
    "Config",
    "ConfigError",
    "DemoDialect",
    "LogLevel",
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
DemoDialect = Literal["ros1", "ros2"]
DemoWorld = Literal["turtle", "nav2"]


class ConfigError(ValueError):
    """A configuration value is invalid; ``str()`` is one line saying which and how to fix it."""


@dataclass(frozen=True)
class Config:
    """Everything the server needs to know, validated.

    ``url`` is the rosbridge WebSocket URL. With ``demo`` set the CLI starts a simulated robot and replaces
    ``url`` with the simulator's own address before anything connects.
    """

    url: str = f"ws://{DEFAULT_HOST}:{DEFAULT_PORT}"
    request_timeout: float = DEFAULT_REQUEST_TIMEOUT
    connect_timeout: float = DEFAULT_CONNECT_TIMEOUT
    log_level: LogLevel = "INFO"
    demo: bool = False
    demo_dialect: DemoDialect = "ros2"
    #: The demo robot's world: the turtle (default) or a Nav2-scale mobile robot, ``demo_robots`` of them.
    demo_world: DemoWorld = "turtle"
    demo_robots: int = 1
    #: Faults the demo's Nav2 robot is broken with (``--demo-fault``), checked by the simulated robot.
    demo_faults: tuple[str, ...] = ()
    policy: Policy = field(default_factory=Policy)
    audit_log: str | None = None
    ca_file: str | None = None
    client_cert: str | None = None
    client_key: str | None = None
    headers: tuple[tuple[str, str], ...] = field(default=(), repr=False)
    #: Names of the tools a host sees; ``None`` is every tool.
    tools: tuple[str, ...] | None = None
    #: Where ``record`` writes and ``read_recording`` reads (``--record-dir``); ``None``: the default.
    record_dir: str | None = None

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


def load_config(
    environ: Mapping[str, str],
    *,
    host: str | None = None,
    port: str | int | None = None,
    url: str | None = None,
    timeout: str | float | None = None,
    log_level: str | None = None,
    demo: bool = False,
    demo_dialect: str = "ros2",
    demo_world: str = "turtle",
    demo_robots: int = 1,
    demo_faults: str | None = None,
    policy: str | None = None,
    read_only: bool = False,
    audit_log: str | None = None,
    ca_file: str | None = None,
    client_cert: str | None = None,
    client_key: str | None = None,
    headers: Sequence[str] | None = None,
    tools: str | None = None,
    record_dir: str | None = None,
) -> Config:
    """Build a :class:`Config` from command-line values (``None`` = not given) and the environment.

    Raises :class:`ConfigError` with a one-line message naming the bad value and its source.
    """
    resolved_url = _resolve_url(environ, host=host, port=port, url=url)
    env_timeout = environ.get("ROSBRIDGE_TIMEOUT", "").strip()
    if timeout is not None:
        request_timeout = parse_timeout(timeout, source="--timeout")
    elif env_timeout:
        request_timeout = parse_timeout(env_timeout, source="ROSBRIDGE_TIMEOUT")
    else:
        request_timeout = DEFAULT_REQUEST_TIMEOUT
    level_text = log_level if log_level is not None else environ.get("ROSBRIDGE_MCP_LOG_LEVEL")
    level_source = "--log-level" if log_level is not None else "ROSBRIDGE_MCP_LOG_LEVEL"
    level = _parse_log_level(level_text, source=level_source) if level_text else "INFO"
    if demo_dialect not in ("ros1", "ros2"):
        raise ConfigError(f"--demo-dialect must be ros1 or ros2, not {demo_dialect!r}")
    if demo_world not in ("turtle", "nav2"):
        raise ConfigError(f"--demo-world must be turtle or nav2, not {demo_world!r}")
    if not 1 <= demo_robots <= 100 or (demo_robots > 1 and demo_world != "nav2"):
        raise ConfigError(
            f"--demo-robots must be 1-100 and more than 1 needs --demo-world nav2, not {demo_robots}"
        )
    faults = tuple(f.strip() for f in (demo_faults or "").split(",") if f.strip())
    if faults and demo_world != "nav2":
        raise ConfigError("--demo-fault needs --demo-world nav2")
    tools_text = tools if tools is not None else environ.get("ROSBRIDGE_MCP_TOOLS", "").strip() or None
    tools_source = "--tools" if tools is not None else "ROSBRIDGE_MCP_TOOLS"
    chosen = _parse_tools(tools_text, source=tools_source) if tools_text is not None else None
    config = Config(
        url=resolved_url,
        request_timeout=request_timeout,
        log_level=level,
        demo=demo,
        demo_dialect="ros1" if demo_dialect == "ros1" else "ros2",
        demo_world="nav2" if demo_world == "nav2" else "turtle",
        demo_robots=demo_robots,
        demo_faults=faults,
        policy=_load_policy(environ, policy, read_only),
        audit_log=_path(environ, audit_log, "--audit-log", "ROSBRIDGE_MCP_AUDIT_LOG"),
        ca_file=_path(environ, ca_file, "--ca-file", "ROSBRIDGE_CA_FILE"),
        client_cert=_path(environ, client_cert, "--client-cert", "ROSBRIDGE_CLIENT_CERT"),
        client_key=_path(environ, client_key, "--client-key", "ROSBRIDGE_CLIENT_KEY"),
        headers=_headers(environ, headers),
        tools=chosen,
        record_dir=_path(environ, record_dir, "--record-dir", "ROSBRIDGE_MCP_RECORD_DIR"),
    )
    _check_tls(config)
    return config


_TRUE = ("1", "true", "yes", "on")
_FALSE = ("", "0", "false", "no", "off")


def _load_policy(environ: Mapping[str, str], path: str | None, read_only: bool) -> Policy:
    source = "--policy" if path is not None else "ROSBRIDGE_MCP_POLICY"
    text = path if path is not None else environ.get("ROSBRIDGE_MCP_POLICY", "").strip()
    try:
        loaded = load_policy(text, source=source) if text else Policy()
    except PolicyError as exc:
        raise ConfigError(str(exc)) from None
    env_read_only = environ.get("ROSBRIDGE_MCP_READ_ONLY", "").strip().lower()
    if env_read_only not in _TRUE + _FALSE:
        raise ConfigError(f"ROSBRIDGE_MCP_READ_ONLY must be 1 or 0 (true or false), not {env_read_only!r}")
    if read_only or env_read_only in _TRUE:
        return loaded.with_read_only()
    return loaded


def _path(environ: Mapping[str, str], flag: str | None, flag_name: str, env_name: str) -> str | None:
    value = flag if flag is not None else environ.get(env_name, "").strip() or None
    if value is not None and not value.strip():
        raise ConfigError(f"{flag_name} is empty; give a file path")
    return value


# An HTTP header name is a token (RFC 9110); values must not break the request line by line.
_HEADER_NAME = re.compile(r"^[!#$%&'*+.^_`|~0-9A-Za-z-]+$")


def _headers(environ: Mapping[str, str], flags: Sequence[str] | None) -> tuple[tuple[str, str], ...]:
    if flags:
        lines, source = list(flags), "--header"
    else:
        lines = [line for line in environ.get("ROSBRIDGE_HEADERS", "").splitlines() if line.strip()]
        source = "ROSBRIDGE_HEADERS"
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


def _check_tls(config: Config) -> None:
    uses_tls = config.ca_file is not None or config.client_cert is not None
    if config.client_key is not None and config.client_cert is None:
        raise ConfigError("--client-key / ROSBRIDGE_CLIENT_KEY needs --client-cert / ROSBRIDGE_CLIENT_CERT")
    if uses_tls and not config.demo and urlsplit(config.url).scheme != "wss":
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
    if parts.scheme != "ws" or _is_loopback(host):
        return None
    return (
        f"rosbridge at {url} is reached over plain ws://: anyone on the network path can read and inject "
        "robot commands. Use wss:// (rosbridge's certfile/keyfile, or a TLS proxy) for a robot off this "
        "machine."
    )


def _is_loopback(host: str) -> bool:
    if host.lower() in ("localhost", "localhost.localdomain") or host.lower().endswith(".localhost"):
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _parse_tools(value: str, *, source: str) -> tuple[str, ...] | None:
    try:
        chosen = select_tools(value)
    except ValueError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    return None if len(chosen) == len(ALL_TOOL_NAMES) else chosen


def _resolve_url(
    environ: Mapping[str, str], *, host: str | None, port: str | int | None, url: str | None
) -> str:
    if url is not None:
        return parse_url(url, source="--url")
    if host is not None or port is not None:
        host_text = host if host is not None else environ.get("ROSBRIDGE_HOST") or DEFAULT_HOST
        host_source = "--host" if host is not None else "ROSBRIDGE_HOST"
        port_value = port if port is not None else environ.get("ROSBRIDGE_PORT") or DEFAULT_PORT
        port_source = "--port" if port is not None else "ROSBRIDGE_PORT"
        return _url_from(host_text, host_source, port_value, port_source)
    env_url = environ.get("ROSBRIDGE_URL", "").strip()
    if env_url:
        return parse_url(env_url, source="ROSBRIDGE_URL")
    env_host = environ.get("ROSBRIDGE_HOST", "").strip() or DEFAULT_HOST
    env_port = environ.get("ROSBRIDGE_PORT", "").strip() or DEFAULT_PORT
    return _url_from(env_host, "ROSBRIDGE_HOST", env_port, "ROSBRIDGE_PORT")


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
