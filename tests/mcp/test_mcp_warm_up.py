"""The service types are learnt in the background after each connect, so a model's first listing is cheap.

The harness waits for that warm-up before handing out a session (``mcp_harness.warmed_up``), as a model's
first call comes seconds after the server connected.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable

from mcp_harness import Session, open_session, service_rows, types_for, warmed_up

from rosbridge_mcp_server.robot.known_types import infrastructure_types
from rosbridge_mcp_server.robot.warm_up import ServiceTypeWarmUp
from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]
WAIT = 30.0


def calls_since(robot: SimulatedRobot, before: dict[str, int]) -> dict[str, int]:
    """The service calls the robot received since *before* (a copy of ``world.service_calls``)."""
    now = robot.world.service_calls
    return {name: n - before.get(name, 0) for name, n in now.items() if n != before.get(name, 0)}


async def listing(session: Session) -> dict[str, str]:
    """list_services as {name: type}."""
    data = (await session.ok("list_services")).structured_content
    assert data is not None
    return {row["name"]: row["type"] for row in service_rows(data)}


def own_services(types: dict[str, str], version: int) -> list[str]:
    """The listed services that only a look-up can type (not per-node, not rosapi's own)."""
    fixed = infrastructure_types(list(types), version)
    return [name for name in types if name not in fixed]


async def test_the_first_listing_asks_only_for_the_names(session: Session, sim: SimulatedRobot) -> None:
    """Every type is known before the model asks: the first list_services is one rosapi call, and typed."""
    before = dict(sim.world.service_calls)
    types = await listing(session)
    assert calls_since(sim, before) == {"/rosapi/services": 1}
    assert sim.world.refused_calls == {}, "no probe call either"
    assert all(types.values()), types


async def test_on_rosapi_2_1_the_warm_up_asks_rosapi_and_probes_nothing(make_sim: MakeSim) -> None:
    """rosapi's service_type for each of the robot's own services, once; no probe (a bridge logs those)."""
    robot = await make_sim(
        dialect="ros2", in_order=True, distro="jazzy", rosapi="2.1.0", rosapi_latency=0.002
    )
    async with open_session(robot.url) as session:
        learnt = robot.world.service_calls.get("/rosapi/service_type", 0)
        before = dict(robot.world.service_calls)
        types = await listing(session)
        assert calls_since(robot, before) == {"/rosapi/services": 1}
        assert learnt == len(own_services(types, 2)) > 0
        assert types["/add_two_ints"] == "example_interfaces/srv/AddTwoInts"
    assert robot.world.refused_calls == {}, "a probe call leaves an error line in a real bridge's log"


async def test_a_service_call_after_the_warm_up_skips_the_type_look_up(
    session: Session, sim: SimulatedRobot
) -> None:
    """publish_service finds the service's type known: rosapi's service_type is not asked."""
    add_type = types_for(sim)["add_two_ints"]
    before = dict(sim.world.service_calls)
    request = {"service": "/add_two_ints", "service_type": add_type, "request": {"a": 2, "b": 3}}
    await session.ok("publish_service", request)
    asked = calls_since(sim, before)
    assert asked["/add_two_ints"] == 1
    assert "/rosapi/service_type" not in asked


async def test_the_types_are_learnt_again_after_a_reconnect(make_sim: MakeSim) -> None:
    """A new connection may be to another robot: what the old one learnt is dropped, and learnt anew."""
    robot = await make_sim(dialect="ros2")
    async with open_session(robot.url) as session:
        learnt = robot.world.service_calls.get("/rosapi/service_type", 0)
        assert learnt == len(own_services(await listing(session), 2)) > 0
        await robot.drop_connections()
        await session.ros.wait_disconnected(WAIT)
        await session.ros.wait_connected(WAIT)
        await warmed_up(session.ros)
        assert robot.world.service_calls["/rosapi/service_type"] == 2 * learnt
        before = dict(robot.world.service_calls)
        await listing(session)
        assert calls_since(robot, before) == {"/rosapi/services": 1}


async def test_nothing_is_learnt_for_a_server_without_list_services(sim_ros2: SimulatedRobot) -> None:
    """--tools without list_services: no warm-up, no look-ups the host never wanted."""
    async with open_session(sim_ros2.url, tools=("list_topics", "publish_topic")) as session:
        assert not any(isinstance(w, ServiceTypeWarmUp) for w in session.ros.watchers)
        await session.ok("list_topics")
        assert "/rosapi/service_type" not in sim_ros2.world.service_calls
