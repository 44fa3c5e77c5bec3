"""The bridge's dialect has one owner: each session's ``Dialect`` spells types and time fields once."""

from __future__ import annotations

import ast
import json
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
from client_harness import MakeClient
from websockets.asyncio.server import ServerConnection, serve

import rosbridge_mcp_server
from rosbridge_mcp_server.client import Dialect, RosbridgeClient
from rosbridge_mcp_server.sim import SimulatedRobot


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is done with the answers is tested."""
    return True


STAMPED = {"stamp": {"sec": 12, "nanosec": 34}, "label": "x"}


class RecordingBridge:
    """A raw bridge of one ROS *version* that answers every call with ``{}`` and keeps each call's args."""

    def __init__(self, version: int) -> None:
        self.version = version
        self.url = ""
        self.args: dict[str, Any] = {}

    async def handler(self, ws: ServerConnection) -> None:
        async for raw in ws:
            request = json.loads(raw)
            if request.get("op") != "call_service":
                continue
            service = request["service"]
            self.args[service] = request.get("args")
            values = (
                {"version": self.version, "distro": "test"} if service.endswith("get_ros_version") else {}
            )
            reply = {"op": "service_response", "id": request["id"], "service": service, "result": True}
            await ws.send(json.dumps({**reply, "values": values}))


@pytest.fixture(params=[1, 2], ids=["ros1", "ros2"])
async def recording(request: pytest.FixtureRequest) -> AsyncIterator[RecordingBridge]:
    bridge = RecordingBridge(request.param)
    async with serve(bridge.handler, "127.0.0.1", 0) as server:
        bridge.url = f"ws://127.0.0.1:{server.sockets[0].getsockname()[1]}"
        yield bridge


