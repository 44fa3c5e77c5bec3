"""The console's guard: the session secret in a header for every /api request, its own Host only, no motion.

These talk HTTP/1.1 to a served console over a real socket (a few lines of asyncio streams below), the page's
own requests being covered by the browser tests.
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from typing import Any
from urllib.parse import urlsplit

import pytest
from console_harness import Console, served_console, text_of

from rosbridge_mcp_server.config import ConfigError
from rosbridge_mcp_server.console import console_settings
from rosbridge_mcp_server.console.web import SECRET_HEADER
from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot

CMD_VEL = "/turtle1/cmd_vel"
WAIT = 30.0  # a bound on an event, not a pause: a busy machine (load 20 on 2 cores) still passes
TWIST_CALL = {"topic": CMD_VEL, "message_type": "geometry_msgs/msg/Twist", "message": {"linear": {"x": 0.4}}}


@dataclass
class Answer:
    status_code: int
    headers: dict[str, str]
    text: str

    def json(self) -> Any:
        return json.loads(self.text)


class Http:
    """Just enough of an HTTP/1.1 client: one request per connection."""

    def __init__(self, base_url: str) -> None:
        parts = urlsplit(base_url)
        assert parts.hostname is not None
        assert parts.port is not None
        self.host, self.port = parts.hostname, parts.port

    async def __aenter__(self) -> Http:
        return self

    async def __aexit__(self, *exc: object) -> None:
        return None

    async def _open(
        self, method: str, path: str, headers: dict[str, str] | None, body: Any
    ) -> tuple[asyncio.StreamReader, asyncio.StreamWriter, int, dict[str, str]]:
        reader, writer = await asyncio.open_connection(self.host, self.port)
        data = b"" if body is None else json.dumps(body).encode()
        lines = {"Host": f"{self.host}:{self.port}", "Connection": "close", "Content-Length": str(len(data))}
        if body is not None:
            lines["Content-Type"] = "application/json"
        lines.update(headers or {})
        head = f"{method} {path} HTTP/1.1\r\n" + "".join(f"{k}: {v}\r\n" for k, v in lines.items()) + "\r\n"
        writer.write(head.encode() + data)
        await writer.drain()
        async with asyncio.timeout(WAIT):
            status = int((await reader.readline()).split()[1])
            received: dict[str, str] = {}
            while (line := (await reader.readline()).decode().rstrip("\r\n")) != "":
                name, _, value = line.partition(":")
                received[name.strip().lower()] = value.strip()
        return reader, writer, status, received

    async def request(
        self, method: str, path: str, headers: dict[str, str] | None = None, json: Any = None
    ) -> Answer:
        reader, writer, status, received = await self._open(method, path, headers, json)
        try:
            async with asyncio.timeout(WAIT):
                body = await reader.read()
        finally:
            writer.close()
        return Answer(status, received, body.decode())

    async def post(self, path: str, headers: dict[str, str] | None = None, json: Any = None) -> Answer:
        return await self.request("POST", path, headers, json)

    async def get(self, path: str, headers: dict[str, str] | None = None) -> Answer:
        return await self.request("GET", path, headers)

    @asynccontextmanager
    async def stream(
        self, path: str, headers: dict[str, str]
    ) -> AsyncIterator[tuple[Answer, asyncio.StreamReader]]:
        reader, writer, status, received = await self._open("GET", path, headers, None)
        try:
            yield Answer(status, received, ""), reader
        finally:
            writer.close()


def http(console: Console) -> Http:
    return Http(console.running.base_url)


def secret(console: Console) -> dict[str, str]:
    return {SECRET_HEADER: console.running.secret}


async def first_pending(console: Console) -> str:
    changed = asyncio.Event()
    console.operator.listen(changed.set)
    async with asyncio.timeout(WAIT):
        while not console.operator.pending:
            await changed.wait()
            changed.clear()
    return console.operator.pending[0].id


@pytest.mark.parametrize(
    "headers",
    [
        {},
        {SECRET_HEADER: "guess"},
        {"Cookie": "secret=anything"},
        {"Origin": "http://evil.example"},
        {"Origin": "null"},
    ],
)
async def test_a_request_without_the_secret_changes_nothing(
    sim_ros2: SimulatedRobot, headers: dict[str, str]
) -> None:
    """E-STOP, approve, the camera and the map panel are refused (403) without the secret; nothing moves."""
    policy = parse_policy({"confirm": "motion", "confirm_timeout": 30})
    async with served_console(sim_ros2.url, policy) as console, http(console) as web:
        calling = asyncio.create_task(console.call("publish_topic", TWIST_CALL))
        pending_id = await first_pending(console)
        for path in ("/api/estop", f"/api/confirmations/{pending_id}/approve", "/api/camera", "/api/map"):
            answer = await web.post(path, headers=headers, json={"topic": "/camera/image_raw"})
            assert answer.status_code == 403, path
            assert SECRET_HEADER in answer.json()["error"]
        assert (await web.get("/api/events", headers=headers)).status_code == 403
        assert console.operator.latched is None
        assert [p.id for p in console.operator.pending] == [pending_id]
        assert console.running.hub.camera_topic is None
        assert console.running.hub.map.topic == "/map"
        # The secret's owner still decides.
        denied = await web.post(f"/api/confirmations/{pending_id}/deny", headers=secret(console))
        assert denied.status_code == 200
        assert (await calling).is_error
    assert CMD_VEL not in sim_ros2.world.published


def own_origin(console: Console) -> dict[str, str]:
    """What a browser sends with a POST from a page of the console's own origin (a tab without the secret)."""
    return {"Origin": console.running.base_url.rstrip("/")}


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_estop_from_a_page_of_the_consoles_own_origin_stops_without_the_secret(
    make_sim: Any, dialect: str
) -> None:
    """A tab opened without the secret still has a working E-STOP: it ends a 10 Hz stream, latches, and
    answers with what it stopped; on the robot no command arrives after that answer."""
    sim = await make_sim(dialect=dialect)
    twist = "geometry_msgs/msg/Twist" if dialect == "ros2" else "geometry_msgs/Twist"
    call = {**TWIST_CALL, "message_type": twist, "rate_hz": 10, "duration": 30}
    async with served_console(sim.url) as console, http(console) as web:
        streaming = asyncio.create_task(console.call("publish_topic", call))
        await sim.world.wait_for(lambda world: len(world.published.get(CMD_VEL, ())) >= 2, 10)
        answer = await web.post("/api/estop", headers=own_origin(console))
        answered = time.monotonic()
        assert answer.status_code == 200, answer.text
        assert answer.json()["robots"][0]["streams_stopped"] == [CMD_VEL]
        assert console.operator.latched == "console"
        result = await asyncio.wait_for(streaming, 10)
        assert text_of(result).startswith("E-STOP on the operator console ended the stream"), text_of(result)
    late = [m for m in sim.world.published[CMD_VEL] if m.received_at > answered and m.msg["linear"]["x"]]
    assert late == []


