"""Configuration: read once from flags and the environment, validated into a frozen :class:`Config`.

Precedence, highest first:

1. ``--url``;
2. ``--host`` / ``--port`` (a missing half comes from ``ROSBRIDGE_HOST`` / ``ROSBRIDGE_PORT``);
3. ``ROSBRIDGE_URL``;
4. ``ROSBRIDGE_HOST`` / ``ROSBRIDGE_PORT``;
5. ``ws://localhost:9090``.

So a flag always beats the environment, and within one source a URL beats host and port. Nothing else in the
package reads the environment; :func:`load_config` is called once, from ``cli.run()``. The same rule holds for
``--timeout`` / ``ROSBRIDGE_TIMEOUT``, ``--log-level`` / ``ROSBRIDGE_MCP_LOG_LEVEL`` and ``--tools`` /
``ROSBRIDGE_MCP_TOOLS``.
"""

from __future__ import annotations

import ipaddress
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal
from urllib.parse import urlsplit

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
]

DEFAULT_HOST = "localhost"
DEFAULT_PORT = 9090
DEFAULT_REQUEST_TIMEOUT = 10.0
DEFAULT_CONNECT_TIMEOUT = 5.0
MAX_TIMEOUT = 300.0

LogLevel = Literal["DEBUG", "INFO", "WARNING", "ERROR", "CRITICAL"]
LOG_LEVELS: tuple[LogLevel, ...] = ("DEBUG", "INFO", "WARNING", "ERROR", "CRITICAL")
DemoDialect = Literal["ros1", "ros2"]


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
    #: Names of the tools a host sees; ``None`` is every tool.
    tools: tuple[str, ...] | None = None


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
    tools: str | None = None,
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
    tools_text = tools if tools is not None else environ.get("ROSBRIDGE_MCP_TOOLS", "").strip() or None
    tools_source = "--tools" if tools is not None else "ROSBRIDGE_MCP_TOOLS"
    chosen = _parse_tools(tools_text, source=tools_source) if tools_text is not None else None
    return Config(
        url=resolved_url,
        request_timeout=request_timeout,
        log_level=level,
        demo=demo,
        demo_dialect="ros1" if demo_dialect == "ros1" else "ros2",
        tools=chosen,
    )


def _parse_tools(value: str, *, source: str) -> tuple[str, ...] | None:
    # The tool registry lives with the tools; imported here only, so the configuration stays importable alone.
    from rosbridge_mcp_server.tools import TOOL_MODULES, select_tools  # noqa: PLC0415

    try:
        chosen = select_tools(value)
    except ValueError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    return None if len(chosen) == len(TOOL_MODULES) else chosen


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
