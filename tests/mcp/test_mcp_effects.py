"""An effect is judged by what it does, under its canonical name, and only the console's person approves.

Each test attacks as a user of an MCP client would (issue 25, findings 2, 3 and 8) and watches the robot
from a raw rosbridge socket of its own: the goal topic, the action's status, the parameter's value read back
from the robot, the turtle's pose.
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import itertools
import json
from collections.abc import AsyncIterator
from typing import Any

import pytest
from mcp.client.context import ClientRequestContext
from mcp.types import ElicitRequestParams, ElicitResult
from mcp_harness import Session, open_session, text_of, types_for
from websockets.asyncio.client import ClientConnection, connect

from rosbridge_mcp_server.safety import Audit, Operator, Policy, PolicyGuard, parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 30.0
_ids = itertools.count(1)


def policy(**sections: Any) -> Policy:
    return parse_policy(sections, where="test-policy.toml")


class Person:
    """The person at the MCP client (or the requester's own client): answers every question so."""

    def __init__(self, action: str = "accept") -> None:
        self.action = action
        self.questions: list[str] = []

    async def __call__(self, context: ClientRequestContext, params: ElicitRequestParams) -> ElicitResult:
        self.questions.append(params.message)
        if self.action == "accept":
            return ElicitResult(action="accept", content={"approve": True})
        return ElicitResult(action=self.action)  # type: ignore[arg-type]


class Watcher:
    """A raw rosbridge socket of the test's own: subscribes to topics, reads what the robot holds."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        self.seen: dict[str, list[Any]] = {}
        self.changed = asyncio.Event()
        self.replies: dict[str, asyncio.Future[dict[str, Any]]] = {}

    async def read(self) -> None:
        async for raw in self.ws:
            frame = json.loads(raw)
            if frame.get("op") == "publish":
                self.seen.setdefault(frame["topic"], []).append(frame["msg"])
                self.changed.set()
            elif frame.get("op") == "service_response" and frame.get("id") in self.replies:
                self.replies.pop(frame["id"]).set_result(frame)

    async def subscribe(self, topic: str, type_name: str) -> None:
        await self.ws.send(json.dumps({"op": "subscribe", "topic": topic, "type": type_name}))

    async def call(self, service: str, args: dict[str, Any]) -> Any:
        request_id = f"watch:{next(_ids)}"
        reply: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self.replies[request_id] = reply
        await self.ws.send(
            json.dumps({"op": "call_service", "id": request_id, "service": service, "args": args})
        )
        frame = await asyncio.wait_for(reply, WAIT)
        assert frame.get("result") is True, frame
        return frame["values"]

    async def wait_for(self, topic: str, predicate: Any) -> Any:
        """The first message on ``topic`` (seen so far or to come) that ``predicate`` holds for."""
        async with asyncio.timeout(WAIT):
            while True:
                for message in self.seen.get(topic, []):
                    if predicate(message):
                        return message
                self.changed.clear()
                await self.changed.wait()

    async def parameter(self, sim: SimulatedRobot, name: str) -> Any:
        """The parameter's value as the robot holds it (ROS 2: the node's own get_parameters)."""
        if sim.dialect == "ros2":
            node, _, local = name.partition(":")
            values = await self.call(f"{node}/get_parameters", {"names": [local]})
            value = values["values"][0]
            return value.get("integer_value") if value.get("type") == 2 else value
        return json.loads((await self.call("/rosapi/get_param", {"name": name}))["value"])


@contextlib.asynccontextmanager
async def watching(sim: SimulatedRobot) -> AsyncIterator[Watcher]:
    async with connect(sim.url) as ws:
        watcher = Watcher(ws)
        reader = asyncio.create_task(watcher.read())
        try:
            yield watcher
        finally:
            reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reader


def chatter(sim: SimulatedRobot, text: str) -> dict[str, Any]:
    """A publish that the policies here allow, sent after the call under test: a barrier on one connection."""
    return {"topic": "/chatter", "message_type": types_for(sim)["string"], "message": {"data": text}}


async def barrier(session: Session, watcher: Watcher, sim: SimulatedRobot) -> None:
    """Whatever the server sent before this returns has reached the watcher: the server's frames arrive in
    order, and the marker it publishes now comes after them."""
    marker = f"barrier {next(_ids)}"
    await session.ok("publish_topic", chatter(sim, marker))
    await watcher.wait_for("/chatter", lambda m: m.get("data") == marker)


def audited(stream: io.StringIO) -> list[dict[str, Any]]:
    return [json.loads(line) for line in stream.getvalue().splitlines()]


# --- 2: an action goal reached through its topic (ROS 1) or its service (ROS 2) --------------------------


ROS1_GOAL_TYPE = "actionlib_tutorials/FibonacciActionGoal"


def ros1_goal_call(order: int = 3) -> dict[str, Any]:
    goal = {"header": {}, "goal_id": {"id": f"attack-{order}"}, "goal": {"order": order}}
    return {"topic": "/fibonacci/goal", "message_type": ROS1_GOAL_TYPE, "message": goal}


def ros2_goal_call(order: int = 3) -> dict[str, Any]:
    goal = {"goal_id": {"uuid": list(range(16))}, "goal": {"order": order}}
    return {
        "service": "/fibonacci/_action/send_goal",
        "service_type": "example_interfaces/action/Fibonacci_SendGoal",
        "request": goal,
    }


async def test_ros1_a_goal_published_on_the_goal_topic_meets_the_actions_deny(
    sim_ros1: SimulatedRobot,
) -> None:
    """[actions] deny /fibonacci refuses publish_topic /fibonacci/goal too; nothing reaches the goal topic."""
    sim = sim_ros1
    stream = io.StringIO()
    rules = policy(actions={"deny": ["/fibonacci"]})
    async with (
        watching(sim) as watcher,
        open_session(sim.url, guard=PolicyGuard(rules, Audit(stream)), policy=rules) as session,
    ):
        await watcher.subscribe("/fibonacci/goal", ROS1_GOAL_TYPE)
        await watcher.subscribe("/chatter", "std_msgs/String")
        await barrier(session, watcher, sim)
        text = await session.error("publish_topic", ros1_goal_call())
        # the same spelled oddly
        odd = dict(ros1_goal_call(), topic="//fibonacci//goal/")
        odd_text = await session.error("publish_topic", odd)
        await barrier(session, watcher, sim)
    assert "[actions] deny '/fibonacci' matches /fibonacci" in text
    assert "a goal of action /fibonacci" in text
    assert "nothing was sent" in text
    assert "[actions] deny '/fibonacci'" in odd_text
    assert "/fibonacci/goal" not in watcher.seen
    assert sim.world.goals == {}
    refused = [e for e in audited(stream) if e["outcome"] == "refused"]
    assert [(e["name"], e.get("given"), e["effects"]) for e in refused] == [
        ("/fibonacci/goal", None, [{"kind": "action", "name": "/fibonacci", "what": "goal"}]),
        ("/fibonacci/goal", "//fibonacci//goal/", [{"kind": "action", "name": "/fibonacci", "what": "goal"}]),
    ]


async def test_ros2_a_goal_sent_through_the_send_goal_service_meets_the_actions_deny(
    sim_ros2: SimulatedRobot,
) -> None:
    """[actions] deny /fibonacci refuses publish_service /fibonacci/_action/send_goal; no goal appears."""
    sim = sim_ros2
    stream = io.StringIO()
    rules = policy(actions={"deny": ["/fibonacci"]})
    async with (
        watching(sim) as watcher,
        open_session(sim.url, guard=PolicyGuard(rules, Audit(stream)), policy=rules) as session,
    ):
        await watcher.subscribe("/fibonacci/_action/status", "action_msgs/msg/GoalStatusArray")
        text = await session.error("publish_service", ros2_goal_call())
        result_text = await session.error(
            "publish_service",
            {
                "service": "/fibonacci//_action/get_result",
                "service_type": "example_interfaces/action/Fibonacci_GetResult",
                "request": {"goal_id": {"uuid": list(range(16))}},
            },
        )
    assert "[actions] deny '/fibonacci' matches /fibonacci" in text
    assert "a goal of action /fibonacci" in text
    assert "a result of action /fibonacci" in result_text
    assert sim.world.service_calls.get("/fibonacci/_action/send_goal", 0) == 0
    assert sim.world.goals == {}
    assert "/fibonacci/_action/status" not in watcher.seen
    [first, second] = [e for e in audited(stream) if e["outcome"] == "refused"]
    assert first["effects"] == [{"kind": "action", "name": "/fibonacci", "what": "goal"}]
    assert second["given"] == "/fibonacci//_action/get_result"


async def test_a_goal_through_a_topic_or_service_is_motion_the_person_confirms(sim: SimulatedRobot) -> None:
    """confirm = "motion": the goal through its topic (ROS 1) or service (ROS 2) is asked about; a no keeps it
    from the robot; a yes lets it through."""
    declining = Person("decline")
    call = (
        ("publish_topic", ros1_goal_call())
        if sim.dialect == "ros1"
        else ("publish_service", ros2_goal_call())
    )
    async with (
        watching(sim) as watcher,
        open_session(
            sim.url, guard=None, policy=policy(confirm="motion"), elicitation_callback=declining
        ) as session,
    ):
        if sim.dialect == "ros1":
            await watcher.subscribe("/fibonacci/goal", ROS1_GOAL_TYPE)
            await watcher.subscribe("/chatter", "std_msgs/String")
        else:
            await watcher.subscribe("/chatter", "std_msgs/msg/String")
        text = await session.error(*call)
        declining.action = "accept"
        accepted = await session.call(*call)
        await barrier(session, watcher, sim)
    assert "The person declined" in text
    # /chatter is not motion; the goal was asked about twice (declined, then accepted).
    assert len(declining.questions) == 2
    assert all("a goal of action /fibonacci" in question for question in declining.questions)
    if sim.dialect == "ros1":
        assert not accepted.is_error, text_of(accepted)
        assert [m["goal_id"]["id"] for m in watcher.seen["/fibonacci/goal"]] == ["attack-3"]
    else:
        # Past the person, the bridge itself refuses the hidden service's type (as rosbridge 2.x does).
        assert "Fibonacci_SendGoal" in text_of(accepted)
        assert sim.world.goals == {}


# --- 2: parameters written through services --------------------------------------------------------------


def parameter_service_call(sim: SimulatedRobot, value: int, service: str | None = None) -> dict[str, Any]:
    """A write of /turtlesim's background_r through a service instead of set_parameter."""
    if sim.dialect == "ros2":
        return {
            "service": service or "/turtlesim/set_parameters",
            "service_type": "rcl_interfaces/srv/SetParameters",
            "request": {
                "parameters": [{"name": "background_r", "value": {"type": 2, "integer_value": value}}]
            },
        }
    return {
        "service": "/rosapi/set_param",
        "service_type": "rosapi/SetParam",
        "request": {"name": "turtlesim//background_r/", "value": json.dumps(value)},
    }