async def test_a_page_of_the_consoles_own_origin_cannot_release_or_approve_without_the_secret(
    sim_ros2: SimulatedRobot,
) -> None:
    """Only stopping is open to such a tab: Release, Approve, the event stream need the secret still."""
    policy = parse_policy({"confirm": "motion", "confirm_timeout": 30})
    async with served_console(sim_ros2.url, policy) as console, http(console) as web:
        calling = asyncio.create_task(console.call("publish_topic", TWIST_CALL))
        pending_id = await first_pending(console)
        approve = await web.post(f"/api/confirmations/{pending_id}/approve", headers=own_origin(console))
        assert approve.status_code == 403
        assert (await web.get("/api/events", headers=own_origin(console))).status_code == 403
        assert (await web.post("/api/estop", headers=own_origin(console))).status_code == 200
        assert (await calling).is_error
        assert (await web.post("/api/release", headers=own_origin(console))).status_code == 403
        assert console.operator.latched == "console"
    assert CMD_VEL not in sim_ros2.world.published


async def test_release_needs_the_secret_too(sim_ros2: SimulatedRobot) -> None:
    """A latched stop stays latched for a request without the secret, and acting calls stay refused."""
    async with served_console(sim_ros2.url) as console, http(console) as web:
        assert (await web.post("/api/estop", headers=secret(console))).status_code == 200
        assert (await web.post("/api/release")).status_code == 403
        assert console.operator.latched == "console"
        refused = await console.call("publish_topic", TWIST_CALL)
        assert "E-STOP" in text_of(refused)
        released = await web.post("/api/release", headers=secret(console))
        assert released.json() == {"released": True, "latched": False}
        assert not (await console.call("publish_topic", TWIST_CALL)).is_error


async def test_the_console_has_no_way_to_send_a_command_of_its_own(sim_ros2: SimulatedRobot) -> None:
    """Even with the secret there is no publish, call or goal route: only approve, deny, stop and release."""
    async with served_console(sim_ros2.url) as console, http(console) as web:
        for path in ("/api/publish", "/api/publish_topic", "/api/call_service", "/api/tools/publish_topic"):
            answer = await web.post(path, headers=secret(console), json=TWIST_CALL)
            assert answer.status_code in (404, 405), path
        assert (await web.get("/api/estop", headers=secret(console))).status_code == 405
        assert console.operator.latched is None
    assert CMD_VEL not in sim_ros2.world.published


