"""A call approved before a stop sends nothing after it, even when the stop comes before its first frame.

Over a link that takes 150 ms each way, a single ``publish_topic`` spends a round trip on its liveness ping
and a goal one on opening its lane (ROS 2) or waiting for the action server's status (ROS 1) before anything
of it is sent. ``stop_robot`` called in that gap (the moment the console's audit shows the call allowed)
voids it: nothing reaches the robot, and the call's answer says stop_robot stopped it.
"""

from __future__ import annotations

import asyncio

from console_harness import text_of
from race_harness import CMD_VEL, FIB, race_console, types_of

from rosbridge_mcp_server.sim import SimulatedRobot

LINK = 0.15


async def test_a_single_publish_approved_before_stop_robot_is_not_sent(sim: SimulatedRobot) -> None:
    types = types_of(sim.dialect)
    async with race_console(sim.url, sim.dialect, LINK, world=sim.world) as race:
        race.allowed.clear()
        call = {"topic": CMD_VEL, "message_type": types["twist"], "message": {"linear": {"x": 0.7}}}
        publishing = asyncio.create_task(race.mcp.call_tool("publish_topic", call))
        async with asyncio.timeout(10):
            await race.allowed.wait()
        stopped = await race.mcp.call_tool("stop_robot", {})
        assert not stopped.is_error, text_of(stopped)
        result = await asyncio.wait_for(publishing, 10)
        await race.mark()  # everything sent before it has reached the robot
    assert result.is_error, text_of(result)
    assert "stop_robot stopped this call before it was sent" in text_of(result)
    assert [m for m in sim.world.published.get(CMD_VEL, ()) if m.msg["linear"]["x"]] == []


async def test_a_goal_approved_before_stop_robot_is_never_sent(sim: SimulatedRobot) -> None:
    types = types_of(sim.dialect)
    async with race_console(sim.url, sim.dialect, LINK, world=sim.world) as race:
        goals_before = set(sim.world.goals)
        race.allowed.clear()
        call = {"action_name": FIB, "action_type": types["fibonacci"], "goal": {"order": 5}, "timeout": 10}
        sending = asyncio.create_task(race.mcp.call_tool("publish_action", call))
        async with asyncio.timeout(10):
            await race.allowed.wait()
        stopped = await race.mcp.call_tool("stop_robot", {})
        assert not stopped.is_error, text_of(stopped)
        result = await asyncio.wait_for(sending, 15)
        # A goal sent late would be accepted within a round trip; the robot's own record says none came.
        await asyncio.sleep(2 * LINK)
        await race.mark()
    assert result.is_error, text_of(result)
    assert "stop_robot" in text_of(result), text_of(result)
    assert "before it was sent" in text_of(result), text_of(result)
    assert set(sim.world.goals) == goals_before


async def test_a_goal_whose_cancel_came_first_is_never_sent(sim_ros1: SimulatedRobot) -> None:
    """cancel_action in the gap before the goal's first frame: the goal never reaches the robot, and its call
    says cancel_action cancelled it before it was sent.

    ROS 1 only: there the gap is long enough to land in every time (the goal waits for the action server's
    first status, published at 5 Hz); a ROS 2 goal's gap (its lane opening) is about as long as
    cancel_action's own look-up of the action, so which comes first varies.
    """
    sim = sim_ros1
    types = types_of(sim.dialect)
    # The gap held open on a busy machine too: the server's status every 3 s, not 5 Hz, so the goal waits for
    # its first status longer than cancel_action takes.
    server = sim._nodes.fibonacci1
    assert server is not None
    server.STATUS_PERIOD = 3.0
    async with race_console(sim.url, sim.dialect, LINK, world=sim.world) as race:
        goals_before = set(sim.world.goals)
        race.allowed.clear()
        call = {"action_name": FIB, "action_type": types["fibonacci"], "goal": {"order": 5}, "timeout": 10}
        sending = asyncio.create_task(race.mcp.call_tool("publish_action", call))
        async with asyncio.timeout(10):
            await race.allowed.wait()
        cancelled = await race.mcp.call_tool("cancel_action", {"action_name": FIB})
        assert not cancelled.is_error, text_of(cancelled)
        result = await asyncio.wait_for(sending, 15)
        await asyncio.sleep(2 * LINK)  # a goal sent late would be accepted within a round trip
        await race.mark()
    assert result.is_error, text_of(result)
    assert "cancelled by cancel_action before it was sent" in text_of(result), text_of(result)
    assert set(sim.world.goals) == goals_before
