"""What the client decides a bridge can do, from how the bridge behaves on the connection (three kinds)."""

from __future__ import annotations

from typing import Any

import pytest
from client_harness import MakeClient, MakeSim

from rosbridge_mcp_server.client import BridgeCapabilities


@pytest.fixture
def sim_in_memory() -> bool:
    """This module's robots are reached in memory (no port): what is done with the answers is tested."""
    return True


#: Per bridge: the simulated robot's options, and what the client must decide of it.
BRIDGES: dict[str, tuple[dict[str, Any], dict[str, bool]]] = {
    "ros1 0.11": (
        {"dialect": "ros1"},
        {
            "action_ops": False,
            "status_replies": False,
            "cancel_by_owner_only": False,
            "one_call_per_connection": True,
            "parameter_services_on_node": False,
            "get_param_names_safe": True,
            "node_details_of_unknown_safe": True,
            "drops_large_cbor": False,
        },
    ),
    "rosbridge_suite 2.1.0 (in order)": (
        {"dialect": "ros2", "in_order": True, "rosapi": "2.1.0"},
        {
            "action_ops": True,
            "status_replies": False,
            "cancel_by_owner_only": False,
            "goals_hold_connection": True,
            "calls_may_queue": True,
            "one_call_per_connection": False,
            "parameter_services_on_node": True,
            "get_param_names_safe": False,
            "node_details_of_unknown_safe": False,
            "drops_large_cbor": True,
        },
    ),
    "rosbridge-server-rs 0.1.6": (
        {"dialect": "ros2", "server": "rs"},
        {
            "action_ops": True,
            "status_replies": True,
            "cancel_by_owner_only": True,
            "goals_hold_connection": False,
            "calls_may_queue": False,
            "one_call_per_connection": False,
            "parameter_services_on_node": True,
            "get_param_names_safe": True,
            "node_details_of_unknown_safe": True,
            "drops_large_cbor": True,
        },
    ),
}


@pytest.mark.parametrize("bridge", sorted(BRIDGES))
async def test_the_client_names_what_each_kind_of_bridge_can_do(
    bridge: str, make_sim: MakeSim, make_client: MakeClient
) -> None:
    """Each capability is decided once on connecting, from the bridge's answers (not its name)."""
    options, expected = BRIDGES[bridge]
    client = await make_client(await make_sim(**options))
    caps = await client.capabilities()
    assert isinstance(caps, BridgeCapabilities)
    assert {name: getattr(caps, name) for name in expected} == expected
    session = client.session
    assert session is not None
    assert session.capabilities is caps
    assert (await client.dialect()).capabilities is caps


@pytest.mark.parametrize(("server", "refusal"), [("rs", "unknown active goal"), ("rosbridge_suite", None)])
async def test_a_cancel_of_another_clients_goal_by_its_id_tells_the_bridges_refusal(
    server: str, refusal: str | None, make_sim: MakeSim, make_client: MakeClient
) -> None:
    """rosbridge-server-rs refuses it (only the starting connection may cancel), rosbridge_suite says nothing;
    what the capabilities say of cancelling stays as the bridge showed it."""
    client = await make_client(await make_sim(dialect="ros2", server=server))
    heard = (await client.goals.cancel("/fibonacci", "goal:/fibonacci:someone-1", timeout=3.0)).refused
    if refusal is None:
        assert heard is None
    else:
        assert heard is not None
        assert refusal in heard
    assert (await client.capabilities()).cancel_by_owner_only is (server == "rs")
