"""A trajectory this server published on a controller's ``…/joint_trajectory`` topic is stopped by
``stop_robot`` and by the E-STOP: a raw socket sees the hold reach the topic, and the simulated arm stops
where it is within 0.5 s (``robot/arm_stop.py``)."""

from __future__ import annotations

import asyncio
import contextlib
import json
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from dataclasses import replace
from typing import Any

import pytest
import websockets
from mcp_harness import open_session, text_of

from rosbridge_mcp_server.robot.arm_stop import stop_trajectories
from rosbridge_mcp_server.safety import emergency_stop, parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.nodes.arm import ARM_JOINTS, HOME

MakeSim = Callable[..., Awaitable[SimulatedRobot]]
TOPIC = "/arm_controller/joint_trajectory"
#: The controller's topic on each dialect (ros2_control's, ros_control's).
TOPICS = {"ros2": TOPIC, "ros1": "/arm_controller/command"}
TYPES = {"ros2": "trajectory_msgs/msg/JointTrajectory", "ros1": "trajectory_msgs/JointTrajectory"}


def pan(dialect: str, radians: float, seconds: float) -> dict[str, Any]:
    """HOME with the shoulder panned to *radians*, reached at *seconds* (whole)."""
    when = {"secs": int(seconds), "nsecs": 0} if dialect == "ros1" else {"sec": int(seconds), "nanosec": 0}
    positions = [radians if name == "shoulder_pan_joint" else HOME[name] for name in ARM_JOINTS]
    return {"joint_names": list(ARM_JOINTS), "points": [{"positions": positions, "time_from_start": when}]}


class Seen:
    """The messages a raw socket heard on the topic, and a wait for the n-th."""

    def __init__(self) -> None:
        self.messages: list[dict[str, Any]] = []
        self.changed = asyncio.Event()

    def add(self, message: dict[str, Any]) -> None:
        self.messages.append(message)
        self.changed.set()

    async def count(self, n: int, timeout: float) -> None:
        async with asyncio.timeout(timeout):
            while len(self.messages) < n:
                self.changed.clear()
                await self.changed.wait()


@contextlib.asynccontextmanager
async def topic_watcher(robot: SimulatedRobot, dialect: str) -> AsyncIterator[Seen]:
    """Every message on the trajectory topic, as a raw rosbridge client hears it."""
    seen = Seen()
    topic = TOPICS[dialect]
    async with websockets.connect(robot.url) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": topic, "type": TYPES[dialect]}))

        async def read() -> None:
            async for raw in ws:
                frame = json.loads(raw)
                if frame.get("op") == "publish" and frame.get("topic") == topic:
                    seen.add(frame["msg"])

        reader = asyncio.create_task(read())
        try:
            yield seen
        finally:
            reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reader


@pytest.mark.parametrize("how", ["stop_robot", "estop"])
@pytest.mark.parametrize("dialect", ["ros2", "ros1"])
async def test_a_trajectory_published_on_the_topic_is_held_by_both_stops(
    make_sim: MakeSim, dialect: str, how: str
) -> None:
    robot = await make_sim(dialect=dialect, world="arm")
    arm, topic = robot.arm, TOPICS[dialect]
    async with (
        open_session(robot.url, guard=None, policy=parse_policy({}, where="t")) as session,
        topic_watcher(robot, dialect) as seen,
    ):
        # 90° at a quarter of 2 rad/s needs 3.1 s: 4 s is allowed.
        sent = await session.call(
            "publish_topic", {"topic": topic, "message_type": TYPES[dialect], "message": pan(dialect, 1.5, 4)}
        )
        assert not sent.is_error, text_of(sent)
        await robot.wait_for(lambda _: arm.run is not None and arm.velocities["shoulder_pan_joint"] > 0, 15.0)
        await seen.count(1, 5.0)
        if how == "stop_robot":
            answer = text_of(await session.ok("stop_robot"))
            assert f"Stopped the trajectory on {topic}" in answer, answer
        else:
            assert session.robot is not None
            report = await emergency_stop(session.robot, by="console")
            assert report.held_topics == [topic], report
        await robot.wait_for(lambda _: arm.run is None and not any(arm.velocities.values()), 0.5)
        stopped_at = arm.positions["shoulder_pan_joint"]
        await seen.count(2, 2.0)
        # A second stop has nothing left to hold on the topic.
        again = text_of(await session.ok("stop_robot"))
    hold = seen.messages[1]
    assert hold["joint_names"] == list(ARM_JOINTS)
    if dialect == "ros1":
        assert hold["points"] == []
    else:
        assert len(hold["points"]) == 1
        assert hold["points"][0]["time_from_start"] == {"sec": 0, "nanosec": 0}
    assert 0.0 < stopped_at < 1.4
    assert arm.positions["shoulder_pan_joint"] == pytest.approx(stopped_at, abs=0.02)
    assert "Stopped the trajectory" not in again


async def test_a_trajectory_that_has_run_out_is_not_held(make_sim: MakeSim) -> None:
    """Once its last point is past (and the grace), a stop leaves the topic alone: a hold then could only
    preempt what another client runs."""
    robot = await make_sim(dialect="ros2", world="arm")
    async with (
        open_session(robot.url, guard=None, policy=parse_policy({}, where="t")) as session,
        topic_watcher(robot, "ros2") as seen,
    ):
        sent = await session.call(
            "publish_topic", {"topic": TOPIC, "message_type": TYPES["ros2"], "message": pan("ros2", 0.02, 1)}
        )
        assert not sent.is_error, text_of(sent)
        assert session.robot is not None
        [entry] = session.robot.activity.trajectories
        assert entry.topic == TOPIC
        assert entry.joints == tuple(ARM_JOINTS)
        await seen.count(1, 5.0)
        await robot.wait_for(lambda _: robot.arm.run is None, 15.0)
        client, graph = session.robot.client, session.robot.graph
        over = replace(entry, until=time.monotonic() - 0.01)
        assert await stop_trajectories(client, graph, [over]) == ([], [])
        running = replace(entry, until=time.monotonic() + 5)
        held, failures = await stop_trajectories(client, graph, [running])
        await seen.count(2, 2.0)
        # One whose first message has run out but whose stream this stop ended is held too (the stream's
        # last message may have come long after the first).
        streamed, _ = await stop_trajectories(client, graph, [over], streamed={TOPIC})
        await seen.count(3, 2.0)
    assert not failures
    assert [topic for topic, _, _ in held] == [TOPIC]
    assert [topic for topic, _, _ in streamed] == [TOPIC]
    assert seen.messages[1]["points"][0]["positions"][0] == pytest.approx(0.02, abs=0.005)
