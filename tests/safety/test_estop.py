"""The e-stop against the simulated robot: streams end first, then each velocity topic gets one zero."""

from __future__ import annotations

import asyncio
import contextlib
from typing import Any, get_args

import pytest

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.errors import NotConnectedError
from rosbridge_mcp_server.robot.activity import SessionActivity
from rosbridge_mcp_server.robot.approval import ALLOW_ALL
from rosbridge_mcp_server.robot.goals import run_goal
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import Presser, emergency_stop
from rosbridge_mcp_server.sim import SimulatedRobot

WAIT = 30.0
CMD_VEL = "/turtle1/cmd_vel"


def twist_type(sim: SimulatedRobot, stamped: bool = False) -> str:
    name = "TwistStamped" if stamped else "Twist"
    return f"geometry_msgs/msg/{name}" if sim.dialect == "ros2" else f"geometry_msgs/{name}"


async def stream(
    client: RosbridgeClient,
    activity: SessionActivity,
    topic: str,
    type_name: str,
    message: dict[str, Any],
    *,
    through_outages: bool = False,
) -> int:
    """A publish stream as a tool runs it: registered for its whole life, 50 Hz until asked to stop.

    ``through_outages`` keeps it going while the robot is unreachable, so that only the stop can end it.
    """
    sent = 0
    with activity.stream(topic, type_name) as running:
        while True:
            try:
                await client.publish(topic, type_name, message)
            except NotConnectedError:
                if not through_outages:
                    raise
            else:
                activity.published(topic, type_name, message)
                sent += 1
            if await running.pause(0.02):
                return sent


def is_zero(message: dict[str, Any]) -> bool:
    twist = message.get("twist", message)
    return all(twist[v][axis] == 0 for v in ("linear", "angular") for axis in ("x", "y", "z"))


async def test_a_running_stream_ends_and_its_last_message_is_zero(sim: SimulatedRobot) -> None:
    """After the e-stop, the stream's task is done and the newest message on the topic stands still."""
    client = RosbridgeClient(sim.url)
    robot = RobotSession(client, ALLOW_ALL)
    activity = robot.activity
    async with client:
        await client.wait_connected(WAIT)
        moving = {"linear": {"x": 0.8, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.4}}
        task = asyncio.create_task(stream(client, activity, CMD_VEL, twist_type(sim), moving))
        await sim.world.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) >= 3, WAIT)
        report = await emergency_stop(robot, by="stop_robot")
        assert task.done()
        assert task.result() >= 3  # it ended by itself, on the request, not by a cancel
        # A barrier: a service reply on the same connection comes after every publish sent before it.
        await client.call_service("/rosapi/get_time", {})
    assert report.streams_stopped == [CMD_VEL]
    assert report.zeroed_topics == [CMD_VEL]
    assert report.failures == []
    assert activity.streams == []
    assert is_zero(sim.world.published[CMD_VEL][-1].msg)
    assert not is_zero(sim.world.published[CMD_VEL][-2].msg)


async def test_a_twist_stamped_stop_keeps_the_frame_and_carries_the_time(sim: SimulatedRobot) -> None:
    """A TwistStamped zero is stamped now (a zero stamp could be dropped as stale), in the last frame."""
    client = RosbridgeClient(sim.url)
    robot = RobotSession(client, ALLOW_ALL)
    activity = robot.activity
    type_name = twist_type(sim, stamped=True)
    message = {"header": {"frame_id": "base_link"}, "twist": {"linear": {"x": 0.5}}}
    async with client:
        await client.wait_connected(WAIT)
        await client.publish("/base/cmd_vel", type_name, message)
        activity.published("/base/cmd_vel", type_name, message)
        await emergency_stop(robot, by="stop_robot")
        await client.call_service("/rosapi/get_time", {})
    last = sim.world.published["/base/cmd_vel"][-1].msg
    assert is_zero(last)
    assert last["header"]["frame_id"] == "base_link"
    stamp = last["header"]["stamp"]
    seconds = stamp.get("sec", stamp.get("secs"))
    assert seconds > 1_600_000_000


async def test_a_stream_that_will_not_end_is_reported_and_the_zero_still_goes_out(
    sim_ros2: SimulatedRobot,
) -> None:
    """A stream deaf to cancellation cannot hold the stop hostage: it is named, and the zero goes out."""
    client = RosbridgeClient(sim_ros2.url)
    robot = RobotSession(client, ALLOW_ALL)
    activity = robot.activity
    release = asyncio.Event()
    running = asyncio.Event()

    async def stubborn() -> None:
        with activity.stream(CMD_VEL, "geometry_msgs/msg/Twist"):
            running.set()
            while not release.is_set():
                with contextlib.suppress(asyncio.CancelledError):
                    await release.wait()

    async with client:
        await client.wait_connected(WAIT)
        activity.published(CMD_VEL, "geometry_msgs/msg/Twist", {})
        task = asyncio.create_task(stubborn())
        await asyncio.wait_for(running.wait(), WAIT)
        # The stream never ends by itself: a stop that waited for it would not answer at all.
        report = await asyncio.wait_for(emergency_stop(robot, by="stop_robot"), 2 * WAIT)
        assert not task.done()
        await sim_ros2.world.wait_for(
            lambda w: bool(w.published.get(CMD_VEL)) and is_zero(w.published[CMD_VEL][-1].msg), WAIT
        )
        release.set()
        await task
    assert report.streams_still_running == [CMD_VEL]
    assert report.zeroed_topics == [CMD_VEL]


