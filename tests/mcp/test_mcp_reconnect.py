"""A bridge that drops or restarts: in-flight calls fail at once, nothing is sent late, later calls work."""

from __future__ import annotations

import asyncio
import signal
import socket
import sys
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import asynccontextmanager
from typing import Any

import pytest
from mcp_harness import Session, open_session, text_of, types_for

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.robot.owed_zeros import ROS1_REPEAT_SECONDS
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.world import PublishedMessage, World

CMD_VEL = "/turtle1/cmd_vel"
WAIT = 30.0


@pytest.fixture(params=["ros2", "ros1"])
async def robot(
    request: pytest.FixtureRequest, make_sim: Callable[..., Awaitable[SimulatedRobot]]
) -> SimulatedRobot:
    """A robot of each dialect with a service slow enough to be in flight when the bridge goes away."""
    return await make_sim(dialect=request.param, slow_service_seconds=30.0)


@pytest.fixture
async def robot_session(robot: SimulatedRobot) -> AsyncIterator[Session]:
    """A session on that robot."""
    async with open_session(robot.url, request_timeout=60.0) as opened:
        yield opened


def _twist(robot: SimulatedRobot, x: float) -> dict[str, object]:
    return {"topic": CMD_VEL, "message_type": types_for(robot)["twist"], "message": {"linear": {"x": x}}}


async def test_a_call_in_flight_fails_at_once_when_the_connection_drops(
    robot_session: Session, robot: SimulatedRobot
) -> None:
    """A pending service call ends with the connection-lost text; the next call works after reconnecting."""
    slow = asyncio.create_task(
        robot_session.call(
            "publish_service",
            {
                "service": "/slow_service",
                "service_type": types_for(robot)["trigger"],
                "request": {},
                "timeout": 60,
            },
        )
    )
    await robot.world.wait_for(lambda w: w.service_calls.get("/slow_service") == 1, WAIT)
    await robot.drop_connections()
    result = await asyncio.wait_for(slow, WAIT)
    assert result.is_error
    text = result.content[0].text  # type: ignore[union-attr]
    assert f"The connection to rosbridge at {robot.url} dropped while waiting" in text
    assert "Nothing will be re-sent automatically" in text

    await robot_session.ros.wait_connected(WAIT)
    await robot_session.ok("list_topics")


async def test_a_publish_during_an_outage_fails_and_is_never_delivered_later(
    robot_session: Session, robot: SimulatedRobot
) -> None:
    """With the bridge down, publish_topic is an error; after the restart only later messages arrive."""
    await robot_session.ok("publish_topic", _twist(robot, 0.1))
    await robot.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) == 1, WAIT)

    await robot.stop()
    await robot_session.ros.wait_disconnected(WAIT)
    outage = await robot_session.error("publish_topic", _twist(robot, 0.9))
    assert f"Not connected to rosbridge at {robot.url}" in outage
    assert "nothing was sent" in outage
    listing = await robot_session.error("list_topics")
    assert "Not connected" in listing

    await robot.start()
    await robot_session.ros.wait_connected(WAIT)
    await robot_session.ok("publish_topic", _twist(robot, 0.2))
    await robot.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) >= 2, WAIT)
    await robot_session.ok("list_topics")  # one more round trip for anything queued to show up
    assert [m.msg["linear"]["x"] for m in robot.world.published[CMD_VEL]] == [0.1, 0.2]


async def test_after_a_reconnect_to_another_kind_of_robot_the_tools_follow_it(
    make_sim: Callable[..., Awaitable[SimulatedRobot]],
) -> None:
    """When a ROS 1 bridge replaces the ROS 2 one at the same address, types and checks follow it."""
    ros2 = await make_sim(dialect="ros2")
    async with open_session(ros2.url) as session:
        await session.ok("publish_topic", _twist(ros2, 0.3))
        port = ros2.port
        await ros2.stop()
        await session.ros.wait_disconnected(WAIT)
        ros1 = await make_sim(dialect="ros1", port=port)
        await session.ros.wait_connected(WAIT)
        listed = (await session.ok("list_topics")).structured_content
        assert listed is not None
        assert {"name": CMD_VEL, "type": "geometry_msgs/Twist"} in listed["topics"]
        text = await session.error("publish_topic", {**_twist(ros1, 0.0), "message": {"linear": {"x": "x"}}})
        assert "geometry_msgs/Twist" in text
        await session.ok("publish_topic", _twist(ros1, 0.4))
        await ros1.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) == 1, WAIT)
    assert ros1.world.published[CMD_VEL][0].msg["linear"]["x"] == 0.4


