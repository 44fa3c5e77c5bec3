"""Item 16: stops and reconnects on the simulated robot, as what reaches the robot shows them.

* ``stop_robot`` while a ``publish_topic`` velocity stream runs: the time to its answer, the time to the first
  zero command a raw subscriber of the velocity topic receives, and the non-zero commands that reach the
  robot after the answer (a marker, published on a raw socket once the answer came, divides before from
  after in the bridge's own order);
* ``stop_robot`` while a ``navigate_to`` goal drives the Nav2 world's robot: the time to its answer and to
  the first ``/odom`` that shows the robot standing still (the world publishes ``/odom`` at 20 Hz);
* the bridge (the simulated robot's process) killed and started again on the same port: the time from its
  port accepting connections again to a ``list_topics`` that succeeds, and every velocity command the new
  bridge receives (none may: one command went out before the outage, one was refused during it).

Every figure comes through the public ways in: the console script over MCP stdio (the SDK's client, which
can have a call running while another is made), the simulated robot as a process, raw rosbridge sockets.
The item starts its own simulated robots, also with --url (a real bridge is not killed, nor driven).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import signal
import time
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass, field
from typing import IO, Any

import mcp_types
from websockets.asyncio.client import ClientConnection, connect

from benchmarks.harness import (
    CMD_VEL,
    REPO,
    Context,
    Row,
    Served,
    Stats,
    free_port,
    log,
    our_server_command,
    serve_mcp,
    simulated_robot,
    simulated_robot_command,
    tail,
    timing_row,
    verdict,
    wait_for_port,
)

__all__: list[str] = []

#: A topic of the benchmark's own: published on a raw socket once an answer came, so that what the robot
#: receives after it in the bridge's order came after the answer.
MARKER = "/bench/stops_marker"
MARKER_TYPE = "std_msgs/msg/String"
TWIST = "geometry_msgs/msg/Twist"
ODOM = "/odom"
ODOM_TYPE = "nav_msgs/msg/Odometry"
STREAM_RATE = 10.0
MOVING = {"linear": {"x": 0.2}, "angular": {"z": 0.1}}
#: Two free places of the Nav2 world's map, 4.6 m apart: each press drives towards the other one.
NAV2_GOALS = ({"x": 2.5, "y": 7.5}, {"x": 3.0, "y": 3.0})
#: How long the bridge stays down in each outage, and how often a tool call asks after it is back.
OUTAGE_SECONDS = 1.0
RETRY_SECONDS = 0.05
#: docs/performance.md ("Hostile input and outages"): usable within 1 s of the bridge's return.
RECONNECT_TARGET = 1.0
#: After a stop's answer (or the first call that succeeds after an outage), the raw socket keeps watching
#: this long for commands that should not come.
AFTERWARDS = 0.5


def text_of(result: mcp_types.CallToolResult) -> str:
    return " ".join(getattr(block, "text", "") for block in result.content)


def is_zero(twist: dict[str, Any]) -> bool:
    return all(
        float(twist.get(part, {}).get(axis, 0.0)) == 0.0
        for part in ("linear", "angular")
        for axis in ("x", "y", "z")
    )


@dataclass
class Arrival:
    at: float
    topic: str
    msg: dict[str, Any]


def twist(odometry: Arrival) -> dict[str, Any]:
    found: dict[str, Any] = odometry.msg.get("twist", {}).get("twist", {})
    return found


def speed(odometry: Arrival) -> float:
    return float(twist(odometry).get("linear", {}).get("x", 0.0))


def marked(mark: str) -> Callable[[list[Arrival]], bool]:
    """Whether the marker ``mark`` is among the messages."""
    return lambda seen: any(arrival.msg.get("data") == mark for arrival in seen)


def still_after(moment: float) -> Callable[[list[Arrival]], bool]:
    """Whether an odometry message read after ``moment`` shows the robot standing still."""
    return lambda seen: any(arrival.at >= moment and is_zero(twist(arrival)) for arrival in seen)


@dataclass
class Watcher:
    """A raw rosbridge socket on the robot's side that notes every message of its topics, in the bridge's
    order, with the moment it was read."""

    ws: ClientConnection
    arrivals: list[Arrival] = field(default_factory=list)
    changed: asyncio.Event = field(default_factory=asyncio.Event)
    _ids: int = 0
    _replies: set[str] = field(default_factory=set)

    async def subscribe(self, topic: str, msg_type: str) -> None:
        await self.ws.send(
            json.dumps({"op": "subscribe", "id": f"w:{topic}", "topic": topic, "type": msg_type})
        )

    async def barrier(self) -> None:
        """A service call on this socket: its reply comes after the bridge handled everything sent before."""
        self._ids += 1
        request_id = f"w:barrier:{self._ids}"
        await self.ws.send(
            json.dumps({"op": "call_service", "id": request_id, "service": "/rosapi/get_time", "args": {}})
        )
        await self.wait_for(lambda: request_id in self._replies, 10)

    async def listen(self) -> None:
        async for frame in self.ws:
            message = json.loads(frame)
            if message.get("op") == "publish":
                self.arrivals.append(Arrival(time.perf_counter(), message["topic"], message["msg"]))
            elif message.get("op") == "service_response":
                self._replies.add(str(message.get("id")))
            self.changed.set()

    async def wait_for(self, ready: Callable[[], bool], timeout: float) -> None:
        async with asyncio.timeout(timeout):
            while not ready():
                self.changed.clear()
                await self.changed.wait()

    def since(self, index: int, topic: str) -> list[Arrival]:
        return [arrival for arrival in self.arrivals[index:] if arrival.topic == topic]

    async def seen(
        self, index: int, topic: str, test: Callable[[list[Arrival]], bool], timeout: float = 10
    ) -> None:
        """Wait until ``test`` holds for the messages of ``topic`` read since ``index``."""
        await self.wait_for(lambda: test(self.since(index, topic)), timeout)


@contextlib.asynccontextmanager
async def watching(url: str, topics: dict[str, str]) -> AsyncIterator[Watcher]:
    async with connect(url, max_size=None, compression=None) as ws:
        watcher = Watcher(ws)
        listener = asyncio.create_task(watcher.listen())
        try:
            for topic, msg_type in topics.items():
                await watcher.subscribe(topic, msg_type)
            await watcher.barrier()  # the subscriptions are in place
            yield watcher
        finally:
            listener.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await listener


async def call(served: Served, tool: str, arguments: dict[str, Any]) -> mcp_types.CallToolResult:
    return await served.session.call_tool(tool, arguments)


async def ok(served: Served, tool: str, arguments: dict[str, Any]) -> mcp_types.CallToolResult:
    result = await call(served, tool, arguments)
    if result.is_error:
        raise RuntimeError(f"{tool} {json.dumps(arguments)} answered with an error: {text_of(result)}")
    return result


async def measure_stops(ctx: Context) -> list[Row]:
    """Item 16: stop_robot with a velocity stream running, stop_robot with a navigate_to goal running, and
    the bridge killed and started again on its port. Item 13 already times ``diagnose``."""
    full = ctx.plan.name == "full"
    rows = await _estop_rows(ctx, presses=20 if full else 3)
    rows += await _navigate_rows(ctx, presses=10 if full else 2)
    rows += await _reconnect_rows(ctx, outages=5 if full else 2)
    return rows


# ------------------------------------------------------------------------------ stop_robot, a stream running


async def _estop_rows(ctx: Context, presses: int) -> list[Row]:
    answers: list[float] = []
    zeros: list[float] = []
    after: list[int] = []  # non-zero commands the robot received after each answer
    late_zeros = 0  # zeros after the answer (harmless, but the answer should come after them)
    sent = 0
    async with contextlib.AsyncExitStack() as stack:
        url = await stack.enter_async_context(simulated_robot(ctx.errlog))
        served = await stack.enter_async_context(serve_mcp(our_server_command(url), ctx.errlog))
        watcher = await stack.enter_async_context(watching(url, {CMD_VEL: TWIST, MARKER: MARKER_TYPE}))
        publisher = await stack.enter_async_context(connect(url, max_size=None, compression=None))
        await publisher.send(json.dumps({"op": "advertise", "id": "m", "topic": MARKER, "type": MARKER_TYPE}))
        await ok(served, "list_topics", {})  # the server is connected
        stream_arguments = {
            "topic": CMD_VEL,
            "message_type": TWIST,
            "message": MOVING,
            "rate_hz": STREAM_RATE,
            "duration": 25.0,
        }
        for press in range(presses):
            start = len(watcher.arrivals)
            stream = asyncio.create_task(call(served, "publish_topic", stream_arguments))
            await watcher.seen(start, CMD_VEL, lambda seen: sum(not is_zero(a.msg) for a in seen) >= 3)
            began = time.perf_counter()
            answer = await ok(served, "stop_robot", {})
            answered = time.perf_counter()
            stopped = answer.structured_content or {}
            if CMD_VEL not in str(stopped.get("streams_stopped", "")):
                raise RuntimeError(f"stop_robot did not name the stream: {text_of(answer)}")
            await publisher.send(json.dumps({"op": "publish", "topic": MARKER, "msg": {"data": f"{press}"}}))
            ended = await asyncio.wait_for(stream, 10)
            if "stop_robot" not in text_of(ended):
                raise RuntimeError(f"the stream's answer does not say stop_robot ended it: {text_of(ended)}")
            await watcher.seen(start, MARKER, marked(f"{press}"))
            # The window after the answer: a command that came late would be read within it.
            await asyncio.sleep(AFTERWARDS)
            await watcher.barrier()
            window = watcher.arrivals[start:]
            marker = next(
                i for i, a in enumerate(window) if a.topic == MARKER and a.msg.get("data") == f"{press}"
            )
            commands = [a for a in window if a.topic == CMD_VEL]
            sent += len(commands)
            first_zero = next((a.at for a in commands if a.at >= began and is_zero(a.msg)), None)
            if first_zero is None:
                raise RuntimeError(f"press {press + 1}: no zero command reached the robot")
            answers.append(answered - began)
            zeros.append(first_zero - began)
            later = [a for a in window[marker:] if a.topic == CMD_VEL]
            after.append(sum(not is_zero(a.msg) for a in later))
            late_zeros += sum(is_zero(a.msg) for a in later)
    what = f"`stop_robot`, a {STREAM_RATE:g} Hz `publish_topic` stream on {CMD_VEL} running"
    rows = [
        timing_row("16a", f"{what}: sent → its answer", Stats.of(answers), target="info", verdict="info"),
        timing_row(
            "16b",
            f"{what}: sent → the first zero a raw subscriber of {CMD_VEL} receives",
            Stats.of(zeros),
            target="info",
            verdict="info",
        ),
    ]
    total_after = sum(after)
    row = Row(
        "16c",
        f"{what}: non-zero commands reaching the robot after the answer (in the bridge's order, a marker "
        f"published once the answer came; {sent} commands received in all, zeros after it: {late_zeros})",
        n=presses,
        median=f"{total_after} in {presses} presses",
        target="0 (docs/safety.md: nothing of what ran before reaches the robot after the answer)",
        verdict=verdict(total_after == 0),
    )
    row.figures.update(after=after, late_zeros=late_zeros, received=sent)
    rows.append(row)
    ctx.samples.update(stops_estop_answer=answers, stops_estop_zero=zeros)
    return rows


# ------------------------------------------------------------------------- stop_robot, a navigate_to running


async def _navigate_rows(ctx: Context, presses: int) -> list[Row]:
    answers: list[float] = []
    still: list[float] = []
    first_still = 0  # presses whose first /odom after the press already stood still
    async with contextlib.AsyncExitStack() as stack:
        url = await stack.enter_async_context(simulated_robot(ctx.errlog, world="nav2"))
        served = await stack.enter_async_context(serve_mcp(our_server_command(url), ctx.errlog))
        watcher = await stack.enter_async_context(watching(url, {ODOM: ODOM_TYPE}))
        await ok(served, "list_topics", {})

        for press in range(presses):
            start = len(watcher.arrivals)
            goal = NAV2_GOALS[press % 2]
            drive = asyncio.create_task(call(served, "navigate_to", {"goal": goal}))
            driving = asyncio.create_task(
                watcher.seen(start, ODOM, lambda seen: any(speed(a) > 0.1 for a in seen), timeout=30)
            )
            done, _ = await asyncio.wait({drive, driving}, return_when=asyncio.FIRST_COMPLETED)
            if drive in done:
                driving.cancel()
                early = text_of(drive.result())
                raise RuntimeError(f"navigate_to {goal} answered before the robot drove: {early}")
            await driving
            began = time.perf_counter()
            await ok(served, "stop_robot", {})
            answered = time.perf_counter()
            await watcher.seen(start, ODOM, still_after(began))
            after_press = [a for a in watcher.since(start, ODOM) if a.at >= began]
            stood = next(a.at for a in after_press if is_zero(twist(a)))
            first_still += is_zero(twist(after_press[0]))
            result = await asyncio.wait_for(drive, 10)
            data = result.structured_content or {}
            if data.get("succeeded") or data.get("canceled_by") != "stop_robot":
                raise RuntimeError(f"navigate_to was not ended by stop_robot: {text_of(result)}")
            answers.append(answered - began)
            still.append(stood - began)
    what = "`stop_robot`, a `navigate_to` goal driving the Nav2 world's robot"
    ctx.samples.update(stops_navigate_answer=answers, stops_navigate_still=still)
    return [
        timing_row("16d", f"{what}: sent → its answer", Stats.of(answers), target="info", verdict="info"),
        timing_row(
            "16e",
            f"{what}: sent → the first {ODOM} standing still on a raw socket (published at 20 Hz; the press "
            f"follows an {ODOM} that showed it driving, so the next comes one period later)",
            Stats.of(still),
            versus=f"the first {ODOM} after the press stood still in {first_still} of {presses}",
            target="info",
            verdict="info",
        ),
    ]


# --------------------------------------------------------------------------------------- the bridge restarted


class Restartable:
    """The simulated robot as a process of its own on a fixed port, killed and started again."""

    def __init__(self, errlog: IO[str]) -> None:
        self.port = free_port()
        self.url = f"ws://127.0.0.1:{self.port}"
        self._errlog = errlog
        self._process: asyncio.subprocess.Process | None = None

    async def start(self) -> None:
        command = simulated_robot_command(self.port)
        self._process = process = await asyncio.create_subprocess_exec(
            *command, stdin=asyncio.subprocess.DEVNULL, stdout=self._errlog, stderr=self._errlog, cwd=REPO
        )
        try:
            await wait_for_port("127.0.0.1", self.port, process, asyncio.get_running_loop().time() + 30)
        except (RuntimeError, TimeoutError) as error:
            raise RuntimeError(f"{error}; the end of its stderr:\n{tail(self._errlog)}") from None

    async def kill(self) -> None:
        if self._process is not None and self._process.returncode is None:
            self._process.send_signal(signal.SIGKILL)
            await self._process.wait()


async def _reconnect_rows(ctx: Context, outages: int) -> list[Row]:
    back: list[float] = []
    down_calls: list[float] = []
    replayed = 0
    refused_while_down = 0
    watcher_first = 0  # outages whose raw socket was subscribed before the first call succeeded
    robot = Restartable(ctx.errlog)
    await robot.start()
    try:
        async with serve_mcp(our_server_command(robot.url), ctx.errlog) as served:
            await ok(served, "list_topics", {})
            for outage in range(outages):
                # One command the bridge takes before the outage.
                before = {"linear": {"x": 0.11 + outage / 1000}}
                await ok(
                    served, "publish_topic", {"topic": CMD_VEL, "message_type": TWIST, "message": before}
                )
                await robot.kill()
                # One command while the bridge is down: it must fail now, not wait for the bridge's return.
                began = time.perf_counter()
                refused = await call(
                    served,
                    "publish_topic",
                    {"topic": CMD_VEL, "message_type": TWIST, "message": {"linear": {"x": 0.12}}},
                )
                down_calls.append(time.perf_counter() - began)
                refused_while_down += refused.is_error
                await asyncio.sleep(OUTAGE_SECONDS)  # the outage itself
                await robot.start()
                returned = time.perf_counter()
                # The raw socket on the new bridge is put in place while the server calls.
                async with watching(robot.url, {CMD_VEL: TWIST}) as watcher:
                    watched = time.perf_counter()
                    # A tool call is what is measured: it is asked again until it succeeds (each fails fast).
                    while (await call(served, "list_topics", {})).is_error:  # noqa: ASYNC110
                        await asyncio.sleep(RETRY_SECONDS)
                    back.append(time.perf_counter() - returned)
                    watcher_first += watched - returned < back[-1]
                    await asyncio.sleep(AFTERWARDS)  # the window a replay would show in
                    await watcher.barrier()
                    replayed += len(watcher.since(0, CMD_VEL))
    finally:
        await robot.kill()
    log.info("reconnect: %d of %d calls during the outages failed", refused_while_down, outages)
    what = f"the bridge killed, {OUTAGE_SECONDS:g} s down, started again on its port"
    row = timing_row(
        "16f",
        f"{what}: its port accepting again → `list_topics` succeeding "
        f"(asked every {RETRY_SECONDS * 1e3:g} ms)",
        Stats.of(back),
        versus=f"a `publish_topic` while down failed in {Stats.of(down_calls).median * 1e3:.1f} ms (median)",
        target=f"every one ≤ {RECONNECT_TARGET:g} s (docs/performance.md, outages)",
    )
    row.verdict = verdict(max(back) <= RECONNECT_TARGET)
    replay = Row(
        "16g",
        f"{what}: velocity commands the new bridge receives (one sent before each outage, one refused during "
        f"it: {refused_while_down} of {outages} refused; the raw socket subscribed before the first success "
        f"in {watcher_first} of {outages})",
        n=outages,
        median=f"{replayed} in {outages} outages",
        target="0, and every call while down refused",
        verdict=verdict(replayed == 0 and refused_while_down == outages),
    )
    replay.figures.update(
        replayed=replayed,
        refused_while_down=refused_while_down,
        watcher_first=watcher_first,
        down_call_s=down_calls,
    )
    ctx.samples.update(stops_reconnect=back)
    return [row, replay]
