"""A bridge that answers like rosbridge/rosapi 2.1.0 (Jazzy and Kilted labs): what the client and graph learn.

The scripted answers are the ones the real 2.1.0 gave: no ``/rosapi/action_type``, hidden ``_action`` names
unknown to rosapi, the bridge's refusal of a call to ``<action>/_action/send_goal`` naming the type, and the
threading switches readable through ``/rosapi/get_param``.
"""

from __future__ import annotations

import json
from collections.abc import AsyncIterator, Callable
from typing import Any

import pytest
from client_harness import MakeClient
from websockets.asyncio.server import ServerConnection, serve

from rosbridge_mcp_server.client.ordering import PROBE_SERVICE_PREFIX
from rosbridge_mcp_server.robot.graph import RosGraph


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is done with the answers is tested."""
    return True


Answer = tuple[bool, Any]


class Rosbridge21:
    """Answers call_service like rosbridge 2.1.0 with the given threading switches; records every op."""

    def __init__(self, *, calls_threaded: bool = False, goals_threaded: bool = False) -> None:
        self.switches = {
            "call_services_in_new_thread": calls_threaded,
            "send_action_goals_in_new_thread": goals_threaded,
        }
        self.ops: list[dict[str, Any]] = []
        self.services: dict[str, Callable[[dict[str, Any]], Answer]] = {
            "/rosapi/get_ros_version": lambda _args: (True, {"version": 2, "distro": "jazzy"}),
            "/rosapi/nodes": lambda _args: (True, {"nodes": ["/rosapi", "/rosbridge_websocket", "/fib"]}),
            "/rosbridge_websocket/get_parameters": self._get_parameters,
            "/rosapi/action_servers": lambda _args: (True, {"action_servers": ["/fibonacci"]}),
            "/rosapi/topic_type": lambda _args: (True, {"type": ""}),
            "/fibonacci/_action/send_goal": self._send_goal,
        }

    def _get_parameters(self, args: dict[str, Any]) -> Answer:
        # As rclpy answers: a ParameterValue per name, type 1 (bool) if declared, 0 if not.
        values = [
            {"type": 1, "bool_value": self.switches[name]} if name in self.switches else {"type": 0}
            for name in args.get("names", [])
        ]
        return True, {"values": values}

    def _send_goal(self, args: dict[str, Any]) -> Answer:
        # 2.1.0 cannot load an action's services; the real text, before any request is built.
        return False, (
            "Unable to import srv class Fibonacci_SendGoal from package example_interfaces. Caused by module "
            "'example_interfaces.srv' has no attribute 'Fibonacci_SendGoal'"
        )

    async def handle(self, ws: ServerConnection) -> None:
        async for raw in ws:
            op: dict[str, Any] = json.loads(raw)
            self.ops.append(op)
            if op.get("op") != "call_service":
                continue
            answer = self.services.get(op["service"])
            ok, values = (
                answer(op.get("args") or {}) if answer else (False, f"Service {op['service']} does not exist")
            )
            await ws.send(
                json.dumps({"op": "service_response", "id": op["id"], "result": ok, "values": values})
            )


@pytest.fixture
async def serve_bridge() -> AsyncIterator[Callable[[Rosbridge21], Any]]:
    """Serve a scripted bridge on a loopback port: ``url = await serve_bridge(bridge)``."""
    servers: list[Any] = []

    async def start(bridge: Rosbridge21) -> str:
        server = await serve(bridge.handle, "127.0.0.1", 0, compression=None).__aenter__()
        servers.append(server)
        return f"ws://127.0.0.1:{server.sockets[0].getsockname()[1]}"

    yield start
    for server in servers:
        server.close()
        await server.wait_closed()


async def test_the_bridge_nodes_parameters_are_never_taken_for_the_bridges_behaviour(
    serve_bridge: Callable[[Rosbridge21], Any], make_client: MakeClient
) -> None:
    """A /rosbridge_websocket node saying its calls and goals are threaded is not believed (it may be another
    bridge on the graph): without a measurement the bridge counts as in order, and nothing asks parameters."""
    bridge = Rosbridge21(calls_threaded=True, goals_threaded=True)
    client = await make_client(await serve_bridge(bridge))
    info = await client.ros_info()
    assert info.distro == "jazzy"
    assert (info.calls_threaded, info.goals_threaded) == (None, None)
    assert info.may_be_in_order
    assert info.goals_may_block
    asked = [op.get("service") for op in bridge.ops]
    assert "/rosbridge_websocket/get_parameters" not in asked
    assert "/rosapi/get_param" not in asked


async def test_the_action_type_comes_from_the_bridges_refusal_of_a_send_goal_probe(
    serve_bridge: Callable[[Rosbridge21], Any], make_client: MakeClient
) -> None:
    """Without /rosapi/action_type the type is read from the send_goal refusal, and no goal is ever sent."""
    bridge = Rosbridge21()
    client = await make_client(await serve_bridge(bridge))
    graph = RosGraph(client)
    entries = await graph.actions()
    assert [(entry.name, entry.type) for entry in entries] == [
        ("/fibonacci", "example_interfaces/action/Fibonacci")
    ]
    probes = [op for op in bridge.ops if op.get("service") == "/fibonacci/_action/send_goal"]
    assert len(probes) == 1
    assert list(probes[0]["args"]) == ["__type_probe__"], "a field no request has: nothing is built"
    assert not [op for op in bridge.ops if op.get("op") == "send_action_goal"]
    # The answer is cached: a second listing asks the bridge nothing new.
    before = len(bridge.ops)
    assert (await graph.actions())[0].type == "example_interfaces/action/Fibonacci"
    asked = [op.get("service") for op in bridge.ops[before:]]
    assert asked == ["/rosapi/action_servers"]


async def test_a_newer_bridges_refusal_names_the_type_too(
    serve_bridge: Callable[[Rosbridge21], Any], make_client: MakeClient
) -> None:
    """A bridge that can load the action's services refuses the unknown field, naming the request type."""
    bridge = Rosbridge21()
    bridge.services["/fibonacci/_action/send_goal"] = lambda args: (
        False,
        "Message type example_interfaces/action/Fibonacci_SendGoal_Request does not have a field "
        + next(iter(args)),
    )
    client = await make_client(await serve_bridge(bridge))
    assert await RosGraph(client).action_type("/fibonacci") == "example_interfaces/action/Fibonacci"


