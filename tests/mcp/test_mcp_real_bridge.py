"""The eight tools through a real MCP session against a real rosbridge (ROS 1 or ROS 2, detected).

Skipped unless ``ROSBRIDGE_TEST_URL`` names a bridge, e.g.::

    ROSBRIDGE_TEST_URL=ws://robot:9090 uv run pytest tests/mcp/test_mcp_real_bridge.py -q

Every assertion holds on any healthy robot with rosapi running. The goal tests also need an action server that
runs a goal for a second or more and sends feedback while it runs::

    ROSBRIDGE_TEST_ACTION=/fibonacci ROSBRIDGE_TEST_ACTION_TYPE=actionlib_tutorials/FibonacciAction \\
    ROSBRIDGE_TEST_ACTION_GOAL='{"order": 20}' ...

Without ``ROSBRIDGE_TEST_ACTION_GOAL`` the goal is ``{"order": 30}`` (as in the safety suite): an empty goal
(a Fibonacci of order 0) ends before its first feedback, and the goal tests would wait for it in vain.

The tests publish only on topics under ``/mcp_test/`` and call only rosapi's read-only services and a service
they offer themselves under ``/mcp_test/``.
"""

from __future__ import annotations

import asyncio
import base64
import io
import json
import os
import re
from collections.abc import AsyncIterator
from typing import Any

import pytest
import websockets
from mcp.types import CallToolResult
from mcp_harness import Session, open_session, parameter_names, service_rows, text_of, unreadable_services

from rosbridge_mcp_server.cli.check import run_check
from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.config import Config

REAL_URL = os.environ.get("ROSBRIDGE_TEST_URL")
ACTION = os.environ.get("ROSBRIDGE_TEST_ACTION")
ACTION_TYPE = os.environ.get("ROSBRIDGE_TEST_ACTION_TYPE")
ACTION_GOAL: dict[str, Any] = json.loads(os.environ.get("ROSBRIDGE_TEST_ACTION_GOAL") or '{"order": 30}')

pytestmark = [
    pytest.mark.real_bridge,
    pytest.mark.skipif(
        REAL_URL is None, reason="set ROSBRIDGE_TEST_URL=ws://host:port to run against a real bridge"
    ),
]

WAIT = 10.0
# A goal id as publish_action names it in its progress messages.
_GOAL_IN_PROGRESS = re.compile(r"^goal (\S+) feedback \d+:")


@pytest.fixture
async def real() -> AsyncIterator[Session]:
    """An MCP session on the real bridge."""
    assert REAL_URL is not None
    async with open_session(REAL_URL, request_timeout=WAIT) as opened:
        yield opened


def _needs_action() -> tuple[str, str]:
    if not ACTION or not ACTION_TYPE:
        pytest.skip("set ROSBRIDGE_TEST_ACTION and ROSBRIDGE_TEST_ACTION_TYPE to run the goal tests")
    return ACTION, ACTION_TYPE


async def _version(session: Session) -> int:
    return (await session.ros.ros_info()).version


async def _rosapi_node(session: Session) -> str:
    """The node that serves /rosapi/topics: /rosapi for rosbridge_suite, the bridge itself for
    rosbridge-server-rs (its rosapi is built in: /rosbridge_rs on the lab)."""
    nodes = (await session.ok("list_nodes")).structured_content
    assert nodes is not None
    ordered = sorted(nodes["nodes"], key=lambda node: (node != "/rosapi", "ros" not in node, node))
    for node in ordered:
        info = (await session.call("get_node_info", {"node": node})).structured_content or {}
        if "/rosapi/topics" in {s["name"] for s in info.get("services", [])}:
            return str(node)
    raise AssertionError(f"no node serves /rosapi/topics among {ordered}")


async def _node_with_parameters(session: Session) -> str:
    """A node with parameter services: rosapi's where it has them (not rosbridge-server-rs's bridge node)."""
    rosapi = await _rosapi_node(session)
    nodes = (await session.ok("list_nodes")).structured_content
    assert nodes is not None
    for node in [rosapi, *sorted(nodes["nodes"])]:
        info = (await session.call("get_node_info", {"node": node})).structured_content or {}
        if f"{node}/list_parameters" in {s["name"] for s in info.get("services", [])}:
            return node
    raise AssertionError("no node offers parameter services")