async def test_only_velocity_commands_are_remembered_for_the_stop() -> None:
    """A String published on /chatter gets no "zero" from the e-stop."""
    activity = SessionActivity()
    activity.published("/chatter", "std_msgs/msg/String", {"data": "hi"})
    activity.published("/cmd_vel", "geometry_msgs/Twist", {})
    assert [t.topic for t in activity.velocity_topics] == ["/cmd_vel"]


async def test_a_stream_that_does_not_look_at_the_request_is_cancelled(sim_ros2: SimulatedRobot) -> None:
    """A loop sleeping with plain asyncio.sleep is cancelled halfway through the wait, and counts as ended."""
    client = RosbridgeClient(sim_ros2.url)
    robot = RobotSession(client, ALLOW_ALL)
    activity = robot.activity
    running = asyncio.Event()

    async def oblivious() -> None:
        with activity.stream(CMD_VEL, "geometry_msgs/msg/Twist"):
            running.set()
            await asyncio.Event().wait()

    async with client:
        await client.wait_connected(WAIT)
        task = asyncio.create_task(oblivious())
        await asyncio.wait_for(running.wait(), WAIT)
        report = await emergency_stop(robot, by="stop_robot")
    assert task.cancelled()
    assert report.streams_stopped == [CMD_VEL]
    assert report.streams_still_running == []


@pytest.mark.parametrize("dialect", ["ros2"])
async def test_without_a_connection_the_stop_still_ends_the_streams_and_says_what_failed(
    make_sim: Any, dialect: str
) -> None:
    """The robot unreachable: streams end all the same, and the report says no zero could be sent."""
    sim: SimulatedRobot = await make_sim(dialect=dialect)
    client = RosbridgeClient(sim.url, reconnect_min=5.0)
    robot = RobotSession(client, ALLOW_ALL)
    activity = robot.activity
    async with client:
        await client.wait_connected(WAIT)
        activity.published(CMD_VEL, "geometry_msgs/msg/Twist", {})
        task = asyncio.create_task(
            stream(client, activity, CMD_VEL, "geometry_msgs/msg/Twist", {}, through_outages=True)
        )
        await sim.world.wait_for(lambda w: CMD_VEL in w.published, WAIT)
        await sim.stop()
        await client.wait_disconnected(WAIT)
        report = await emergency_stop(robot, by="stop_robot")
        assert task.done()
    assert report.streams_stopped == [CMD_VEL]
    assert report.zeroed_topics == []
    assert report.failures
    assert "not connected" in report.failures[0]


#: Each presser as every answer of what its stop ended must name it: (voided calls and ended streams,
#: a cancelled goal's canceled_by). Written out here, not read from the code, so a mislabel fails.
PRESSED_BY: dict[str, tuple[str, str]] = {
    "stop_robot": ("stop_robot", "stop_robot"),
    "console": ("E-STOP on the operator console", "estop"),
    "shutdown": ("the server shutting down", "request_cancelled"),
}


def test_every_presser_has_its_expected_names() -> None:
    """A presser added without saying how its stops are named fails here."""
    assert set(get_args(Presser)) == set(PRESSED_BY)


@pytest.mark.parametrize("by", list(PRESSED_BY))
async def test_each_presser_is_named_by_what_its_stop_ended(sim: SimulatedRobot, by: Presser) -> None:
    """A call approved before the stop, a running stream and a running goal: each says who stopped it."""
    name, canceled_by = PRESSED_BY[by]
    client = RosbridgeClient(sim.url)
    robot = RobotSession(client, ALLOW_ALL)
    ros2 = sim.dialect == "ros2"
    action_type = "example_interfaces/action/Fibonacci" if ros2 else "actionlib_tutorials/FibonacciAction"
    async with client:
        await client.wait_connected(WAIT)
        ticket = robot.gate.ticket()
        assert robot.gate.refusal(ticket) is None
        moving = {"linear": {"x": 0.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
        streaming = asyncio.create_task(stream(client, robot.activity, CMD_VEL, twist_type(sim), moving))
        goal = asyncio.create_task(
            run_goal(robot.goals, "/fibonacci", action_type, {"order": 40}, timeout=10.0)
        )
        await sim.world.wait_for(
            lambda w: (
                len(w.published.get(CMD_VEL, ())) >= 2
                and any(not g.finished and g.feedback_count >= 1 for g in w.goals.values())
            ),
            WAIT,
        )
        [running] = robot.activity.streams
        report = await emergency_stop(robot, by=by)
        outcome = await asyncio.wait_for(goal, WAIT)
        await asyncio.wait_for(streaming, WAIT)
    assert report.streams_stopped == [CMD_VEL]
    assert len(report.goals_cancelled) == 1
    assert running.stopped_by == name
    refusal = robot.gate.refusal(ticket)
    assert refusal is not None
    assert refusal.startswith(f"Stopped: {name} stopped this call")
    assert outcome.canceled_by == canceled_by


async def test_a_stop_by_no_known_presser_is_refused_before_it_voids_anything(
    sim_ros2: SimulatedRobot,
) -> None:
    """``by`` must be a real presser: an unknown one is a clear error, and nothing is stopped under it."""
    client = RosbridgeClient(sim_ros2.url)
    robot = RobotSession(client, ALLOW_ALL)
    async with client:
        await client.wait_connected(WAIT)
        ticket = robot.gate.ticket()
        with pytest.raises(ValueError, match="unknown presser 'someone'; one of stop_robot, console"):
            await emergency_stop(robot, by="someone")  # type: ignore[arg-type]
        assert robot.gate.refusal(ticket) is None
