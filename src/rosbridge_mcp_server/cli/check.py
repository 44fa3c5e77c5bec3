"""``rosbridge-mcp-server check``: a diagnosis of the connection to rosbridge, for a person at a terminal.

It is not the MCP server, so it writes to stdout. It says whether the bridge is reachable (and if not, what to
try), which ROS and distro it runs, what this rosbridge can do, whether rosapi answers, and how many topics,
services and actions it sees. Exit code 0 when healthy, 1 when not.
"""

from __future__ import annotations

import asyncio
from typing import TextIO
from urllib.parse import urlsplit

from rosbridge_mcp_server import __version__
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.config import Config, plain_text_warning
from rosbridge_mcp_server.errors import NotConnectedError, RosbridgeError
from rosbridge_mcp_server.robot.graph import RosGraph
from rosbridge_mcp_server.wire.dialect import RosInfo

__all__ = ["run_check", "unreachable_advice"]

_OK = "ok  "
_BAD = "FAIL"
_NOTE = "note"


def unreachable_advice(url: str, reason: str | None) -> list[str]:
    """What to try when nothing answers at ``url``, most likely cause first."""
    parts = urlsplit(url)
    host = parts.hostname or "?"
    secure = parts.scheme == "wss"
    port = parts.port or (443 if secure else 80)
    text = (reason or "").lower()
    advice: list[str] = []
    if "refused" in text or "connect call failed" in text:
        advice.append(f"Nothing listens on {host}:{port}: is rosbridge running, and on this port?")
    elif "name" in text and ("resolution" in text or "not known" in text or "resolve" in text):
        advice.append(f"The host name {host!r} does not resolve: check the spelling, or use the IP address.")
    elif "timed out" in text or "timeout" in text:
        advice.append(
            f"{host}:{port} did not answer in time: check the address, that the robot is on this network, "
            "and that no firewall blocks the port."
        )
    if "invalidstatus" in text or "rejected websocket" in text:
        advice.append(
            f"Something at {host}:{port} answers HTTP but refused the WebSocket upgrade: is this rosbridge's "
            "port, and is the URL path right? rosbridge serves at / unless its url_path is set."
        )
    elif secure and (not text or any(word in text for word in ("ssl", "tls", "certificate", "handshake"))):
        advice.append("The TLS handshake failed: if rosbridge runs without TLS, use ws:// instead of wss://.")
    elif not secure and any(word in text for word in ("invalid http", "valid http", "handshake")):
        advice.append("The server did not answer like a WebSocket server: if it uses TLS, try wss://.")
    advice += [
        "Start rosbridge on the robot: `ros2 launch rosbridge_server rosbridge_websocket_launch.xml` (ROS "
        "2) or `roslaunch rosbridge_server rosbridge_websocket.launch` (ROS 1).",
        f"Check host and port: ROSBRIDGE_HOST / ROSBRIDGE_PORT (or ROSBRIDGE_URL); now {url}. rosbridge's "
        "default port is 9090.",
        f"Check that a firewall lets TCP port {port} through (e.g. `nc -vz {host} {port}`).",
        "Check ws:// versus wss://: rosbridge speaks plain ws:// unless it was started with TLS.",
    ]
    return advice


def _count(number: int, noun: str) -> str:
    return f"{number} {noun}{'' if number == 1 else 's'}"


def _features(info: RosInfo, services: set[str]) -> list[tuple[str, str]]:
    """What this rosbridge can do, told from its ROS version and from which rosapi services it offers."""
    if info.version == 1:
        return [
            (_NOTE, "actions: over actionlib topics (ROS 1 rosbridge has no action ops)"),
            (
                _NOTE,
                "service calls: ROS 1 rosbridge has no timeout field; this server applies its own deadline",
            ),
        ]
    # rosapi grew with rosbridge: `interfaces` came with Humble 2.0.1 / Jazzy 2.2.0 (as did the call_service
    # timeout field), `action_type` with Humble 2.0.2 / Jazzy 2.4.0. Action ops exist from 2.0.0 on.
    recent = "/rosapi/interfaces" in services
    features = [
        (
            (_OK, "actions: native action ops (rosbridge 2.0.0 and later)")
            if recent
            else (
                _NOTE,
                "actions: native action ops from rosbridge 2.0.0 on; this bridge may be older (1.3.x)",
            )
        ),
        (
            (_OK, "service calls: the bridge reads the timeout field")
            if recent
            else (_NOTE, "service calls: this bridge may ignore the timeout field; this server keeps its own")
        ),
    ]
    if "/rosapi/action_type" not in services:
        features.append((_NOTE, "action types: no /rosapi/action_type here; read from the action's topics"))
    if info.may_be_in_order:
        features.append(
            (
                _NOTE,
                "this bridge may handle one connection strictly in order (Humble defaults): goals and "
                "service calls run on extra connections so they do not block each other",
            )
        )
    else:
        features.append((_OK, "calls on one connection run side by side"))
    return features


async def run_check(config: Config, out: TextIO) -> int:
    """Run the diagnosis against ``config.url``, writing to ``out``; 0 when healthy, 1 when not."""

    def say(mark: str, text: str) -> None:
        out.write(f"[{mark}] {text}\n")

    out.write(f"rosbridge-mcp-server {__version__}: checking {config.url}\n")
    if config.demo:
        say(_NOTE, f"demo mode: this is the built-in simulated ROS {config.demo_dialect[-1]} robot")
    for line in config.policy.describe():
        say(_NOTE, f"safety {line.strip()}" if not line.startswith(" ") else f"  {line.strip()}")
    warning = plain_text_warning(config.url)
    if warning:
        say(_NOTE, warning)

    async with RosbridgeClient(
        config.url,
        connect_timeout=config.connect_timeout,
        request_timeout=config.request_timeout,
        ssl_context=config.ssl_context(),
        headers=config.headers,
    ) as client:
        try:
            # ros_info() waits for the first connection attempt only, so a refused connection shows at once.
            info = await client.ros_info()
        except NotConnectedError as exc:
            say(_BAD, f"cannot reach rosbridge at {config.url}: {exc.reason or 'no connection'}")
            out.write("What to try:\n")
            for line in unreachable_advice(config.url, exc.reason):
                out.write(f"  - {line}\n")
            return 1
        say(_OK, f"rosbridge reachable at {config.url}")
        distro = info.distro or ("unknown distro" if info.version == 2 else "Melodic/Noetic line")
        say(_OK, f"ROS {info.version} ({distro})")

        graph = RosGraph(client)
        try:
            topics, services, actions = await asyncio.gather(
                graph.topics(), graph.service_names(), graph.action_names()
            )
        except RosbridgeError as exc:
            say(_BAD, f"rosapi does not answer: {exc}")
            return 1
        say(_OK, "rosapi answers")
        for mark, text in _features(info, set(services)):
            say(mark, text)
        counts = [
            _count(len(topics), "topic"),
            _count(len(services), "service"),
            _count(len(actions), "action server"),
        ]
        say(_OK, ", ".join(counts))
        out.write("Healthy: the MCP server can use this bridge.\n")
        return 0