async def test_list_topics_finds_rosout_with_its_type(real: Session) -> None:
    """list_topics answers a non-empty, sorted list that includes /rosout with a type."""
    data = (await real.ok("list_topics")).structured_content
    assert data is not None
    names = [row["name"] for row in data["topics"]]
    assert names == sorted(names)
    assert "/rosout" in names
    assert data["count"] == len(names)
    rosout = next(row for row in data["topics"] if row["name"] == "/rosout")
    assert rosout["type"] in ("rosgraph_msgs/Log", "rcl_interfaces/msg/Log")


async def test_get_topic_info_of_a_listed_topic_matches_its_listed_type(real: Session) -> None:
    """get_topic_info of /rosout names the type list_topics gave and at least one publisher."""
    listed = (await real.ok("list_topics")).structured_content
    assert listed is not None
    rosout_type = next(row["type"] for row in listed["topics"] if row["name"] == "/rosout")
    data = (await real.ok("get_topic_info", {"topic": "/rosout"})).structured_content
    assert data is not None
    assert data["topic"] == "/rosout"
    assert data["type"] == rosout_type
    assert data["publishers"], "every ROS node publishes its log on /rosout"


async def test_get_topic_info_of_an_unknown_topic_is_an_error(real: Session) -> None:
    """A topic nobody publishes or subscribes to is an error that points at list_topics."""
    text = await real.error("get_topic_info", {"topic": "/mcp_test/nobody_uses_this"})
    assert "/mcp_test/nobody_uses_this" in text
    assert "list_topics" in text


async def test_a_published_string_reaches_a_subscriber(real: Session) -> None:
    """publish_topic on a fresh test topic delivers the message to our own client's subscription."""
    string_type = "std_msgs/String" if await _version(real) == 1 else "std_msgs/msg/String"
    topic = "/mcp_test/chatter"
    text = f"hello from the real-bridge test {os.getpid()}"
    async with real.ros.subscribe(topic, string_type) as sub:

        async def delivered() -> dict[str, Any]:
            # A new publisher's first messages can go out before the bridge's own subscriber is connected
            # (ROS 1 TCPROS, ROS 2 discovery), so publish until one arrives.
            while True:
                await real.ok(
                    "publish_topic", {"topic": topic, "message_type": string_type, "message": {"data": text}}
                )
                try:
                    return await sub.get(timeout=0.5)
                except TimeoutError:
                    continue

        message = await asyncio.wait_for(delivered(), WAIT)
    assert message == {"data": text}


async def test_a_twist_passes_the_check_and_reaches_a_subscriber(real: Session) -> None:
    """A geometry Twist as a model writes it is checked against rosapi's TypeDefs and delivered as sent."""
    twist = "geometry_msgs/Twist" if await _version(real) == 1 else "geometry_msgs/msg/Twist"
    topic = "/mcp_test/cmd_vel"
    sent = {"linear": {"x": 0.25}, "angular": {"z": 0.5}}
    async with real.ros.subscribe(topic, twist) as sub:

        async def delivered() -> dict[str, Any]:
            while True:
                await real.ok("publish_topic", {"topic": topic, "message_type": twist, "message": sent})
                try:
                    return await sub.get(timeout=0.5)
                except TimeoutError:
                    continue

        message = await asyncio.wait_for(delivered(), WAIT)
    assert message["linear"] == {"x": 0.25, "y": 0.0, "z": 0.0}
    assert message["angular"] == {"x": 0.0, "y": 0.0, "z": 0.5}


async def test_a_message_that_does_not_fit_its_type_is_refused(real: Session) -> None:
    """A string in a float field is refused before anything is published, naming the field."""
    twist = "geometry_msgs/Twist" if await _version(real) == 1 else "geometry_msgs/msg/Twist"
    text = await real.error(
        "publish_topic",
        {"topic": "/mcp_test/cmd_vel", "message_type": twist, "message": {"linear": {"x": "fast"}}},
    )
    assert "linear.x" in text
    assert "Nothing was published" in text


