"""Streamable HTTP's defences over real HTTP: tokens, Host/Origin checks, no open port without auth."""

from __future__ import annotations

import asyncio
import json
import os
import ssl
import sys
from pathlib import Path
from typing import Any

import httpx2
import pytest
import trustme
from e2e_transports import INITIALIZE, TOKEN, WAIT, serving, stop

from rosbridge_mcp_server.sim import SimulatedRobot

PUBLISH = {
    "jsonrpc": "2.0",
    "id": 2,
    "method": "tools/call",
    "params": {
        "name": "publish_topic",
        "arguments": {
            "topic": "/turtle1/cmd_vel",
            "message_type": "geometry_msgs/msg/Twist",
            "message": {"linear": {"x": 1.0}},
        },
    },
}


def _headers(token: str | None = None, **extra: str) -> dict[str, str]:
    headers = {"Content-Type": "application/json", "Accept": "application/json, text/event-stream"}
    if token is not None:
        headers["Authorization"] = f"Bearer {token}"
    return headers | extra


async def _post(url: str, body: dict[str, Any], **headers: str) -> httpx2.Response:
    async with httpx2.AsyncClient(timeout=WAIT) as http:
        return await http.post(url, json=body, headers=headers)


async def test_a_request_without_a_token_is_401_with_the_bearer_challenge(sim_ros2: SimulatedRobot) -> None:
    """No Authorization header: 401 and a WWW-Authenticate Bearer challenge (RFC 6750, as MCP asks)."""
    async with serving("http", "--url", sim_ros2.url) as served:
        response = await _post(served.url, INITIALIZE, **_headers())
    assert response.status_code == 401
    challenge = response.headers["www-authenticate"]
    assert challenge.startswith("Bearer ")
    assert 'error="invalid_token"' in challenge


async def test_a_wrong_token_is_401_and_a_right_one_initializes(sim_ros2: SimulatedRobot) -> None:
    """A token not in the file is refused; the file's token opens a session."""
    async with serving("http", "--url", sim_ros2.url) as served:
        wrong = await _post(served.url, INITIALIZE, **_headers("not-the-token-0123456789abcdef"))
        right = await _post(served.url, INITIALIZE, **_headers(TOKEN))
    assert wrong.status_code == 401
    assert wrong.headers["www-authenticate"].startswith("Bearer ")
    assert right.status_code == 200
    assert right.headers["mcp-session-id"]


async def test_a_foreign_host_or_origin_is_refused_even_with_a_good_token(sim_ros2: SimulatedRobot) -> None:
    """DNS-rebinding protection: a Host or an Origin the server does not know is refused."""
    async with serving("http", "--url", sim_ros2.url) as served:
        host = await _post(served.url, INITIALIZE, **_headers(TOKEN, Host="evil.example.com"))
        origin = await _post(served.url, INITIALIZE, **_headers(TOKEN, Origin="http://evil.example.com"))
        allowed = await _post(served.url, INITIALIZE, **_headers(TOKEN, Origin="http://localhost:1234"))
    assert host.status_code == 421
    assert origin.status_code == 403
    assert allowed.status_code == 200


async def test_a_name_given_with_allow_host_is_accepted(sim_ros2: SimulatedRobot) -> None:
    """--allow-host adds a name (e.g. a reverse proxy's) to the Host and Origin lists."""
    async with serving("http", "--url", sim_ros2.url, "--allow-host", "robot.example.com") as served:
        response = await _post(
            served.url,
            INITIALIZE,
            **_headers(TOKEN, Host="robot.example.com", Origin="https://robot.example.com"),
        )
    assert response.status_code == 200


@pytest.mark.parametrize("bind", ["0.0.0.0:0", "192.0.2.1:8765"])
async def test_listening_beyond_loopback_without_authentication_exits_2(bind: str) -> None:
    """No tokens and no OAuth on a non-loopback address: one clear line and exit code 2, nothing listens."""
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosbridge_mcp_server",
        "--transport",
        "http",
        "--bind",
        bind,
        stdin=asyncio.subprocess.DEVNULL,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    stdout, stderr = await asyncio.wait_for(process.communicate(), WAIT)
    assert process.returncode == 2
    assert stdout == b""
    lines = stderr.decode().strip().splitlines()
    assert len(lines) == 1, lines
    assert "refusing to listen" in lines[0]
    assert "without authentication" in lines[0]
    assert "--auth-tokens" in lines[0]


@pytest.mark.parametrize("bind", ["0.0.0.0:0", "[::]:0"])
async def test_tokens_in_plain_http_beyond_loopback_exit_2_unless_a_tls_proxy_is_stated(bind: str) -> None:
    """Tokens but no TLS on a non-loopback address: one line naming --tls-cert and --behind-tls-proxy, exit
    2, nothing listens; with --behind-tls-proxy the same command serves."""
    env = {**os.environ, "ROSBRIDGE_MCP_AUTH_TOKENS": f"ops {TOKEN}"}
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosbridge_mcp_server",
        "--transport",
        "http",
        "--bind",
        bind,
        env=env,
        stdin=asyncio.subprocess.DEVNULL,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    stdout, stderr = await asyncio.wait_for(process.communicate(), WAIT)
    assert process.returncode == 2
    assert stdout == b""
    lines = stderr.decode().strip().splitlines()
    assert len(lines) == 1, lines
    assert "refusing to listen" in lines[0]
    assert "in plain HTTP" in lines[0]
    assert "--tls-cert" in lines[0]
    assert "--behind-tls-proxy" in lines[0]


