"""Where the operator console listens, and whether it may: ``--console [HOST:]PORT`` /
``ROSBRIDGE_MCP_CONSOLE`` and its TLS options (flags only).

Loopback by default. Any other address shows the robot's camera and its stop button to a network, so it needs
TLS (``--console-cert`` / ``--console-key``) or an explicit ``--console-insecure``; the session secret still
guards every request either way.
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from rosbridge_mcp_server.config.addresses import is_loopback
from rosbridge_mcp_server.config.robot import parse_port
from rosbridge_mcp_server.config.sources import ConfigError, Setting, Sources

__all__ = [
    "DEFAULT_CONSOLE_HOST",
    "RUNTIME_DIR",
    "ConsoleSettings",
    "console_runtime_dir",
    "console_settings",
    "load_console_settings",
]

DEFAULT_CONSOLE_HOST = "127.0.0.1"


@dataclass(frozen=True)
class ConsoleSettings:
    """The console's address and TLS files, checked."""

    host: str = DEFAULT_CONSOLE_HOST
    port: int = 0
    cert: str | None = None
    key: str | None = None
    insecure: bool = False

    @property
    def scheme(self) -> str:
        return "https" if self.cert else "http"

    @property
    def loopback(self) -> bool:
        return is_loopback(self.host)


#: Where the console listens; its TLS options are flags only.
CONSOLE = Setting("--console", "ROSBRIDGE_MCP_CONSOLE")
#: This user's directory for a running console's URL file (an environment variable only, no flag).
RUNTIME_DIR = "ROSBRIDGE_MCP_RUNTIME_DIR"
_APP = "rosbridge-mcp-server"


def load_console_settings(
    environ: Mapping[str, str],
    *,
    address: str | None = None,
    cert: str | None = None,
    key: str | None = None,
    insecure: bool = False,
) -> ConsoleSettings | None:
    """:func:`console_settings` from ``--console`` (``None``: not given) or ``ROSBRIDGE_MCP_CONSOLE``."""
    chosen = Sources({CONSOLE.flag: address}, environ).pick(CONSOLE)
    return console_settings(
        chosen.value if chosen is not None else None,
        cert=cert,
        key=key,
        insecure=insecure,
        source=chosen.source if chosen is not None else CONSOLE.flag,
    )


def console_settings(
    address: str | None,
    *,
    cert: str | None = None,
    key: str | None = None,
    insecure: bool = False,
    source: str = "--console",
) -> ConsoleSettings | None:
    """The settings from ``--console [HOST:]PORT`` and its options; ``None`` when no console was asked for.

    :class:`ConfigError` names what is wrong: a bad address, a key without a certificate, a missing file, or a
    non-loopback address without TLS or ``--console-insecure``.
    """
    if address is None:
        if cert or key or insecure:
            raise ConfigError("--console-cert, --console-key and --console-insecure need --console PORT")
        return None
    host, port = _split(address.strip(), source)
    if key and not cert:
        raise ConfigError("--console-key needs --console-cert (the certificate it belongs to)")
    for flag, path in (("--console-cert", cert), ("--console-key", key)):
        if path is not None and not Path(path).is_file():
            raise ConfigError(f"{flag}: file {path!r} does not exist")
    settings = ConsoleSettings(host=host, port=port, cert=cert, key=key, insecure=insecure)
    if not settings.loopback and not cert and not insecure:
        raise ConfigError(
            f"{source}: {host} is not a loopback address, so the console would be plain HTTP on a network; "
            "give --console-cert and --console-key (TLS), or --console-insecure if the network is trusted"
        )
    return settings


def _split(address: str, source: str) -> tuple[str, int]:
    if not address:
        raise ConfigError(f"{source}: give a port or HOST:PORT, e.g. 8770 or 127.0.0.1:8770")
    if address.startswith("["):  # [::1]:8770
        host, _, rest = address[1:].partition("]")
        if not rest.startswith(":"):
            raise ConfigError(f"{source}: {address!r} is not [IPv6]:PORT, e.g. [::1]:8770")
        port_text = rest[1:]
    elif address.count(":") == 1:
        host, port_text = address.split(":")
    elif ":" in address:
        raise ConfigError(f"{source}: write an IPv6 address in brackets, e.g. [::1]:8770")
    else:
        host, port_text = DEFAULT_CONSOLE_HOST, address
    host = host or DEFAULT_CONSOLE_HOST
    if any(ch.isspace() or ch in "/?#@" for ch in host):
        raise ConfigError(f"{source}: {host!r} is not a host name or address")
    if port_text.strip() == "0":
        return host, 0  # any free port; the URL printed names the one taken
    return host, parse_port(port_text, source=source)


def console_runtime_dir(environ: Mapping[str, str]) -> Path:
    """This user's directory for the console's URL file (:mod:`rosbridge_mcp_server.console.address`):
    ``ROSBRIDGE_MCP_RUNTIME_DIR``, else ``$XDG_RUNTIME_DIR/rosbridge-mcp-server`` (Linux), else
    ``%LOCALAPPDATA%\\rosbridge-mcp-server`` (Windows), else ``~/Library/Caches/rosbridge-mcp-server`` (macOS)
    or ``~/.cache/rosbridge-mcp-server``. A blank variable is the same as none."""
    named = environ.get(RUNTIME_DIR, "").strip()
    if named:
        return Path(named)
    xdg = environ.get("XDG_RUNTIME_DIR", "").strip()
    if xdg:
        return Path(xdg) / _APP
    local = environ.get("LOCALAPPDATA", "").strip()
    if sys.platform == "win32" and local:
        return Path(local) / _APP
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / _APP
    return Path.home() / ".cache" / _APP