async def test_list_services_includes_rosapi_topics_with_its_type(real: Session) -> None:
    """list_services lists /rosapi/topics, typed, each service once; its text names every service and type."""
    result = await real.ok("list_services")
    data = result.structured_content
    assert data is not None
    assert unreadable_services(result) == []
    names = [row["name"] for row in service_rows(data)]
    assert len(names) == len(set(names))
    assert "/rosapi/topics" in names
    topics_type = next(row["type"] for row in service_rows(data) if row["name"] == "/rosapi/topics")
    assert topics_type in ("rosapi/Topics", "rosapi_msgs/srv/Topics")


async def test_publish_service_calls_rosapi_topics_and_returns_the_response(real: Session) -> None:
    """Calling /rosapi/topics with its listed type answers the topics, /rosout among them."""
    services = (await real.ok("list_services")).structured_content
    assert services is not None
    srv_type = next(row["type"] for row in service_rows(services) if row["name"] == "/rosapi/topics")
    data = (
        await real.ok(
            "publish_service", {"service": "/rosapi/topics", "service_type": srv_type, "request": {}}
        )
    ).structured_content
    assert data is not None
    assert data["service"] == "/rosapi/topics"
    assert "/rosout" in data["response"]["topics"]


async def test_publish_service_refuses_a_request_field_the_type_lacks(real: Session) -> None:
    """A request field /rosapi/topics does not have is refused before the call, naming the field."""
    services = (await real.ok("list_services")).structured_content
    assert services is not None
    srv_type = next(row["type"] for row in service_rows(services) if row["name"] == "/rosapi/topics")
    text = await real.error(
        "publish_service",
        {"service": "/rosapi/topics", "service_type": srv_type, "request": {"no_such_field": 1}},
    )
    assert "no_such_field" in text
    assert "not called" in text


async def test_a_missing_service_fails_naming_it(real: Session) -> None:
    """Calling a service nobody offers fails at once, naming the service and pointing at list_services."""
    std_empty = "std_srvs/Empty" if await _version(real) == 1 else "std_srvs/srv/Empty"
    text = await real.error(
        "publish_service", {"service": "/mcp_test/no_such_service", "service_type": std_empty, "request": {}}
    )
    assert "/mcp_test/no_such_service" in text
    assert "not offered" in text
    assert "list_services" in text


async def test_list_actions_names_each_action_once(real: Session) -> None:
    """list_actions answers each action server once, sorted (rosapi repeats some on ROS 1)."""
    data = (await real.ok("list_actions")).structured_content
    assert data is not None
    names = [row["name"] for row in data["actions"]]
    assert names == sorted(set(names))
    assert data["count"] == len(names)
    if ACTION:
        assert ACTION in names


async def test_list_actions_types_the_test_action(real: Session) -> None:
    """The test action is listed with its type, whether or not rosapi has action_type."""
    action, action_type = _needs_action()
    data = (await real.ok("list_actions")).structured_content
    assert data is not None
    row = next(row for row in data["actions"] if row["name"] == action)
    expected = Dialect.action_names(action_type).for_version(await _version(real))
    assert row["type"] == expected


async def test_a_slow_service_call_does_not_hold_up_other_tools(real: Session) -> None:
    """While one publish_service waits on a slow service, list_topics still answers at once."""
    assert REAL_URL is not None
    version = await _version(real)
    name = f"/mcp_test/slow_{os.getpid()}"
    trigger = "std_srvs/Trigger" if version == 1 else "std_srvs/srv/Trigger"
    async with websockets.connect(REAL_URL, compression=None) as host:
        await host.send(json.dumps({"op": "advertise_service", "service": name, "type": trigger}))
        try:
            await _until_listed(real, name)
            call = asyncio.create_task(
                real.call("publish_service", {"service": name, "service_type": trigger, "request": {}})
            )
            request = await asyncio.wait_for(_next_call(host, name), WAIT)
            # The service has the call and holds it: another tool must not wait behind it.
            listed = await asyncio.wait_for(real.ok("list_topics"), 2.0)
            assert listed.structured_content is not None
            assert not call.done()
            answer = {"success": True, "message": "held"}
            reply = {"op": "service_response", "id": request["id"], "service": name, "result": True}
            await host.send(json.dumps({**reply, "values": answer}))
            result = await asyncio.wait_for(call, WAIT)
            assert not result.is_error, text_of(result)
            assert result.structured_content is not None
            assert result.structured_content["response"] == answer
        finally:
            await host.send(json.dumps({"op": "unadvertise_service", "service": name}))


