"""The one loopback rule (``config/addresses.py``) and every setting that asks it.

The MCP HTTP listener, the console and the robot URL's plain-text warning each had a rule of their own; they
disagreed on ``localhost.localdomain`` and ``*.localhost`` (loopback for the robot URL only), on letter case
(``LOCALHOST`` loopback for the console, not for HTTP) and, with Python 3.13, on IPv4-mapped ``::ffff:127.x``.
The one rule takes the narrower answer where a name or address may leave the machine, and reads ``localhost``
in any letter case: a host it does not recognise sends each caller down its safe path (refuse, or warn).
"""

from __future__ import annotations

import pytest

from rosbridge_mcp_server.config import ConfigError, plain_text_warning
from rosbridge_mcp_server.config.addresses import is_loopback
from rosbridge_mcp_server.config.console import console_settings
from rosbridge_mcp_server.config.http import load_http_settings

# (host as a setting holds it, loopback?)
RULE: list[tuple[str, bool]] = [
    ("127.0.0.1", True),
    ("127.8.9.10", True),  # all of 127.0.0.0/8
    ("127.255.255.254", True),
    ("::1", True),
    ("0:0:0:0:0:0:0:1", True),  # ::1 written out
    ("::1%lo", True),  # with a zone
    ("[::1]", True),  # as a URL writes it
    ("localhost", True),
    ("0.0.0.0", False),  # every interface
    ("::", False),
    ("[::]", False),
    ("", False),  # every interface, to a bind
    ("128.0.0.1", False),
    ("192.168.1.5", False),
    ("10.0.0.7", False),
    ("fe80::1", False),
    ("::ffff:127.0.0.1", False),  # IPv4-mapped: loopback to Python 3.13 only, so to no version here
    ("::127.0.0.1", False),  # IPv4-compatible (deprecated)
    ("127.1", False),  # a short form inet_aton reads, ipaddress does not
    ("2130706433", False),  # 127.0.0.1 as one number
    ("LOCALHOST", True),  # names are case-insensitive
    ("LocalHost", True),
    ("localhost.", False),  # absolute: some resolvers ask DNS
    ("localhost.localdomain", False),
    ("robot.localhost", False),
    ("robot", False),
    ("robot.lan", False),
    ("[127.0.0.1]", False),  # brackets are for IPv6 only
    ("[localhost]", False),
    ("[::1", False),
    (" 127.0.0.1", False),
]


@pytest.mark.parametrize(("host", "loopback"), RULE, ids=[repr(host) for host, _ in RULE])
def test_the_rule(host: str, loopback: bool) -> None:
    assert is_loopback(host) is loopback


def _bind(host: str) -> str:
    return f"[{host}]:8765" if ":" in host and not host.startswith("[") else f"{host}:8765"


# Hosts a --bind or --console can carry (brackets are taken off by the address parser; --bind takes no zone).
BINDABLE = [
    (host, loopback)
    for host, loopback in RULE
    if host and host.strip() == host and "[" not in host and "%" not in host
]


@pytest.mark.parametrize(("host", "loopback"), BINDABLE, ids=[repr(host) for host, _ in BINDABLE])
def test_the_http_listener_needs_authentication_and_tls_off_loopback(host: str, loopback: bool) -> None:
    """Without tokens: a loopback --bind listens, any other is refused naming authentication."""
    if loopback:
        assert load_http_settings({}, transport="http", bind=_bind(host)).host == host
    else:
        with pytest.raises(ConfigError, match=f"refusing to listen on {host}:8765 without authentication"):
            load_http_settings({}, transport="http", bind=_bind(host))


@pytest.mark.parametrize(("host", "loopback"), BINDABLE, ids=[repr(host) for host, _ in BINDABLE])
def test_the_console_needs_tls_or_insecure_off_loopback(host: str, loopback: bool) -> None:
    """A loopback --console serves plain HTTP; any other needs --console-cert or --console-insecure."""
    if loopback:
        settings = console_settings(_bind(host))
        assert settings is not None
        assert settings.loopback
    else:
        with pytest.raises(ConfigError, match=f"{host} is not a loopback address"):
            console_settings(_bind(host))
        insecure = console_settings(_bind(host), insecure=True)
        assert insecure is not None
        assert not insecure.loopback


@pytest.mark.parametrize(
    ("url", "warns"),
    [
        ("ws://localhost:9090", False),
        ("ws://LOCALHOST:9090", False),  # a URL's host is case-insensitive
        ("ws://127.0.0.2:9090", False),
        ("ws://[::1]:9090", False),
        ("ws://localhost.localdomain:9090", True),  # was no warning
        ("ws://robot.localhost:9090", True),  # was no warning
        ("ws://[::ffff:127.0.0.1]:9090", True),
        ("ws://0.0.0.0:9090", True),
        ("ws://robot:9090", True),
        ("wss://robot.localhost:9090", False),
    ],
)
def test_a_plain_robot_url_is_warned_about_off_loopback(url: str, warns: bool) -> None:
    assert (plain_text_warning(url) is not None) is warns