def _strict(service_type: str) -> Callable[[dict[str, Any]], Answer]:
    """A service as rosbridge converts its request: an unknown field is refused, naming the request type."""

    def answer(args: dict[str, Any]) -> Answer:
        unknown = [name for name in args if name.startswith("_")]
        if unknown:
            return False, f"Message type {service_type}_Request does not have a field {unknown[0]}"
        return True, {}

    return answer


async def test_list_services_reads_types_from_the_bridges_refusals(
    serve_bridge: Callable[[Rosbridge21], Any], make_client: MakeClient
) -> None:
    """A bridge that refuses unknown fields names each service's type; rosapi's service_type is not asked."""
    bridge = Rosbridge21()
    bridge.services["/rosapi/services"] = lambda _args: (
        True,
        {"services": ["/add_two_ints", "/rosapi/get_time"]},
    )
    bridge.services["/rosapi/get_time"] = _strict("rosapi_msgs/GetTime")
    bridge.services["/add_two_ints"] = _strict("example_interfaces/AddTwoInts")
    client = await make_client(await serve_bridge(bridge))
    entries = await RosGraph(client).services()
    assert [(entry.name, entry.type) for entry in entries] == [
        ("/add_two_ints", "example_interfaces/srv/AddTwoInts"),
        ("/rosapi/get_time", "rosapi_msgs/srv/GetTime"),
    ]
    asked = [op for op in bridge.ops if op.get("service") == "/rosapi/service_type"]
    # Only the ordering measurement's look-ups of its own service (see client/ordering.py).
    assert all(op["args"]["service"].startswith(PROBE_SERVICE_PREFIX) for op in asked)


async def test_a_bridge_that_takes_unknown_fields_is_never_probed(
    serve_bridge: Callable[[Rosbridge21], Any], make_client: MakeClient
) -> None:
    """If rosapi's get_time takes the probe field, no service is probed: rosapi's service_type is asked."""
    bridge = Rosbridge21()
    bridge.services["/rosapi/services"] = lambda _args: (True, {"services": ["/reset"]})
    bridge.services["/rosapi/get_time"] = lambda _args: (True, {"time": {"sec": 1, "nanosec": 0}})
    bridge.services["/rosapi/service_type"] = lambda _args: (True, {"type": "std_srvs/srv/Empty"})
    client = await make_client(await serve_bridge(bridge))
    entries = await RosGraph(client).services()
    assert [(entry.name, entry.type) for entry in entries] == [("/reset", "std_srvs/srv/Empty")]
    assert not [op for op in bridge.ops if op.get("service") == "/reset"], "/reset is never called"