async def test_a_request_for_another_host_name_is_refused(sim_ros2: SimulatedRobot) -> None:
    """A page that rebinds its own name to 127.0.0.1 reaches the port but not the console (421)."""
    async with served_console(sim_ros2.url) as console, http(console) as web:
        port = console.running.base_url.rsplit(":", 1)[1].strip("/")
        answer = await web.post("/api/estop", headers={**secret(console), "Host": f"evil.example:{port}"})
        assert answer.status_code == 421
        assert (await web.get("/", headers={"Host": f"evil.example:{port}"})).status_code == 421
        assert console.operator.latched is None


async def test_the_page_itself_holds_no_data_and_forbids_framing(sim_ros2: SimulatedRobot) -> None:
    """GET / needs no secret but carries only code, with a strict content security policy."""
    async with served_console(sim_ros2.url) as console, http(console) as web:
        page = await web.get("/")
        assert page.status_code == 200
        assert "E-STOP" in page.text
        assert console.running.secret not in page.text
        assert "frame-ancestors 'none'" in page.headers["content-security-policy"]
        assert page.headers["x-frame-options"] == "DENY"


async def test_the_event_stream_pushes_the_state_to_the_secret_holder(sim_ros2: SimulatedRobot) -> None:
    """The first event is the whole state: the robot connected, nothing latched, nothing waiting."""
    async with (
        served_console(sim_ros2.url) as console,
        http(console) as web,
        web.stream("/api/events", headers=secret(console)) as (events, body),
    ):
        assert events.headers["content-type"].startswith("text/event-stream")
        async with asyncio.timeout(WAIT):
            text = ""
            while "\n\n" not in text:
                text += (await body.readline()).decode()
        # Chunked transfer: a size line, then the event.
        assert "event: state" in text
        data = text.split("data: ", 1)[1]
        assert '"connected":true' in data
        assert '"latched":false' in data


def test_loopback_is_the_default_and_other_addresses_need_tls_or_a_flag() -> None:
    """A port alone binds 127.0.0.1; 0.0.0.0 without --console-cert or --console-insecure is refused."""
    assert console_settings("8765") is not None
    settings = console_settings("8765")
    assert settings is not None
    assert (settings.host, settings.port, settings.scheme) == ("127.0.0.1", 8765, "http")
    with pytest.raises(ConfigError, match="not a loopback address"):
        console_settings("0.0.0.0:8765")
    insecure = console_settings("0.0.0.0:8765", insecure=True)
    assert insecure is not None
    assert insecure.host == "0.0.0.0"
    ipv6 = console_settings("[::1]:8765")
    assert ipv6 is not None
    assert ipv6.loopback


@pytest.mark.parametrize(
    ("address", "options", "message"),
    [
        ("", {}, "give a port"),
        ("host:port", {}, "port number"),
        ("::1:80", {}, "brackets"),
        ("8765", {"key": "key.pem"}, "--console-key needs --console-cert"),
        ("8765", {"cert": "/nonexistent/cert.pem"}, "does not exist"),
        (None, {"insecure": True}, "need --console"),
    ],
)
def test_a_bad_console_setting_is_named(
    address: str | None, options: dict[str, object], message: str
) -> None:
    """Each wrong console option is one sentence saying which and why."""
    with pytest.raises(ConfigError, match=message):
        console_settings(address, **options)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ({"topic": 5}, "topic must be a name"),
        ({"base_frame": ["base_link"]}, "base_frame must be a name"),
        ({"topic": "x" * 300}, "at most 256 characters"),
        ({"topic": "/bad topic"}, "bad topic"),
        ([1, 2], "the body must be JSON"),
    ],
)
async def test_a_bad_map_choice_is_named_and_changes_nothing(
    sim_ros2: SimulatedRobot, body: object, message: str
) -> None:
    """POST /api/map with a wrong field is a 400 naming it; the panel keeps its map topic and base frame."""
    async with served_console(sim_ros2.url) as console, http(console) as web:
        answer = await web.post("/api/map", headers=secret(console), json=body)
        assert answer.status_code == 400
        assert message in answer.json()["error"]
        assert (console.running.hub.map.topic, console.running.hub.map.base_frame) == ("/map", "base_link")
        chosen = await web.post(
            "/api/map", headers=secret(console), json={"topic": "/costmap", "base_frame": ""}
        )
        assert chosen.json() == {"topic": "/costmap", "base_frame": "base_link"}