async def _until_listed(session: Session, service: str) -> None:
    """Until rosapi lists a service just advertised (the bridge registers it with the graph first)."""
    async with asyncio.timeout(WAIT):
        while True:
            values = await session.ros.call_service("/rosapi/service_type", {"service": service})
            if isinstance(values, dict) and values.get("type"):
                return
            await asyncio.sleep(0.05)


async def _next_call(host: Any, service: str) -> dict[str, Any]:
    while True:
        frame = json.loads(await host.recv())
        if frame.get("op") == "call_service" and frame.get("service") == service:
            return dict(frame)


def _start_goal(
    session: Session, action: str, action_type: str
) -> tuple[asyncio.Task[CallToolResult], asyncio.Future[str]]:
    """publish_action running in a task, and the goal id its first feedback progress message names."""
    first: asyncio.Future[str] = asyncio.get_running_loop().create_future()

    async def on_progress(progress: float, total: float | None, message: str | None) -> None:
        match = _GOAL_IN_PROGRESS.match(message or "")
        if match and not first.done():
            first.set_result(match.group(1))

    arguments = {"action_name": action, "action_type": action_type, "goal": ACTION_GOAL, "timeout": 60}
    running = asyncio.create_task(
        session.mcp.call_tool("publish_action", arguments, progress_callback=on_progress)
    )
    return running, first


async def test_a_goal_runs_with_feedback_and_is_cancelled_by_its_id(real: Session) -> None:
    """A running goal reports feedback as progress; cancel_action by its id ends it as cancelled by it."""
    action, action_type = _needs_action()
    running, first_feedback = _start_goal(real, action, action_type)
    try:
        goal_id = await asyncio.wait_for(first_feedback, WAIT)
        cancel = (
            await real.ok("cancel_action", {"action_name": action, "goal_id": goal_id})
        ).structured_content
        assert cancel is not None
        assert cancel["unknown_goal_id"] is False
        result = await asyncio.wait_for(running, WAIT)
    finally:
        running.cancel()
    assert not result.is_error, text_of(result)
    data = result.structured_content
    assert data is not None
    assert data["goal_id"] == goal_id
    assert data["succeeded"] is False
    assert data["status"] in ("canceled", "preempted", "recalled")
    assert data["canceled_by"] == "cancel_action"
    assert data["feedback_count"] >= 1


async def test_cancel_all_reaches_a_running_goal(real: Session) -> None:
    """cancel_action without an id names publish_action's running goal and ends it."""
    action, action_type = _needs_action()
    running, first_feedback = _start_goal(real, action, action_type)
    try:
        goal_id = await asyncio.wait_for(first_feedback, WAIT)
        cancel = (await real.ok("cancel_action", {"action_name": action})).structured_content
        assert cancel is not None
        assert goal_id in cancel["canceled_goals"]
        result = await asyncio.wait_for(running, WAIT)
    finally:
        running.cancel()
    data = result.structured_content
    assert data is not None, text_of(result)
    assert data["succeeded"] is False
    assert data["canceled_by"] == "cancel_action"


async def test_a_goal_past_its_timeout_is_cancelled_on_the_robot(real: Session) -> None:
    """A goal that outlives publish_action's timeout is cancelled, and the answer says so."""
    action, action_type = _needs_action()
    result = await real.call(
        "publish_action",
        {"action_name": action, "action_type": action_type, "goal": ACTION_GOAL, "timeout": 0.5},
    )
    text = text_of(result)
    assert "cancel" in text
    if not result.is_error:
        data = result.structured_content
        assert data is not None
        assert data["succeeded"] is False
        assert data["canceled_by"] == "timeout"


