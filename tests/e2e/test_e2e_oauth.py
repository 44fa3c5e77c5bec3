"""OAuth 2.1 resource-server mode over real HTTP, with keys generated here: JWTs checked for signature,
issuer, audience, expiry and scope; the protected-resource metadata the MCP spec asks for."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import httpx2
import jwt
import pytest
from cryptography.hazmat.primitives.asymmetric import rsa
from e2e_transports import INITIALIZE, WAIT, serving
from jwt.algorithms import RSAAlgorithm

from rosbridge_mcp_server.sim import SimulatedRobot

ISSUER = "https://auth.example.com"
AUDIENCE = "rosbridge-mcp"
RESOURCE = "https://robot.example.com/mcp"


@pytest.fixture(scope="module")
def keys() -> tuple[Any, Any]:
    """The issuer's signing key and a stranger's."""
    return (
        rsa.generate_private_key(public_exponent=65537, key_size=2048),
        rsa.generate_private_key(public_exponent=65537, key_size=2048),
    )


def _jwks(path: Path, key: Any) -> Path:
    public = json.loads(RSAAlgorithm.to_jwk(key.public_key()))
    path.write_text(json.dumps({"keys": [{**public, "kid": "k1", "alg": "RS256", "use": "sig"}]}))
    return path


def _token(key: Any, **claims: Any) -> str:
    now = int(time.time())
    body = {"iss": ISSUER, "aud": AUDIENCE, "sub": "alice", "exp": now + 600, "iat": now, "scope": "robot"}
    body.update(claims)
    return jwt.encode({k: v for k, v in body.items() if v is not None}, key, "RS256", headers={"kid": "k1"})


def _flags(robot: SimulatedRobot, jwks: Path, *extra: str) -> tuple[str, ...]:
    return (
        "--url",
        robot.url,
        "--oauth-issuer",
        ISSUER,
        "--oauth-audience",
        AUDIENCE,
        "--oauth-jwks",
        str(jwks),
        "--oauth-resource",
        RESOURCE,
        *extra,
    )


async def _initialize(url: str, token: str) -> httpx2.Response:
    headers = {
        "Content-Type": "application/json",
        "Accept": "application/json, text/event-stream",
        "Authorization": f"Bearer {token}",
    }
    async with httpx2.AsyncClient(timeout=WAIT) as http:
        return await http.post(url, json=INITIALIZE, headers=headers)


async def test_a_valid_jwt_opens_a_session_and_bad_ones_are_401(
    sim_ros2: SimulatedRobot, tmp_path: Path, keys: tuple[Any, Any]
) -> None:
    """Expired, wrong audience, wrong issuer, a stranger's signature: 401 with the metadata's address."""
    issuer_key, stranger = keys
    jwks = _jwks(tmp_path / "jwks.json", issuer_key)
    async with serving("http", *_flags(sim_ros2, jwks), tokens=False) as served:
        good = await _initialize(served.url, _token(issuer_key))
        bad = {
            "expired": await _initialize(served.url, _token(issuer_key, exp=int(time.time()) - 3600)),
            "audience": await _initialize(served.url, _token(issuer_key, aud="another-service")),
            "issuer": await _initialize(served.url, _token(issuer_key, iss="https://evil.example.com")),
            "signature": await _initialize(served.url, _token(stranger)),
            "no expiry": await _initialize(served.url, _token(issuer_key, exp=None)),
        }
    assert good.status_code == 200
    assert {name: r.status_code for name, r in bad.items()} == dict.fromkeys(bad, 401)
    challenge = bad["expired"].headers["www-authenticate"]
    assert challenge.startswith("Bearer ")
    metadata = "https://robot.example.com/.well-known/oauth-protected-resource/mcp"
    assert f'resource_metadata="{metadata}"' in challenge


async def test_a_token_without_the_required_scope_is_403(
    sim_ros2: SimulatedRobot, tmp_path: Path, keys: tuple[Any, Any]
) -> None:
    """--oauth-scopes: a valid token lacking one is refused with 403 insufficient_scope."""
    issuer_key, _ = keys
    jwks = _jwks(tmp_path / "jwks.json", issuer_key)
    flags = _flags(sim_ros2, jwks, "--oauth-scopes", "robot:drive")
    async with serving("http", *flags, tokens=False) as served:
        lacking = await _initialize(served.url, _token(issuer_key, scope="robot:read"))
        holding = await _initialize(served.url, _token(issuer_key, scope="robot:read robot:drive"))
    assert lacking.status_code == 403
    assert 'error="insufficient_scope"' in lacking.headers["www-authenticate"]
    assert holding.status_code == 200


async def test_the_protected_resource_metadata_names_the_issuer(
    sim_ros2: SimulatedRobot, tmp_path: Path, keys: tuple[Any, Any]
) -> None:
    """RFC 9728 metadata at /.well-known/oauth-protected-resource/mcp, readable without a token."""
    issuer_key, _ = keys
    jwks = _jwks(tmp_path / "jwks.json", issuer_key)
    async with serving("http", *_flags(sim_ros2, jwks), tokens=False) as served:
        base = served.url.removesuffix("/mcp")
        async with httpx2.AsyncClient(timeout=WAIT) as http:
            response = await http.get(f"{base}/.well-known/oauth-protected-resource/mcp")
    assert response.status_code == 200
    metadata = response.json()
    assert metadata["resource"] == RESOURCE
    assert metadata["authorization_servers"] == [ISSUER]


async def test_the_audit_names_the_tokens_subject(
    sim_ros2: SimulatedRobot, tmp_path: Path, keys: tuple[Any, Any]
) -> None:
    """An acting call made with a JWT is audited under the token's subject."""
    issuer_key, _ = keys
    jwks = _jwks(tmp_path / "jwks.json", issuer_key)
    audit = tmp_path / "audit.jsonl"
    flags = _flags(sim_ros2, jwks, "--audit-log", str(audit))
    async with (
        serving("http", *flags, tokens=False) as served,
        served.connect(token=_token(issuer_key, sub="operator-alice")) as client,
    ):
        result = await client.call_tool(
            "publish_topic",
            {"topic": "/turtle1/cmd_vel", "message_type": "geometry_msgs/msg/Twist", "message": {}},
        )
    assert not result.is_error
    [line] = [json.loads(line) for line in audit.read_text().splitlines()]
    assert line["caller"] == "operator-alice"