async def test_each_session_spells_types_the_way_its_bridge_reads_them(
    sim_ros1: SimulatedRobot, sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """ROS 1 gets pkg/Type and pkg/TAction, ROS 2 pkg/msg/T, pkg/srv/T and pkg/action/T, from one name."""
    ros1 = await (await make_client(sim_ros1)).dialect()
    ros2 = await (await make_client(sim_ros2)).dialect()
    assert (ros1.version, ros2.version) == (1, 2)
    assert ros1.message_type("geometry_msgs/msg/Twist") == "geometry_msgs/Twist"
    assert ros2.message_type("geometry_msgs/Twist") == "geometry_msgs/msg/Twist"
    assert ros1.service_type("std_srvs/srv/Trigger") == "std_srvs/Trigger"
    assert ros2.service_type("std_srvs/Trigger") == "std_srvs/srv/Trigger"
    assert ros1.action_type("actionlib_tutorials/action/Fibonacci") == "actionlib_tutorials/FibonacciAction"
    assert ros2.action_type("example_interfaces/FibonacciAction") == "example_interfaces/action/Fibonacci"


async def test_the_dialect_is_the_sessions_and_is_replaced_with_it(
    sim_ros2: SimulatedRobot, make_client: MakeClient
) -> None:
    """A reconnect brings a new session and with it a dialect built from the new bridge's RosInfo."""
    client = await make_client(sim_ros2)
    first = await client.dialect()
    assert client.session is not None
    assert client.session.dialect is first
    assert first.info is client.session.info
    await sim_ros2.drop_connections()
    await client.wait_disconnected(5.0)
    await client.wait_connected(30.0)
    second = await client.dialect()
    assert second is not first
    assert client.session is not None
    assert second.info is client.session.info
    assert client.connections_made == 2


async def test_a_service_request_is_respelled_once_on_the_way_out(recording: RecordingBridge) -> None:
    """ROS 1 gets secs/nsecs (it ignores sec/nanosec); ROS 2 reads both: the request goes out as written."""
    async with RosbridgeClient(recording.url, reconnect_min=0.05, reconnect_max=0.2) as client:
        await client.wait_connected(30.0)
        await client.call_service("/stamp_echo", STAMPED, timeout=5.0, isolated=False)
    sent = recording.args["/stamp_echo"]
    if recording.version == 1:
        assert sent == {"stamp": {"secs": 12, "nsecs": 34}, "label": "x"}
    else:
        assert sent == STAMPED
    assert STAMPED["stamp"] == {"sec": 12, "nanosec": 34}, "the caller's request is not modified"


@pytest.mark.parametrize(
    ("version", "qos", "sent", "note"),
    [
        (2, {"durability": "transient_local"}, {"durability": "transient_local"}, "QoS sent"),
        (2, {"depth": 5}, {"depth": 5, "history": "keep_last"}, "QoS sent"),
        (1, {"durability": "transient_local"}, None, "QoS not applied: ROS 1 has no QoS"),
        (1, {}, None, None),
        (2, None, None, None),
    ],
)
def test_qos_is_sent_only_where_the_bridge_reads_it(
    version: int, qos: dict[str, Any] | None, sent: dict[str, Any] | None, note: str | None
) -> None:
    """ROS 2 gets the QoS object (depth implies keep_last); ROS 1 gets none and a note saying so."""
    wire, said = Dialect.for_version(version).subscription_qos(qos)
    assert wire == sent
    if note is None:
        assert said is None
    else:
        assert said is not None
        assert said.startswith(note)


def test_large_messages_go_as_cbor_unless_a_fixed_size_array_forbids_it() -> None:
    """rosbridge_suite cannot send a fixed-size array as CBOR; only ROS 2 drops a large CBOR frame."""
    assert Dialect.compression_for(fixed_size_arrays=False) == "cbor"
    assert Dialect.compression_for(fixed_size_arrays=True) is None
    assert Dialect.for_version(2).drops_large_cbor
    assert not Dialect.for_version(1).drops_large_cbor


@pytest.mark.parametrize(
    ("version", "code", "word", "ended", "succeeded"),
    [
        (2, 4, "succeeded", True, True),
        (1, 3, "succeeded", True, True),
        (1, 2, "preempted", True, False),
        (2, 2, "executing", False, False),
    ],
)
def test_goal_states_are_read_in_the_numbering_of_the_dialect(
    version: int, code: int, word: str, ended: bool, succeeded: bool
) -> None:
    """ROS 2 numbers goal states 0..6, ROS 1 (actionlib) 0..9."""
    dialect = Dialect.for_version(version)
    assert (dialect.goal_status(code), dialect.goal_ended(code), dialect.goal_succeeded(code)) == (
        word,
        ended,
        succeeded,
    )


@pytest.mark.parametrize(
    ("stamp", "seconds"),
    [
        pytest.param({"sec": 12, "nanosec": 500_000_000}, 12.5, id="ros2"),
        pytest.param({"secs": 12, "nsecs": 250_000_000}, 12.25, id="ros1"),
        pytest.param({"sec": 3}, 3.0, id="seconds-only"),
        pytest.param({"sec": 0, "nanosec": 0}, None, id="unset"),
        pytest.param({"sec": "12"}, None, id="not-a-number"),
        pytest.param(12.5, None, id="not-a-time"),
    ],
)
def test_a_received_time_is_read_in_either_spelling(stamp: Any, seconds: float | None) -> None:
    """Stamps the bridge sends read as seconds whichever line wrote them; an unset stamp is no time."""
    assert Dialect.seconds(stamp) == seconds


def _importers(module: str, allowed: tuple[str, ...]) -> list[str]:
    """Our modules outside the *allowed* top-level packages that import *module* or anything under it."""
    package = Path(rosbridge_mcp_server.__file__).parent
    offenders = []
    for path in package.rglob("*.py"):
        if path.relative_to(package).parts[0] in allowed:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = []
            if isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module] + [f"{node.module}.{alias.name}" for alias in node.names]
            elif isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            if any(name == module or name.startswith(module + ".") for name in names):
                offenders.append(str(path.relative_to(package)))
    return offenders


def test_only_the_client_and_the_wire_import_the_dialect_rules() -> None:
    """robot/, tools/, cli/ and the rest ask the client's Dialect; none imports wire.dialect."""
    offenders = _importers("rosbridge_mcp_server.wire.ros_versions", ("wire", "client"))
    assert offenders == []


def test_only_the_client_builds_ops_among_the_layers_above_the_wire() -> None:
    """robot/, tools/, safety/ and the rest send through the client's methods; none imports wire/ (the
    simulated robot, a bridge of its own, may)."""
    offenders = _importers("rosbridge_mcp_server.wire", ("wire", "client", "sim"))
    assert offenders == []