@asynccontextmanager
async def _robot_process() -> AsyncIterator[tuple[asyncio.subprocess.Process, str]]:
    """The simulated robot in a process of its own (ROS 2), so a test can freeze it the way a hung bridge or a
    silently dead link behaves; yields the process and its URL."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    process = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "rosbridge_mcp_server.sim", "--port", str(port), "--log-level", "ERROR"
    )
    try:
        yield process, f"ws://127.0.0.1:{port}"
    finally:
        process.send_signal(signal.SIGCONT)
        process.terminate()
        await process.wait()


async def test_a_frozen_bridge_is_sent_no_publish_that_it_would_deliver_late() -> None:
    """While the bridge is stopped (SIGSTOP) publish_topic refuses; after SIGCONT only later ones arrive."""
    string = "std_msgs/msg/String"
    topic = "/mcp_test/frozen"
    async with _robot_process() as (process, url):
        watcher = RosbridgeClient(url, reconnect_min=0.05, reconnect_max=0.2)
        async with watcher, open_session(url, request_timeout=1.0, wait=False) as session:
            await watcher.wait_connected(WAIT)
            await session.ros.wait_connected(WAIT)
            async with watcher.subscribe(topic, string) as sub:
                await session.ok(
                    "publish_topic", {"topic": topic, "message_type": string, "message": {"data": "a"}}
                )
                assert await sub.get(timeout=WAIT) == {"data": "a"}
                process.send_signal(signal.SIGSTOP)
                try:
                    text = await session.error(
                        "publish_topic", {"topic": topic, "message_type": string, "message": {"data": "late"}}
                    )
                finally:
                    process.send_signal(signal.SIGCONT)
                assert "did not answer a ping within 1 s" in text
                assert "nothing was published" in text
                await session.ok(
                    "publish_topic", {"topic": topic, "message_type": string, "message": {"data": "b"}}
                )
                assert await sub.get(timeout=WAIT) == {"data": "b"}


async def test_a_timed_out_goal_whose_cancel_is_not_confirmed_may_still_be_running() -> None:
    """A goal past its timeout on a frozen bridge is not called cancelled: it may still be running."""
    async with (
        _robot_process() as (process, url),
        open_session(url, request_timeout=5.0, wait=False) as session,
    ):
        await session.ros.wait_connected(WAIT)
        first_feedback = asyncio.Event()

        async def on_progress(progress: float, total: float | None, message: str | None) -> None:
            first_feedback.set()

        goal = {"action_name": "/fibonacci", "action_type": "example_interfaces/action/Fibonacci"}
        call = asyncio.create_task(
            session.mcp.call_tool(
                "publish_action",
                {**goal, "goal": {"order": 30}, "timeout": 1.0},
                progress_callback=on_progress,
            )
        )
        await asyncio.wait_for(first_feedback.wait(), WAIT)
        process.send_signal(signal.SIGSTOP)
        try:
            result = await asyncio.wait_for(call, WAIT)
        finally:
            process.send_signal(signal.SIGCONT)
    text = text_of(result)
    assert result.structured_content is not None, text
    assert result.structured_content["status"] == "timed out"
    assert result.structured_content["canceled_by"] == "timeout"
    assert "may still be running" in text
    assert "it was cancelled because" not in text


STILL = {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}


@pytest.mark.parametrize("ended_by", ["cancel", "outage"])
async def test_a_velocity_stream_cut_off_by_an_outage_gets_its_zero_once_the_bridge_is_back(
    robot_session: Session, robot: SimulatedRobot, ended_by: str
) -> None:
    """A stream at 0.4 m/s, the bridge down, the call cancelled then (or failing on its own): the closing zero
    could not be sent, and the robot's last command was 0.4 m/s. Once the bridge is back, the zero goes out
    before anything else this server sends on the topic."""
    stream = {**_twist(robot, 0.4), "rate_hz": 10, "duration": 30}
    call = asyncio.create_task(robot_session.call("publish_topic", stream))
    await robot.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) >= 2, WAIT)
    await robot.stop()
    await robot_session.ros.wait_disconnected(WAIT)
    if ended_by == "cancel":
        call.cancel()
        with pytest.raises(asyncio.CancelledError):
            await call
    else:
        assert (await asyncio.wait_for(call, WAIT)).is_error
    assert robot.world.published[CMD_VEL][-1].msg["linear"]["x"] == 0.4
    await robot.start()
    await robot.wait_for(lambda w: w.published[CMD_VEL][-1].msg == STILL, WAIT)
    await robot_session.ok("list_topics")  # a round trip more: nothing else came on the topic
    assert robot.world.published[CMD_VEL][-1].msg == STILL


async def _stop_while_down(session: Session, robot: SimulatedRobot) -> str:
    """One 0.4 m/s command, the bridge down, then stop_robot (its zero owed): the stop's text."""
    await session.ok("publish_topic", _twist(robot, 0.4))
    await robot.wait_for(lambda w: len(w.published.get(CMD_VEL, ())) == 1, WAIT)
    await robot.stop()
    await session.ros.wait_disconnected(WAIT)
    return text_of(await session.call("stop_robot"))