class _StatusWatch:
    """A side channel: another WebSocket following the action's status topic (ROS 2 ``_action/status``,
    ROS 1 actionlib's ``status``), each goal's last status by its id (ROS 2: the UUID in hex)."""

    def __init__(self, ws: Any, version: int) -> None:
        self.ws = ws
        self.version = version
        self.latest: dict[str, int] = {}

    @classmethod
    async def open(cls, action: str, version: int) -> _StatusWatch:
        assert REAL_URL is not None
        ws = await websockets.connect(REAL_URL, compression=None, max_size=None)
        if version == 2:
            topic, msg_type = f"{action}/_action/status", "action_msgs/msg/GoalStatusArray"
        else:
            topic, msg_type = f"{action}/status", "actionlib_msgs/GoalStatusArray"
        await ws.send(json.dumps({"op": "subscribe", "id": "side", "topic": topic, "type": msg_type}))
        return cls(ws, version)

    def _key(self, entry: dict[str, Any]) -> str:
        if self.version == 1:
            return str(entry["goal_id"]["id"])
        uuid = entry["goal_info"]["goal_id"]["uuid"]
        return base64.b64decode(uuid).hex() if isinstance(uuid, str) else bytes(uuid).hex()

    async def until(self, wanted: Any) -> None:
        """Read status messages until ``wanted(latest)`` holds (bounded by WAIT)."""
        async with asyncio.timeout(WAIT):
            while not wanted(self.latest):
                frame = json.loads(await self.ws.recv())
                if frame.get("op") == "publish":
                    for entry in frame["msg"]["status_list"]:
                        self.latest[self._key(entry)] = int(entry["status"])

    def active(self) -> set[str]:
        return {key for key, code in self.latest.items() if code in ((1, 2) if self.version == 2 else (1,))}

    def canceled(self, key: str) -> bool:
        return self.latest.get(key) in ((5,) if self.version == 2 else (2, 8))


async def test_a_goal_publish_action_started_is_seen_cancelled_on_the_status_topic(real: Session) -> None:
    """cancel_action by the goal's id stops it on the robot: the action server's own status topic, read on
    another connection, shows the goal cancelled (every bridge: rosbridge-server-rs cancels only on the
    connection that started the goal)."""
    action, action_type = _needs_action()
    watch = await _StatusWatch.open(action, await _version(real))
    try:
        await watch.until(lambda latest: True)
        before = set(watch.latest)
        running, first_feedback = _start_goal(real, action, action_type)
        try:
            goal_id = await asyncio.wait_for(first_feedback, WAIT)
            await watch.until(lambda latest: bool(watch.active() - before))
            (ours,) = watch.active() - before
            await real.ok("cancel_action", {"action_name": action, "goal_id": goal_id})
            await watch.until(lambda latest: watch.canceled(ours))
            result = await asyncio.wait_for(running, WAIT)
        finally:
            running.cancel()
    finally:
        await watch.ws.close()
    data = result.structured_content
    assert data is not None, text_of(result)
    assert data["canceled_by"] == "cancel_action"


