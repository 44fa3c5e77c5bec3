"""Reading the transport settings: flags, environment, and the refusals that keep a robot unexposed."""

from __future__ import annotations

from pathlib import Path

import pytest

from rosbridge_mcp_server.config import ConfigError
from rosbridge_mcp_server.config.http import load_http_settings, parse_bind, parse_tokens

TOKEN = "0123456789abcdef0123"


def test_stdio_is_the_default_and_http_flags_need_http() -> None:
    """No flags: stdio. --bind with stdio is a mistake, said as one."""
    assert load_http_settings({}).transport == "stdio"
    with pytest.raises(ConfigError, match="--bind needs --transport http"):
        load_http_settings({}, bind="127.0.0.1:9000")


def test_http_defaults_to_loopback_8765_without_tokens() -> None:
    """--transport http alone listens on 127.0.0.1:8765, path /mcp, unauthenticated (loopback only)."""
    settings = load_http_settings({}, transport="http")
    assert (settings.host, settings.port, settings.url) == ("127.0.0.1", 8765, "http://127.0.0.1:8765/mcp")
    assert not settings.authenticated


def test_binding_beyond_loopback_needs_authentication() -> None:
    """0.0.0.0 or a LAN address without tokens or OAuth is refused; with tokens it is allowed."""
    for bind in ("0.0.0.0:8765", "[::]:8765", "192.168.1.5:8765"):
        with pytest.raises(ConfigError, match="refusing to listen"):
            load_http_settings({}, transport="http", bind=bind)
    env = {"ROSBRIDGE_MCP_AUTH_TOKENS": f"ops {TOKEN}"}
    settings = load_http_settings(env, transport="http", bind="192.168.1.5:8765", behind_tls_proxy=True)
    assert settings.tokens == (("ops", TOKEN),)
    assert "192.168.1.5:8765" in settings.allowed_hosts


def test_binding_beyond_loopback_needs_tls_or_a_stated_tls_proxy(tmp_path: Path) -> None:
    """Tokens in clear on a network are refused; the server's own TLS or --behind-tls-proxy lets it listen."""
    env = {"ROSBRIDGE_MCP_AUTH_TOKENS": f"ops {TOKEN}"}
    for bind in ("0.0.0.0:8765", "[::]:8765", "192.168.1.5:8765"):
        with pytest.raises(ConfigError, match=r"in plain HTTP.*--tls-cert.*--behind-tls-proxy"):
            load_http_settings(env, transport="http", bind=bind)
    with pytest.raises(ConfigError, match="in plain HTTP"):
        load_http_settings({}, transport="http", bind="0.0.0.0:8765", oauth_issuer="https://a.example")
    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    cert.write_text("not read here")
    key.write_text("not read here")
    tls = load_http_settings(env, transport="http", bind="0.0.0.0:8765", tls_cert=str(cert), tls_key=str(key))
    assert tls.scheme == "https"
    proxied = load_http_settings(
        {**env, "ROSBRIDGE_MCP_BEHIND_TLS_PROXY": "1"}, transport="http", bind="0.0.0.0:1"
    )
    assert proxied.behind_tls_proxy
    with pytest.raises(ConfigError, match=r"ROSBRIDGE_MCP_BEHIND_TLS_PROXY must be 1 or 0"):
        load_http_settings(
            {**env, "ROSBRIDGE_MCP_BEHIND_TLS_PROXY": "maybe"}, transport="http", bind="0.0.0.0:1"
        )
    with pytest.raises(ConfigError, match="--behind-tls-proxy needs --transport http"):
        load_http_settings({}, behind_tls_proxy=True)
    # Loopback stays plain HTTP without a word: the tokens never leave the machine.
    assert load_http_settings(env, transport="http", bind="127.0.0.1:8765").scheme == "http"


def test_a_token_file_has_one_name_and_token_per_line(tmp_path: Path) -> None:
    """Comments and blank lines are skipped; the environment's pairs may be comma-separated."""
    path = tmp_path / "tokens"
    path.write_text(f"# operators\nalice {TOKEN}\n\nbob {TOKEN}x\n")
    path.chmod(0o600)
    settings = load_http_settings({}, transport="http", auth_tokens=str(path))
    assert [name for name, _ in settings.tokens] == ["alice", "bob"]
    env = {"ROSBRIDGE_MCP_AUTH_TOKENS": f"alice {TOKEN}, bob {TOKEN}y"}
    assert len(load_http_settings(env, transport="http").tokens) == 2


@pytest.mark.parametrize(
    ("lines", "problem"),
    [
        ([f"alice {TOKEN} extra"], "not 'name token'"),
        (["alice short"], "shorter than 16"),
        ([f"alice {TOKEN}", f"alice {TOKEN}x"], "given twice"),
        ([f"alice {TOKEN}", f"bob {TOKEN}"], "same token"),
        (["alice"], "not 'name token'"),
        (["# nothing"], "no tokens"),
    ],
)
def test_bad_token_entries_are_named_without_showing_a_token(lines: list[str], problem: str) -> None:
    """Each mistake is one line naming the entry; no token appears in it."""
    with pytest.raises(ConfigError, match=problem) as caught:
        parse_tokens(lines, source="tokens")
    assert TOKEN not in str(caught.value)


def test_bind_addresses() -> None:
    """HOST:PORT and [IPv6]:PORT; port 0 picks a free port; anything else is refused."""
    assert parse_bind("[::1]:8765", source="--bind") == ("::1", 8765)
    assert parse_bind("localhost:0", source="--bind") == ("localhost", 0)
    for bad in ("8765", "host:", "host:99999", "::1:8765"):
        with pytest.raises(ConfigError, match="--bind"):
            parse_bind(bad, source="--bind")


def test_oauth_needs_an_issuer_url_and_not_tokens_too() -> None:
    """--oauth-* without an issuer, a non-URL issuer, or OAuth with tokens: refused by name."""
    with pytest.raises(ConfigError, match="needs --oauth-issuer"):
        load_http_settings({}, transport="http", oauth_audience="x")
    with pytest.raises(ConfigError, match="not an http"):
        load_http_settings({}, transport="http", oauth_issuer="auth.example.com")
    with pytest.raises(ConfigError, match="not both"):
        load_http_settings(
            {"ROSBRIDGE_MCP_AUTH_TOKENS": f"a {TOKEN}"}, transport="http", oauth_issuer="https://a.example"
        )
    settings = load_http_settings(
        {}, transport="http", bind="0.0.0.0:8765", oauth_issuer="https://a.example", behind_tls_proxy=True
    )
    assert settings.oauth is not None
    assert settings.oauth.jwks == "https://a.example/.well-known/jwks.json"
    assert settings.oauth.audience == settings.oauth.resource == "http://0.0.0.0:8765/mcp"