def turtlesim_r(sim: SimulatedRobot) -> str:
    return "/turtlesim:background_r" if sim.dialect == "ros2" else "/turtlesim/background_r"


async def test_a_parameter_written_through_a_service_meets_the_parameters_deny(sim: SimulatedRobot) -> None:
    """[parameters] deny refuses <node>/set_parameters (ROS 2) and /rosapi/set_param (ROS 1) that write the
    parameter; its value on the robot stays."""
    rules = policy(
        parameters={"deny": ["/turtlesim:*" if sim.dialect == "ros2" else "/turtlesim/background_r"]}
    )
    async with (
        watching(sim) as watcher,
        open_session(sim.url, guard=None, policy=rules) as session,
    ):
        before = await watcher.parameter(sim, turtlesim_r(sim))
        texts = [await session.error("publish_service", parameter_service_call(sim, 7))]
        if sim.dialect == "ros2":
            atomically = parameter_service_call(sim, 8, "/turtlesim/set_parameters_atomically")
            atomically["service_type"] = "rcl_interfaces/srv/SetParametersAtomically"
            texts.append(await session.error("publish_service", atomically))
        else:
            deleting = {"name": "/turtlesim/background_r"}
            texts.append(
                await session.error(
                    "publish_service",
                    {
                        "service": "/rosapi/delete_param",
                        "service_type": "rosapi/DeleteParam",
                        "request": deleting,
                    },
                )
            )
        after = await watcher.parameter(sim, turtlesim_r(sim))
    assert before == after == 69
    for text in texts:
        assert "[parameters] deny" in text, text
        assert f"parameter {turtlesim_r(sim)}" in text, text
        assert "nothing was sent" in text