async def test_a_stop_while_the_bridge_is_down_sends_its_zeros_once_it_is_back(
    robot_session: Session, robot: SimulatedRobot
) -> None:
    """One 0.4 m/s command, the bridge down, stop_robot: it says no zero could be sent yet; once the bridge is
    back, the zero goes out on the velocity topic."""
    text = await _stop_while_down(robot_session, robot)
    assert f"No zero velocity command could be sent on {CMD_VEL} (not connected); each goes out" in text, text
    assert "Nothing to stop" not in text  # it had sent a velocity command: that was claimed not to be so
    await robot.start()
    await robot.wait_for(lambda w: w.published[CMD_VEL][-1].msg == STILL, WAIT)


async def test_an_owed_zero_goes_twice_on_ros1_as_a_new_publishers_first_message_is_often_lost(
    robot_session: Session, robot: SimulatedRobot
) -> None:
    """rospy often loses what a publisher created a moment ago sends: on ROS 1 the owed zero goes once more a
    second later, on the same connection; ROS 2 sends it once."""
    await _stop_while_down(robot_session, robot)
    await robot.start()

    def zeros(world: World) -> list[PublishedMessage]:
        return [m for m in world.published.get(CMD_VEL, ()) if m.msg == STILL]

    if robot.dialect == "ros1":
        await robot.wait_for(lambda w: len(zeros(w)) >= 2, WAIT)
        first, second = zeros(robot.world)
        assert first.connection_id == second.connection_id
        assert second.received_at - first.received_at >= ROS1_REPEAT_SECONDS * 0.9
    else:
        await robot.wait_for(lambda w: len(zeros(w)) >= 1, WAIT)
        # Past the moment a ROS 1 repeat would come, one round trip more: no second zero.
        await asyncio.sleep(ROS1_REPEAT_SECONDS * 1.5)  # the absence of a repeat is what is checked
        await robot_session.ok("list_topics")
        assert len(zeros(robot.world)) == 1


async def test_on_ros1_an_owed_zero_is_not_repeated_over_a_later_command(make_sim: Any) -> None:
    """A command this server sends on the topic after the owed zero went out replaces it: no repeat."""
    robot = await make_sim(dialect="ros1")
    async with open_session(robot.url, request_timeout=60.0) as session:
        await _stop_while_down(session, robot)
        await robot.start()
        await robot.wait_for(lambda w: w.published[CMD_VEL][-1].msg == STILL, WAIT)
        await session.ok("publish_topic", _twist(robot, 0.2))
        await asyncio.sleep(ROS1_REPEAT_SECONDS * 1.5)  # the absence of a repeat is what is checked
        await session.ok("list_topics")
    assert robot.world.published[CMD_VEL][-1].msg["linear"]["x"] == 0.2