async def test_a_stated_tls_proxy_lets_the_server_listen_beyond_loopback(sim_ros2: SimulatedRobot) -> None:
    """--behind-tls-proxy on 0.0.0.0 with tokens: the server listens and answers an authenticated client."""
    # The later --bind wins over start_http's 127.0.0.1:0.
    async with serving("http", "--url", sim_ros2.url, "--bind", "0.0.0.0:0", "--behind-tls-proxy") as served:
        assert served.url.startswith("http://0.0.0.0:")
        response = await _post(served.url.replace("0.0.0.0", "127.0.0.1"), INITIALIZE, **_headers(TOKEN))
    assert response.status_code == 200


async def test_a_thousand_bad_tokens_send_nothing_and_no_token_is_logged(
    sim_ros2: SimulatedRobot, tmp_path: Path
) -> None:
    """1,000 publish calls with wrong tokens: all 401, the robot gets nothing, no log shows a token."""
    audit = tmp_path / "audit.jsonl"
    bad = [f"bad-token-{i:04d}-0123456789abcdef" for i in range(1000)]
    bad[::7] = [f"{TOKEN}x{i}" for i in range(len(bad[::7]))]  # near misses of the real token
    async with serving("http", "--url", sim_ros2.url, "--audit-log", str(audit)) as served:
        limit = asyncio.Semaphore(50)
        async with httpx2.AsyncClient(timeout=WAIT) as http:

            async def attempt(token: str) -> int:
                async with limit:
                    response = await http.post(served.url, json=PUBLISH, headers=_headers(token))
                    return response.status_code

            codes = await asyncio.gather(*(attempt(token) for token in bad))
        # The real token still works afterwards, and is not logged either.
        good = await _post(served.url, INITIALIZE, **_headers(TOKEN))
        code, log = await stop(served)
    assert set(codes) == {401}
    assert good.status_code == 200
    assert code == 0, log
    assert "/turtle1/cmd_vel" not in sim_ros2.world.published
    assert not audit.exists() or audit.read_text() == ""
    logged = log + (audit.read_text() if audit.exists() else "")
    assert TOKEN not in logged
    assert not [token for token in bad if token in logged]
    assert "bad-token" not in logged


async def test_tokens_are_not_logged_even_at_debug_level(sim_ros2: SimulatedRobot) -> None:
    """At DEBUG (every library's log), neither the right token nor a wrong one appears in the log."""
    wrong = "wrong-token-at-debug-0123456789"
    async with serving("http", "--url", sim_ros2.url, "--log-level", "DEBUG") as served:
        await _post(served.url, INITIALIZE, **_headers(wrong))
        response = await _post(served.url, INITIALIZE, **_headers(TOKEN))
        session = response.headers["mcp-session-id"]
        await _post(
            served.url,
            {"jsonrpc": "2.0", "method": "notifications/initialized"},
            **_headers(TOKEN, **{"Mcp-Session-Id": session, "Mcp-Protocol-Version": "2025-06-18"}),
        )
        listed = await _post(
            served.url,
            {"jsonrpc": "2.0", "id": 3, "method": "tools/list"},
            **_headers(TOKEN, **{"Mcp-Session-Id": session, "Mcp-Protocol-Version": "2025-06-18"}),
        )
        _code, log = await stop(served)
    assert listed.status_code == 200
    assert "list_topics" in listed.text
    assert TOKEN not in log
    assert wrong not in log
    assert json.dumps(TOKEN)[1:-1] not in log


async def test_tls_serves_https_with_the_given_certificate(sim_ros2: SimulatedRobot, tmp_path: Path) -> None:
    """--tls-cert/--tls-key: the server speaks HTTPS; a client trusting the CA initializes with its token."""
    authority = trustme.CA()
    certificate = authority.issue_cert("127.0.0.1", "localhost")
    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    certificate.cert_chain_pems[0].write_to_path(str(cert))
    certificate.private_key_pem.write_to_path(str(key))
    context = ssl.create_default_context()
    authority.configure_trust(context)
    flags = ("--url", sim_ros2.url, "--tls-cert", str(cert), "--tls-key", str(key))
    async with serving("http", *flags) as served:
        assert served.url.startswith("https://127.0.0.1:")
        async with httpx2.AsyncClient(timeout=WAIT, verify=context) as http:
            response = await http.post(served.url, json=INITIALIZE, headers=_headers(TOKEN))
        async with httpx2.AsyncClient(timeout=WAIT) as untrusting:
            with pytest.raises(httpx2.ConnectError):
                await untrusting.post(served.url, json=INITIALIZE, headers=_headers(TOKEN))
    assert response.status_code == 200