#: Validly signed tokens with a claim of the wrong JSON type, each refused with 401 (null scope was HTTP 500).
WRONG_TYPES: dict[str, dict[str, Any]] = {
    "scope null": {"scope": None, "scp": None},
    "scope a number": {"scope": 7},
    "scope a list of numbers": {"scope": [1, 2]},
    "scope an object": {"scope": {"robot": True}},
    "scp null": {"scope": ..., "scp": None},
    "sub a number": {"sub": 42},
    "sub a list": {"sub": ["alice"]},
    "sub null": {"sub": None},
    "client_id an object": {"client_id": {"name": "x"}},
    "azp true": {"azp": True},
    "exp a string": {"exp": "tomorrow"},
    "exp infinite": {"exp": float("inf")},
}


def _signed(key: Any, claims: dict[str, Any]) -> str:
    """A token signed by *key* with exactly these claims over the valid ones (``None`` kept as JSON null,
    ``...`` leaves the claim out)."""
    now = int(time.time())
    body = {"iss": ISSUER, "aud": AUDIENCE, "sub": "alice", "exp": now + 600, "iat": now, "scope": "robot"}
    body.update(claims)
    body = {name: value for name, value in body.items() if value is not ...}
    payload = json.dumps(body, allow_nan=True).encode()
    return jwt.api_jws.encode(payload, key, "RS256", headers={"kid": "k1"})


async def test_a_signed_token_whose_claims_have_the_wrong_type_is_401_not_500(
    sim_ros2: SimulatedRobot, tmp_path: Path, keys: tuple[Any, Any]
) -> None:
    """scope, scp, sub, client_id, azp and exp of a JSON type they cannot have: 401, like any bad token."""
    issuer_key, _ = keys
    jwks = _jwks(tmp_path / "jwks.json", issuer_key)
    async with serving("http", *_flags(sim_ros2, jwks), tokens=False) as served:
        statuses = {
            name: (await _initialize(served.url, _signed(issuer_key, claims))).status_code
            for name, claims in WRONG_TYPES.items()
        }
        listed = (
            await _initialize(served.url, _signed(issuer_key, {"scope": ..., "scp": ["robot"]}))
        ).status_code
    assert statuses == dict.fromkeys(WRONG_TYPES, 401)
    assert listed == 200


async def test_a_newline_in_the_subject_cannot_forge_an_audit_line(
    sim_ros2: SimulatedRobot, tmp_path: Path, keys: tuple[Any, Any]
) -> None:
    """A subject holding a newline and an audit line of its own: the audit on stderr and in the file names the
    caller escaped, on one line; no line of stderr is the forged one."""
    issuer_key, _ = keys
    jwks = _jwks(tmp_path / "jwks.json", issuer_key)
    audit = tmp_path / "audit.jsonl"
    forged = "2026-01-01 00:00:00,000 WARNING rosbridge_mcp_server.audit: audit: stop_robot refused"
    subject = f"mallory\n{forged}\x1b[2K\u202e"
    flags = _flags(sim_ros2, jwks, "--audit-log", str(audit))
    async with (
        serving("http", *flags, tokens=False) as served,
        served.connect(token=_signed(issuer_key, {"sub": subject})) as client,
    ):
        result = await client.call_tool(
            "publish_topic",
            {"topic": "/turtle1/cmd_vel", "message_type": "geometry_msgs/msg/Twist", "message": {}},
        )
    assert not result.is_error
    [line] = [json.loads(line) for line in audit.read_text().splitlines()]
    assert line["caller"] == f"mallory\\n{forged}\\x1b[2K\\u202e"
    stderr = "".join(served.stderr)
    assert not any(row.startswith(forged) for row in stderr.splitlines()), stderr
    assert "[caller mallory\\n2026-01-01" in stderr