async def test_a_goal_another_client_started_is_cancelled_by_its_id_or_the_answer_says_why(
    real: Session,
) -> None:
    """ROS 2: a goal a plain WebSocket client started is cancelled by its rosbridge id (rosbridge_suite), or
    the answer says the bridge refused and names the goal's UUID as the way, which then cancels it."""
    action, action_type = _needs_action()
    if await _version(real) == 1:
        pytest.skip("ROS 1 cancels any actionlib goal by its GoalID on <action>/cancel; no action ops")
    watch = await _StatusWatch.open(action, 2)
    assert REAL_URL is not None
    other = await websockets.connect(REAL_URL, compression=None, max_size=None)
    try:
        await watch.until(lambda latest: True)
        before = set(watch.latest)
        rid = f"mcp_test_foreign:{os.getpid()}:{id(other)}"
        wire_type = Dialect.action_names(action_type).ros2
        await other.send(
            json.dumps(
                {
                    "op": "send_action_goal",
                    "id": rid,
                    "action": action,
                    "action_type": wire_type,
                    "args": ACTION_GOAL,
                    "feedback": True,
                }
            )
        )
        await watch.until(lambda latest: bool(watch.active() - before))
        (theirs,) = watch.active() - before
        result = await real.call("cancel_action", {"action_name": action, "goal_id": rid})
        if result.is_error:
            text = text_of(result)
            assert "was not cancelled: the bridge refused" in text, text
            assert "Give the goal's UUID instead" in text
            await real.ok("cancel_action", {"action_name": action, "goal_id": theirs})
        await watch.until(lambda latest: watch.canceled(theirs))
    finally:
        await other.close()
        await watch.ws.close()


async def test_check_finds_the_bridge_healthy() -> None:
    """`check` against the bridge reports it reachable with rosapi answering, and exits 0."""
    assert REAL_URL is not None
    out = io.StringIO()
    code = await run_check(Config(url=REAL_URL), out)
    assert code == 0, out.getvalue()
    assert "rosapi answers" in out.getvalue()


# --- the watch tools --------------------------------------------------------------------------------------


async def _latched(real: Session, topic: str, short_type: str, message: dict[str, Any]) -> str:
    """Publish one latched (ROS 2: transient-local) message on a test topic; returns the type used."""
    package, name = short_type.split("/")
    msg_type = short_type if await _version(real) == 1 else f"{package}/msg/{name}"
    await real.ros.publish(topic, msg_type, message, latch=True)

    async def listed() -> None:
        # The bridge registers the publisher with the graph on its own time (ROS 1 master, ROS 2 discovery).
        while not (await real.ros.call_service("/rosapi/topic_type", {"topic": topic})).get("type"):
            continue

    await asyncio.wait_for(listed(), WAIT)
    return msg_type


async def test_subscribe_topic_reads_a_latched_test_message(real: Session) -> None:
    """subscribe_topic answers at once with the last message of a latched test topic, then unsubscribes."""
    # A topic of this run's own: re-latching one another client latched makes the bridge log a warning, which
    # Kilted's 2.1.0 can fail on (docs/rosbridge-behaviour.md, "A Kilted logging fault").
    topic = f"/mcp_test/latched_{os.getpid()}"
    await _latched(real, topic, "std_msgs/String", {"data": "kept for late subscribers"})
    result = await real.ok("subscribe_topic", {"topic": topic, "timeout": WAIT})
    data = result.structured_content
    assert data is not None
    assert data["messages"][0]["message"] == {"data": "kept for late subscribers"}


async def test_get_image_turns_a_test_frame_into_an_image(real: Session) -> None:
    """A latched 64×48 rgb8 test frame comes back as an MCP image with its size and encoding."""
    image_type = "sensor_msgs/Image" if await _version(real) == 1 else "sensor_msgs/msg/Image"
    if (await real.call("describe_type", {"type_name": image_type})).is_error:
        pytest.skip("sensor_msgs is not installed on this robot (the ROS 1 lab has none)")
    frame = {
        "header": {"frame_id": "mcp_test"},
        "height": 48,
        "width": 64,
        "encoding": "rgb8",
        "is_bigendian": 0,
        "step": 64 * 3,
        "data": list(bytes([200, 40, 10]) * (64 * 48)),
    }
    topic = f"/mcp_test/image_{os.getpid()}"  # this run's own, as above
    await _latched(real, topic, "sensor_msgs/Image", frame)
    result = await real.ok("get_image", {"topic": topic, "format": "png", "timeout": WAIT})
    data = result.structured_content
    assert data is not None
    assert (data["width"], data["height"], data["encoding"]) == (64, 48, "rgb8")
    assert [block.type for block in result.content] == ["text", "image"]


