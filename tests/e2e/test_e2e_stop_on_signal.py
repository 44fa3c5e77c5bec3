"""Stopping stops the robot first: a signal to the server's process group (Ctrl-C in a terminal, an
impatient one pressed twice, SIGTERM from an MCP client) or stdin closing, while ``navigate_to`` drives on the
simulated Nav2 world, cancels the goal on the robot before the process exits; a raw rosbridge socket sees the
goal's status end CANCELED and the robot stands short of the goal.

The server runs in a process group of its own (``start_new_session``), and only that group is signalled.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import os
import signal
import sys
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import httpx2
import pytest
import websockets
from e2e_transports import TOKEN, TOKENS, WAIT, _env, start_http
from mcp.client.streamable_http import streamable_http_client

from mcp import Client
from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]
#: Far enough from the robot's start that it is still driving when the signal comes (0.4 m/s).
GOAL = {"x": 1.5, "y": 2.0}
#: The grace docs/deployment.md promises, plus room for a loaded machine.
EXIT_WAIT = 20.0
CANCELED = 5
CMD_VEL = "/turtle1/cmd_vel"
TWIST = "geometry_msgs/msg/Twist"
STILL = {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
FORWARD_STREAM = {
    "topic": CMD_VEL,
    "message_type": TWIST,
    "message": {"linear": {"x": 0.4, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}},
    "rate_hz": 10,
    "duration": 60,
}

#: How the server is told to stop: signals to its group, 20 ms apart, or (stdio) stdin closing.
STOPS = {
    "sigint": (signal.SIGINT,),
    "sigint-twice": (signal.SIGINT, signal.SIGINT),
    "sigterm": (signal.SIGTERM,),
    "sigint-then-sigterm": (signal.SIGINT, signal.SIGTERM),
    # The terminal it runs in closed (a window, an ssh session): its default was to end the process at once.
    "sighup": (signal.SIGHUP,),
}


class StatusWatcher:
    """A raw rosbridge socket on the navigator's goal status topic: every status each goal had."""

    def __init__(self) -> None:
        self.statuses: dict[str, list[int]] = {}
        self.changed = asyncio.Event()

    async def read(self, ws: Any) -> None:
        async for raw in ws:
            frame = json.loads(raw)
            if frame.get("op") != "publish":
                continue
            for status in frame["msg"].get("status_list", []):
                uuid = str(status["goal_info"]["goal_id"]["uuid"])
                self.statuses.setdefault(uuid, []).append(status["status"])
            self.changed.set()

    async def wait(self, predicate: Callable[[dict[str, list[int]]], bool], timeout: float) -> None:
        async with asyncio.timeout(timeout):
            while not predicate(self.statuses):
                self.changed.clear()
                await self.changed.wait()


@contextlib.asynccontextmanager
async def watching(robot: SimulatedRobot) -> AsyncIterator[StatusWatcher]:
    async with websockets.connect(robot.url) as ws:
        await ws.send(
            json.dumps(
                {
                    "op": "subscribe",
                    "topic": "/navigate_to_pose/_action/status",
                    "type": "action_msgs/msg/GoalStatusArray",
                }
            )
        )
        watcher = StatusWatcher()
        reader = asyncio.create_task(watcher.read(ws))
        try:
            yield watcher
        finally:
            reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reader


@pytest.fixture
async def nav2(make_sim: MakeSim) -> SimulatedRobot:
    return await make_sim(dialect="ros2", world="nav2")


async def _signal_group(process: asyncio.subprocess.Process, signals: tuple[signal.Signals, ...]) -> None:
    for number, sig in enumerate(signals):
        if number:
            await asyncio.sleep(0.02)  # the attack: a second key press 20 ms after the first
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, sig)


async def _stopped_short(robot: SimulatedRobot, watcher: StatusWatcher) -> None:
    """The goal's status ended CANCELED (the raw socket saw it) and the robot stands short of the goal."""
    await watcher.wait(lambda statuses: any(s[-1] == CANCELED for s in statuses.values()), WAIT)
    driven = robot.nav2.robots[0]
    await robot.wait_for(lambda _world: driven.linear == 0.0 and driven.angular == 0.0, WAIT)
    assert math.hypot(driven.x - GOAL["x"], driven.y - GOAL["y"]) > 0.5


async def _start_stdio(
    robot: SimulatedRobot, name: str, arguments: dict[str, Any]
) -> asyncio.subprocess.Process:
    """The stdio server in a process group of its own, initialized and sent one tools/call."""
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosbridge_mcp_server",
        "--url",
        robot.url,
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
        env=_env(None),
        start_new_session=True,
    )
    assert process.stdin is not None
    for message in (
        {
            "jsonrpc": "2.0",
            "id": 1,
            "method": "initialize",
            "params": {
                "protocolVersion": "2025-06-18",
                "capabilities": {},
                "clientInfo": {"name": "e2e-test", "version": "0"},
            },
        },
        {"jsonrpc": "2.0", "method": "notifications/initialized"},
        {"jsonrpc": "2.0", "id": 2, "method": "tools/call", "params": {"name": name, "arguments": arguments}},
    ):
        process.stdin.write((json.dumps(message) + "\n").encode())
    await process.stdin.drain()
    return process


