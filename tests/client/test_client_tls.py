"""Connection security: wss:// with a private CA and a client certificate, and extra handshake headers."""

from __future__ import annotations

import ssl
from pathlib import Path

import pytest
import trustme
from websockets.asyncio.server import ServerConnection, serve

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import load_config
from rosbridge_mcp_server.errors import NotConnectedError
from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 30.0


@pytest.fixture
def ca() -> trustme.CA:
    """A certificate authority made for this test only."""
    return trustme.CA()


def server_context(ca: trustme.CA, *, require_client_cert: bool = False) -> ssl.SSLContext:
    context = ssl.create_default_context(ssl.Purpose.CLIENT_AUTH)
    ca.issue_cert("127.0.0.1").configure_cert(context)
    if require_client_cert:
        ca.configure_trust(context)
        context.verify_mode = ssl.CERT_REQUIRED
    return context


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_wss_with_a_private_ca_file_reaches_the_robot(
    ca: trustme.CA, tmp_path: Path, dialect: str
) -> None:
    """--ca-file makes a robot with a self-signed CA reachable over wss://, in either dialect."""
    ca_file = tmp_path / "ca.pem"
    ca.cert_pem.write_to_path(str(ca_file))
    async with SimulatedRobot(dialect=dialect, port=0, ssl=server_context(ca)) as robot:  # type: ignore[arg-type]
        assert robot.url.startswith("wss://")
        config = load_config({}, url=robot.url, ca_file=str(ca_file))
        async with RosbridgeClient(robot.url, ssl_context=config.ssl_context()) as client:
            info = await client.ros_info()
            assert info.version == (2 if dialect == "ros2" else 1)
            topics = await client.call_service("/rosapi/topics", {})
            assert "/turtle1/cmd_vel" in topics["topics"]


async def test_wss_without_the_ca_is_refused_and_says_the_certificate_was_not_accepted(
    ca: trustme.CA,
) -> None:
    """The system's CAs do not vouch for a private CA: the connection fails with a reason saying so."""
    async with (
        SimulatedRobot(port=0, ssl=server_context(ca)) as robot,
        RosbridgeClient(robot.url, connect_timeout=WAIT) as client,
    ):
        with pytest.raises(NotConnectedError, match=r"TLS certificate was not accepted"):
            await client.ros_info()


async def test_a_client_certificate_is_presented_when_the_bridge_requires_one(
    ca: trustme.CA, tmp_path: Path
) -> None:
    """A bridge (or TLS proxy) that requires client certificates lets in only the client that has one."""
    ca_file, cert_file = tmp_path / "ca.pem", tmp_path / "client.pem"
    ca.cert_pem.write_to_path(str(ca_file))
    ca.issue_cert("robot-operator@example.com").private_key_and_cert_chain_pem.write_to_path(str(cert_file))
    async with SimulatedRobot(port=0, ssl=server_context(ca, require_client_cert=True)) as robot:
        with_cert = load_config({}, url=robot.url, ca_file=str(ca_file), client_cert=str(cert_file))
        async with RosbridgeClient(robot.url, ssl_context=with_cert.ssl_context()) as client:
            assert (await client.ros_info()).version == 2
        without = load_config({}, url=robot.url, ca_file=str(ca_file))
        async with RosbridgeClient(
            robot.url, ssl_context=without.ssl_context(), connect_timeout=WAIT
        ) as client:
            with pytest.raises(NotConnectedError):
                await client.ros_info()


async def test_extra_headers_go_with_every_handshake() -> None:
    """An Authorization header (for a bridge behind an authenticating proxy) reaches the server."""
    seen: list[str | None] = []

    async def handler(ws: ServerConnection) -> None:
        assert ws.request is not None
        seen.append(ws.request.headers.get("Authorization"))
        await ws.close()

    async with serve(handler, "127.0.0.1", 0) as server:
        port = server.sockets[0].getsockname()[1]
        url = f"ws://127.0.0.1:{port}"
        config = load_config({"ROSBRIDGE_HEADERS": "Authorization: Bearer t0ken"}, url=url)
        async with RosbridgeClient(url, headers=config.headers, connect_timeout=WAIT) as client:
            with pytest.raises(NotConnectedError):
                await client.ros_info()
    assert seen
    assert seen[0] == "Bearer t0ken"