async def test_describe_type_outlines_twist_and_a_rosapi_service(real: Session) -> None:
    """Twist is outlined with plain field names; rosapi's topics service shows its request and response."""
    twist = "geometry_msgs/Twist" if await _version(real) == 1 else "geometry_msgs/msg/Twist"
    described = (await real.ok("describe_type", {"type_name": twist})).structured_content
    assert described is not None
    assert described["parts"][0]["outline"][:2] == ["linear: geometry_msgs/Vector3", "  x: float64"]
    assert described["parts"][0]["constants"] == {}
    service_type = (await real.ok("get_node_info", {"node": await _rosapi_node(real)})).structured_content
    assert service_type is not None
    topics_type = next(s["type"] for s in service_type["services"] if s["name"] == "/rosapi/topics")
    service = (await real.ok("describe_type", {"type_name": topics_type})).structured_content
    assert service is not None
    assert service["kind"] == "service"
    assert "topics: string[]" in service["parts"][1]["outline"]


async def test_list_nodes_and_node_info_show_rosapi(real: Session) -> None:
    """The node serving /rosapi/topics is running (/rosapi, or the bridge whose rosapi is built in)."""
    rosapi = await _rosapi_node(real)
    nodes = (await real.ok("list_nodes")).structured_content
    assert nodes is not None
    assert rosapi in nodes["nodes"]
    info = (await real.ok("get_node_info", {"node": rosapi})).structured_content
    assert info is not None
    assert "/rosapi/topics" in {s["name"] for s in info["services"]}
    assert f"Did you mean {rosapi}?" in await real.error("get_node_info", {"node": rosapi + "i"})


async def test_parameters_of_rosapi_are_listed_and_read(real: Session) -> None:
    """ROS 2: a node's own parameters, rosapi's where it has them (never get_param_names: it kills rosapi
    2.1.0); ROS 1: the server's."""
    if await _version(real) == 1:
        names = (await real.ok("list_parameters")).structured_content
        assert names is not None
        assert parameter_names(names)
        first = parameter_names(names)[0]
        value = (await real.ok("get_parameter", {"name": first})).structured_content
        assert value is not None
        assert value["name"] == first
        written = await real.ok("set_parameter", {"name": "/mcp_test/param", "value": [1, 2.5, "x"]})
        assert (written.structured_content or {})["value"] == [1, 2.5, "x"]
        return
    node = await _node_with_parameters(real)
    names = (await real.ok("list_parameters", {"node": node})).structured_content
    assert names is not None
    assert f"{node}:use_sim_time" in parameter_names(names)
    value = (await real.ok("get_parameter", {"name": f"{node}:use_sim_time"})).structured_content
    assert value is not None
    assert value["value"] is False
    assert "has no parameter" in await real.error("get_parameter", {"name": f"{node}:no_such_parameter"})


async def test_get_transform_explains_what_it_heard(real: Session) -> None:
    """Without transforms on the robot it says nothing publishes them; with them, it lists the frames seen."""
    text = await real.error(
        "get_transform", {"target_frame": "mcp_test_a", "source_frame": "mcp_test_b", "timeout": 1}
    )
    assert "nothing publishes transforms" in text or "Frames seen" in text or "No transforms" in text


async def test_a_publish_stream_arrives_at_its_rate(real: Session) -> None:
    """publish_topic at 20 Hz for 0.5 s on a test topic: a subscriber gets the messages of the stream."""
    string_type = "std_msgs/String" if await _version(real) == 1 else "std_msgs/msg/String"
    topic = "/mcp_test/stream"
    async with real.ros.subscribe(topic, string_type) as sub:
        # The first publish registers the topic; a stream after it is heard from its first message.
        await real.ok(
            "publish_topic", {"topic": topic, "message_type": string_type, "message": {"data": "0"}}
        )
        result = await real.ok(
            "publish_topic",
            {
                "topic": topic,
                "message_type": string_type,
                "message": {"data": "s"},
                "rate_hz": 20,
                "duration": 0.5,
            },
        )
        assert (result.structured_content or {})["count"] == 10
        heard = 0
        while heard < 8:
            message = await sub.get(timeout=WAIT)
            heard += message == {"data": "s"}
    assert heard >= 8