def _stops(*extra: str) -> list[Any]:
    """Every way of stopping: the impatient Ctrl-C (and stdin closing) in every run, the rest with -m slow."""
    quick = {"sigint-twice", *extra}
    stops = [*STOPS, *(stop for stop in extra if stop not in STOPS)]
    return [pytest.param(stop, marks=() if stop in quick else pytest.mark.slow) for stop in stops]


@pytest.mark.parametrize("stop", _stops("stdin-closed"))
async def test_stopping_the_stdio_server_cancels_the_goal_first(nav2: SimulatedRobot, stop: str) -> None:
    """stdio: each way of stopping cancels the running navigate_to goal on the robot before the exit."""
    process = await _start_stdio(nav2, "navigate_to", {"goal": GOAL})
    try:
        async with watching(nav2) as watcher:
            driven = nav2.nav2.robots[0]
            await nav2.wait_for(lambda _world: driven.linear > 0.1, WAIT)
            if stop == "stdin-closed":
                assert process.stdin is not None
                process.stdin.close()
            else:
                await _signal_group(process, STOPS[stop])
            await asyncio.wait_for(process.wait(), EXIT_WAIT)
            await _stopped_short(nav2, watcher)
    finally:
        if process.returncode is None:
            process.kill()
        await process.communicate()


async def test_a_stream_ends_with_its_zero_when_the_stdio_server_is_signalled_twice(
    make_sim: MakeSim,
) -> None:
    """A publish_topic stream on a velocity topic, Ctrl-C twice: a raw socket sees the stream end with an
    all-zero command before the process is gone, and nothing after it."""
    robot = await make_sim(dialect="ros2")
    async with websockets.connect(robot.url) as raw:
        await raw.send(json.dumps({"op": "subscribe", "topic": CMD_VEL, "type": TWIST}))
        seen: list[dict[str, Any]] = []
        process = await _start_stdio(robot, "publish_topic", FORWARD_STREAM)
        try:
            async with asyncio.timeout(WAIT):
                while len(seen) < 3:
                    frame = json.loads(await raw.recv())
                    if frame.get("op") == "publish":
                        seen.append(frame["msg"])
            await _signal_group(process, STOPS["sigint-twice"])
            await asyncio.wait_for(process.wait(), EXIT_WAIT)
        finally:
            if process.returncode is None:
                process.kill()
            await process.communicate()
        # What the bridge sent before the process was gone (it relays in order): ends with the zero.
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(1.0):
                while True:
                    frame = json.loads(await raw.recv())
                    if frame.get("op") == "publish":
                        seen.append(frame["msg"])
    assert seen[-1] == STILL, seen[-3:]
    assert seen[0] != STILL


@pytest.mark.parametrize("stop", _stops("sighup"))
async def test_stopping_the_http_server_cancels_the_goal_first(nav2: SimulatedRobot, stop: str) -> None:
    """Streamable HTTP: each signal to the group cancels the running navigate_to goal before the exit."""
    env = {**_env(None), "ROSBRIDGE_MCP_AUTH_TOKENS": TOKENS}
    served = await start_http("--url", nav2.url, env=env, new_group=True)
    process = served.process
    assert process is not None
    try:
        async with watching(nav2) as watcher:
            exited = await _signalled_while_driving(served.url, nav2, process, STOPS[stop])
            assert exited, f"no exit within {EXIT_WAIT:g} s: {''.join(served.stderr)[-2000:]}"
            await _stopped_short(nav2, watcher)
    finally:
        if process.returncode is None:
            process.kill()
        await process.wait()
        if served.drain is not None:
            with contextlib.suppress(BaseException):
                await asyncio.wait_for(served.drain, WAIT)


async def _signalled_while_driving(
    url: str, robot: SimulatedRobot, process: asyncio.subprocess.Process, signals: tuple[signal.Signals, ...]
) -> bool:
    """navigate_to over HTTP, the group signalled while the robot drives; whether the process exited in time.

    The client lives in a task of its own and is never closed before the process exits (closing the session,
    or cancelling the call, would alone cancel the goal: the server must do it); its errors as the server goes
    away are expected and stay in that task.
    """
    driving: asyncio.Future[None] = asyncio.get_running_loop().create_future()
    done = asyncio.Event()

    async def client() -> None:
        headers = {"Authorization": f"Bearer {TOKEN}"}
        async with (
            httpx2.AsyncClient(headers=headers, timeout=httpx2.Timeout(WAIT, read=300)) as http,
            Client(streamable_http_client(url, http_client=http), mode="legacy") as session,
        ):
            call = asyncio.create_task(session.call_tool("navigate_to", {"goal": GOAL}))
            driven = robot.nav2.robots[0]
            await robot.wait_for(lambda _world: driven.linear > 0.1 or call.done(), WAIT)
            driving.set_result(None) if not call.done() else driving.set_exception(
                AssertionError(call.result())
            )
            await done.wait()
            call.cancel()

    hosting = asyncio.create_task(client())
    try:
        await asyncio.wait_for(asyncio.shield(driving), WAIT)
        await _signal_group(process, signals)
        try:
            await asyncio.wait_for(process.wait(), EXIT_WAIT)
        except TimeoutError:
            return False
        return True
    finally:
        done.set()
        with contextlib.suppress(BaseException):
            await asyncio.wait_for(hosting, WAIT)