async def test_ros1_a_namespace_write_over_a_denied_parameter_is_refused(sim_ros1: SimulatedRobot) -> None:
    """ROS 1 set_parameter /turtlesim {...} would replace the denied /turtlesim/background_r: refused."""
    sim = sim_ros1
    rules = policy(parameters={"deny": ["/turtlesim/background_r"]})
    async with watching(sim) as watcher, open_session(sim.url, guard=None, policy=rules) as session:
        text = await session.error("set_parameter", {"name": "/turtlesim", "value": {"background_r": 1}})
        allowed = await session.ok("set_parameter", {"name": "/turtlesim/background_g", "value": 7})
        after = await watcher.parameter(sim, "/turtlesim/background_r")
    assert "matches names under /turtlesim" in text
    assert not allowed.is_error
    assert after == 69


# --- 3: one canonical name before any rule ----------------------------------------------------------------


@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_odd_spellings_of_a_denied_parameter_are_refused_and_audited_canonically(
    dialect: str, make_sim: Any
) -> None:
    """The findings' spellings reach the same parameter, so the same rule refuses them; the audit names the
    canonical parameter and what the caller wrote; the robot's value stays."""
    sim: SimulatedRobot = await make_sim(dialect=dialect)
    if dialect == "ros2":
        deny, spellings = (
            "/turtlesim:*",
            ["/turtlesim/:background_r", "/turtlesim//:background_r", "turtlesim:background_r"],
        )
    else:
        deny = "/turtlesim/background_r"
        spellings = ["/turtlesim/background_r/", "//turtlesim/background_r", "/turtlesim//background_r"]
    stream = io.StringIO()
    rules = policy(parameters={"deny": [deny]})
    async with (
        watching(sim) as watcher,
        open_session(sim.url, guard=PolicyGuard(rules, Audit(stream)), policy=rules) as session,
    ):
        texts = [await session.error("set_parameter", {"name": name, "value": 1}) for name in spellings]
        after = await watcher.parameter(sim, turtlesim_r(sim))
    assert after == 69
    assert all(f"[parameters] deny {deny!r} matches {turtlesim_r(sim)}" in text for text in texts), texts
    refused = [e for e in audited(stream) if e["outcome"] == "refused"]
    assert [(e["name"], e["given"]) for e in refused] == [(turtlesim_r(sim), name) for name in spellings]


# --- 8: motion by service; approvals only at the console ----------------------------------------------------


def teleport_call(sim: SimulatedRobot) -> dict[str, Any]:
    kind = "turtlesim/srv/TeleportAbsolute" if sim.dialect == "ros2" else "turtlesim/TeleportAbsolute"
    return {
        "service": "/turtle1/teleport_absolute",
        "service_type": kind,
        "request": {"x": 1.0, "y": 1.0, "theta": 0.0},
    }


async def pose(watcher: Watcher, sim: SimulatedRobot) -> dict[str, Any]:
    """The turtle's next pose as the robot publishes it."""
    count = len(watcher.seen.get("/turtle1/pose", []))
    await watcher.wait_for("/turtle1/pose", lambda m: len(watcher.seen["/turtle1/pose"]) > count)
    return dict(watcher.seen["/turtle1/pose"][-1])


async def test_a_teleport_is_motion_the_person_confirms(sim: SimulatedRobot) -> None:
    """confirm = "motion" asks before /turtle1/teleport_absolute; declined, the turtle stays where it is."""
    person = Person("decline")
    pose_type = "turtlesim/msg/Pose" if sim.dialect == "ros2" else "turtlesim/Pose"
    async with (
        watching(sim) as watcher,
        open_session(
            sim.url, guard=None, policy=policy(confirm="motion"), elicitation_callback=person
        ) as session,
    ):
        await watcher.subscribe("/turtle1/pose", pose_type)
        start = await pose(watcher, sim)
        text = await session.error("publish_service", teleport_call(sim))
        stayed = await pose(watcher, sim)
        person.action = "accept"
        await session.ok("publish_service", teleport_call(sim))
        moved = await watcher.wait_for("/turtle1/pose", lambda m: m["x"] == 1.0 and m["y"] == 1.0)
    assert "The person declined" in text
    assert (stayed["x"], stayed["y"]) == (start["x"], start["y"]) != (1.0, 1.0)
    assert moved["x"] == 1.0
    assert len(person.questions) == 2
    assert "motion of the robot through /turtle1/teleport_absolute" in person.questions[0]


async def test_the_policy_names_more_motion_services_and_always_asks_for_every_service(
    sim: SimulatedRobot,
) -> None:
    """[services] motion makes /add_two_ints motion; confirm = "always" asks for any service call."""
    t = types_for(sim)
    call = {"service": "/add_two_ints", "service_type": t["add_two_ints"], "request": {"a": 1, "b": 2}}
    for rules in (policy(confirm="motion", services={"motion": ["/add_*"]}), policy(confirm="always")):
        person = Person("decline")
        async with open_session(sim.url, guard=None, policy=rules, elicitation_callback=person) as session:
            text = await session.error("publish_service", call)
            if rules.confirm == "motion":
                # A service the list does not name is not motion: not asked.
                clear = {"service": "/clear", "service_type": t["empty_srv"], "request": {}}
                await session.ok("publish_service", clear)
        assert "The person declined publish_service on /add_two_ints" in text
        assert len(person.questions) == 1
    assert sim.world.service_calls.get("/add_two_ints", 0) == 0
    assert sim.world.service_calls["/clear"] == 1


async def test_approvals_console_never_asks_the_requesters_client(sim: SimulatedRobot) -> None:
    """approvals = "console": a client that would say yes to anything is never asked; the console's person
    decides, and their no keeps the command from the robot; without a console every confirmation is a no."""
    self_approving = Person("accept")
    rules = policy(confirm="motion", approvals="console")
    operator = Operator(present=True)
    asked = asyncio.Event()
    operator.listen(lambda: asked.set() if operator.pending else None)
    twist = {
        "topic": "/turtle1/cmd_vel",
        "message_type": types_for(sim)["twist"],
        "message": {"linear": {"x": 0.3}},
    }
    async with (
        watching(sim) as watcher,
        open_session(
            sim.url,
            guard=PolicyGuard(rules, Audit(), operator),
            policy=rules,
            elicitation_callback=self_approving,
        ) as session,
    ):
        await watcher.subscribe("/turtle1/cmd_vel", types_for(sim)["twist"])
        await watcher.subscribe("/chatter", types_for(sim)["string"])
        for approve in (False, True):
            asked.clear()
            calling = asyncio.create_task(session.call("publish_topic", twist))
            await asyncio.wait_for(asked.wait(), WAIT)
            [pending] = operator.pending
            assert "/turtle1/cmd_vel" in pending.question
            operator.answer(pending.id, approve)
            result = await asyncio.wait_for(calling, WAIT)
            assert result.is_error is not approve, text_of(result)
        await barrier(session, watcher, sim)
    assert self_approving.questions == []
    assert [m["linear"]["x"] for m in watcher.seen["/turtle1/cmd_vel"]] == [0.3]

    async with open_session(
        sim.url,
        guard=PolicyGuard(rules, Audit(), Operator(present=False)),
        policy=rules,
        elicitation_callback=self_approving,
    ) as session:
        text = await session.error("publish_topic", twist)
    assert "approvals = 'console'" in text
    assert "--console" in text
    assert self_approving.questions == []
    assert len(sim.world.published["/turtle1/cmd_vel"]) == 1


async def test_a_goal_pose_for_the_navigation_stack_is_motion_and_the_policy_names_more_topics(
    sim: SimulatedRobot,
) -> None:
    """confirm = "motion" asks before a PoseStamped on /goal_pose (Nav2 drives there) and before a topic that
    [topics] motion names; declined, neither reaches the robot; /chatter is asked about by no one."""
    person = Person("decline")
    pose_type = "geometry_msgs/msg/PoseStamped" if sim.dialect == "ros2" else "geometry_msgs/PoseStamped"
    # In free space: a goal pose meets the map check before anyone is asked.
    goal = {
        "topic": "/goal_pose",
        "message_type": pose_type,
        "message": {"pose": {"position": {"x": 2.0, "y": 2.0}}},
    }
    rules = policy(confirm="motion", topics={"motion": ["/led/*"]})
    led = {"topic": "/led/blink", "message_type": types_for(sim)["string"], "message": {"data": "on"}}
    async with (
        watching(sim) as watcher,
        open_session(sim.url, guard=None, policy=rules, elicitation_callback=person) as session,
    ):
        await watcher.subscribe("/goal_pose", pose_type)
        await watcher.subscribe("/led/blink", types_for(sim)["string"])
        await watcher.subscribe("/chatter", types_for(sim)["string"])
        texts = [await session.error("publish_topic", goal), await session.error("publish_topic", led)]
        await barrier(session, watcher, sim)
    assert all("The person declined" in text for text in texts), texts
    assert len(person.questions) == 2
    assert "motion of the robot through /goal_pose" in person.questions[0]
    assert "/goal_pose" not in watcher.seen
    assert "/led/blink" not in watcher.seen
