"""E-STOP races as a user runs them: an MCP client drives a stream and a goal, the console's E-STOP (over
HTTP, with the secret) is pressed the moment the console's audit shows a call allowed, and what reaches the
robot is watched on the robot itself and on a raw rosbridge socket.

* :class:`DelayingProxy` sits between the server and the bridge and holds every TCP chunk ``delay`` seconds
  each way (order kept): a slow link, as a robot on Wi-Fi has;
* :func:`race_console` is ``console_harness.served_console`` (the server as ``serve --console`` wires it,
  with an MCP client session) with its rosbridge client going through the proxy, a raw socket watching the
  robot and the moment the console's audit shows a call allowed;
* :func:`run_race` presses E-STOP during a 10 Hz ``publish_topic`` stream and a ``publish_action`` goal and
  counts the velocity commands and the goal progress the robot got after E-STOP answered.

"After E-STOP answered" is measured twice. On the simulated robot: messages it received (``received_at``)
after the moment the E-STOP's HTTP answer came, and goal feedback counted after it. On a raw rosbridge socket
straight to the robot (no proxy), subscribed to the velocity topic and to a marker topic: right after the
answer another raw socket publishes a marker; a command the watcher sees after the marker reached the robot
after E-STOP answered.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import urlsplit

import websockets
from console_harness import Console, served_console, text_of

from mcp import Client
from rosbridge_mcp_server.safety import AuditEntry, Policy
from rosbridge_mcp_server.sim import World

CMD_VEL = "/turtle1/cmd_vel"
MARKER = "/estop_race_marker"
FIB = "/fibonacci"
WAIT = 15.0


def types_of(dialect: str) -> dict[str, str]:
    if dialect == "ros2":
        return {
            "twist": "geometry_msgs/msg/Twist",
            "string": "std_msgs/msg/String",
            "fibonacci": "example_interfaces/action/Fibonacci",
            # rosbridge 2.x lets a client subscribe to an action's hidden feedback topic.
            "feedback_topic": f"{FIB}/_action/feedback",
            "feedback": "example_interfaces/action/Fibonacci_FeedbackMessage",
        }
    return {
        "twist": "geometry_msgs/Twist",
        "string": "std_msgs/String",
        "fibonacci": "actionlib_tutorials/FibonacciAction",
        "feedback_topic": f"{FIB}/feedback",
        "feedback": "actionlib_tutorials/FibonacciActionFeedback",
    }


def moving(message: dict[str, Any]) -> bool:
    """Whether a Twist asks for motion (the stream's and E-STOP's closing zeros do not)."""
    return any(
        message.get(part, {}).get(axis, 0) != 0 for part in ("linear", "angular") for axis in ("x", "y", "z")
    )


class DelayingProxy:
    """A TCP proxy on 127.0.0.1 that delivers every chunk ``delay`` seconds after it came, each way."""

    def __init__(self, target_url: str, delay: float) -> None:
        parts = urlsplit(target_url)
        assert parts.hostname is not None
        assert parts.port is not None
        self._target = (parts.hostname, parts.port)
        self._path = parts.path
        self.delay = delay
        self._server: asyncio.Server | None = None
        self._tasks: set[asyncio.Task[None]] = set()
        self._writers: list[asyncio.StreamWriter] = []

    @property
    def url(self) -> str:
        assert self._server is not None
        port = self._server.sockets[0].getsockname()[1]
        return f"ws://127.0.0.1:{port}{self._path}"

    async def __aenter__(self) -> DelayingProxy:
        self._server = await asyncio.start_server(self._serve, "127.0.0.1", 0)
        return self

    async def __aexit__(self, *exc: object) -> None:
        assert self._server is not None
        self._server.close()
        for writer in self._writers:
            writer.close()
        for task in list(self._tasks):
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        await self._server.wait_closed()

    async def _serve(self, down_reader: asyncio.StreamReader, down_writer: asyncio.StreamWriter) -> None:
        try:
            up_reader, up_writer = await asyncio.open_connection(*self._target)
        except OSError:
            down_writer.close()
            return
        self._writers += [down_writer, up_writer]
        for reader, writer in ((down_reader, up_writer), (up_reader, down_writer)):
            queue: asyncio.Queue[tuple[float, bytes]] = asyncio.Queue()
            for job in (self._read(reader, queue), self._write(queue, writer)):
                task = asyncio.create_task(job)
                self._tasks.add(task)
                task.add_done_callback(self._tasks.discard)

    async def _read(self, reader: asyncio.StreamReader, queue: asyncio.Queue[tuple[float, bytes]]) -> None:
        loop = asyncio.get_running_loop()
        with contextlib.suppress(OSError):
            while chunk := await reader.read(65536):
                queue.put_nowait((loop.time() + self.delay, chunk))
        queue.put_nowait((loop.time() + self.delay, b""))

    async def _write(self, queue: asyncio.Queue[tuple[float, bytes]], writer: asyncio.StreamWriter) -> None:
        loop = asyncio.get_running_loop()
        with contextlib.suppress(OSError):
            while True:
                due, chunk = await queue.get()
                # The link's delay itself (not a wait for something to happen).
                await asyncio.sleep(max(0.0, due - loop.time()))
                if not chunk:
                    break
                writer.write(chunk)
                await writer.drain()
        writer.close()


@dataclass
class Watcher:
    """A raw rosbridge socket on the robot: every frame on the velocity and marker topics, in order."""

    frames: list[tuple[str, dict[str, Any]]] = field(default_factory=list)
    changed: asyncio.Event = field(default_factory=asyncio.Event)

    def seen(self, topic: str, marker: str | None = None) -> bool:
        return any(t == topic and (marker is None or m.get("data") == marker) for t, m in self.frames)

    async def wait_marker(self, marker: str) -> None:
        async with asyncio.timeout(WAIT):
            while not self.seen(MARKER, marker):
                self.changed.clear()
                await self.changed.wait()

    def after(self, marker: str) -> list[tuple[str, dict[str, Any]]]:
        index = next(i for i, (t, m) in enumerate(self.frames) if t == MARKER and m.get("data") == marker)
        return self.frames[index + 1 :]

    def moving_after(self, marker: str) -> int:
        """Commands asking for motion that the watcher saw after *marker*."""
        return sum(1 for t, m in self.after(marker) if t == CMD_VEL and moving(m))

    def feedback_after(self, marker: str) -> int:
        """Goal feedback messages (any goal's) that the watcher saw after *marker*."""
        return sum(1 for t, _ in self.after(marker) if t not in (CMD_VEL, MARKER))


@dataclass
class RaceConsole:
    """The served console and its MCP session, with what the races watch it by."""

    dialect: str
    world: World | None  #: the simulated robot's own record; None on a real bridge
    console: Console
    watcher: Watcher
    marker_socket: Any
    allowed: asyncio.Event  #: set when the console's audit shows a call allowed
    observe: float
    marks: int = 0

    @property
    def mcp(self) -> Client:
        return self.console.mcp

    async def mark(self) -> str:
        """Publish a marker through the raw socket and wait until the watcher has seen it."""
        self.marks += 1
        marker = f"mark {self.marks}"
        await self.marker_socket.send(json.dumps({"op": "publish", "topic": MARKER, "msg": {"data": marker}}))
        await self.watcher.wait_marker(marker)
        return marker


@asynccontextmanager
async def race_console(
    robot_url: str,
    dialect: str,
    delay: float,
    *,
    world: World | None = None,
    observe: float = 0.3,
    policy: Policy | None = None,
) -> AsyncIterator[RaceConsole]:
    """The server, its console and an MCP session, with the rosbridge link delayed *delay* s each way.

    *world* is the simulated robot's (None on a real bridge: only the raw socket watches then); *observe* is
    how long each race watches for what must not come after E-STOP answered.
    """
    types = types_of(dialect)
    async with contextlib.AsyncExitStack() as stack:
        url = robot_url
        if delay > 0:
            url = (await stack.enter_async_context(DelayingProxy(robot_url, delay))).url
        watcher = Watcher()
        raw = await stack.enter_async_context(websockets.connect(robot_url))
        watched = [(CMD_VEL, types["twist"]), (MARKER, types["string"])]
        watched.append((types["feedback_topic"], types["feedback"]))
        for topic, type_name in watched:
            await raw.send(json.dumps({"op": "subscribe", "topic": topic, "type": type_name}))

        async def watch() -> None:
            async for frame in raw:
                message = json.loads(frame)
                if message.get("op") == "publish":
                    watcher.frames.append((message["topic"], message["msg"]))
                    watcher.changed.set()

        watching = asyncio.create_task(watch())
        stack.callback(watching.cancel)
        marker_socket = await stack.enter_async_context(websockets.connect(robot_url))
        await marker_socket.send(json.dumps({"op": "advertise", "topic": MARKER, "type": types["string"]}))

        console = await stack.enter_async_context(
            served_console(url, policy, request_timeout=10.0, connect_timeout=5.0, connect_wait=WAIT)
        )
        allowed = asyncio.Event()

        def on_audit(entry: AuditEntry) -> None:
            # What the console shows: the moment a call is allowed, the person presses E-STOP.
            if entry["outcome"] in ("allowed", "confirmed") and entry["tool"] != "console":
                allowed.set()

        console.audit.listen(on_audit)
        race = RaceConsole(dialect, world, console, watcher, marker_socket, allowed, observe)
        # The subscriptions are live once a first marker comes back.
        async with asyncio.timeout(WAIT):
            while True:
                with contextlib.suppress(TimeoutError):
                    async with asyncio.timeout(0.5):
                        await race.mark()
                        break
        yield race


@dataclass
class RaceResult:
    """What one race did, measured on the robot."""

    estop: dict[str, Any]  #: the console's E-STOP answer for the robot
    commands_after: int  #: motion commands the robot received after E-STOP answered
    watcher_commands_after: int  #: the same, as the raw socket saw them (after the marker)
    goal_progress_after: int  #: goal feedback steps, and goals accepted, after E-STOP answered
    watcher_feedback_after: int  #: goal feedback the raw socket saw after the marker
    commands_before: int  #: motion commands of this race the robot received before E-STOP answered
    goal_ran_before: bool  #: the race's goal had reached the robot before E-STOP answered
    stream_text: str
    goal_text: str
    stream_error: bool
    goal_error: bool


async def run_race(
    race: RaceConsole, *, press_after: float = 0.0, goal: bool = True, press_when_running: bool = False
) -> RaceResult:
    """Start a 10 Hz velocity stream (and a goal), press E-STOP *press_after* s after the console first shows
    one of them allowed (with *press_when_running*, once the simulated robot has both the stream's commands
    and the goal, however long a busy machine takes), then measure; the latch is released at the end."""
    types = types_of(race.dialect)
    world = race.world
    race.allowed.clear()
    goals_before = set(world.goals) if world is not None else set()
    started = time.monotonic()
    stream_call = asyncio.create_task(
        race.mcp.call_tool(
            "publish_topic",
            {
                "topic": CMD_VEL,
                "message_type": types["twist"],
                "message": {"linear": {"x": 1.0}},
                "rate_hz": 10,
                "duration": 3,
            },
        )
    )
    goal_call = (
        asyncio.create_task(
            race.mcp.call_tool(
                "publish_action",
                {
                    "action_name": FIB,
                    "action_type": types["fibonacci"],
                    "goal": {"order": 40},
                    "timeout": 10,
                },
            )
        )
        if goal
        else None
    )
    async with asyncio.timeout(WAIT):
        await race.allowed.wait()
    if press_after > 0:
        # Where in the calls' lives the press lands (approval, ping, first messages, goal start).
        await asyncio.sleep(press_after)
    if press_when_running and world is not None:

        def running(w: World) -> bool:
            driven = any(m.received_at > started and moving(m.msg) for m in w.published.get(CMD_VEL, ()))
            return driven and bool(set(w.goals) - goals_before)

        await world.wait_for(running, WAIT)
    status, answer = await race.console.post("/api/estop")
    answered = time.monotonic()
    assert status == 200, answer
    goals_then = world.goals if world is not None else {}
    progress_then = {gid: record.feedback_count for gid, record in goals_then.items()}
    marker = await race.mark()
    async with asyncio.timeout(WAIT):
        stream_result = await stream_call
        goal_result = await goal_call if goal_call is not None else None
    # An observation window for what must NOT happen: a simulated goal steps every 50 ms (a real one each
    # second: give *observe* to suit) and the stream is 10 Hz, so anything still running would show here.
    await asyncio.sleep(race.observe)
    await race.mark()
    published = world.published.get(CMD_VEL, ()) if world is not None else ()
    commands_after = sum(1 for m in published if m.received_at > answered and moving(m.msg))
    commands_before = sum(1 for m in published if started < m.received_at <= answered and moving(m.msg))
    progress_after = 0
    for gid, record in goals_then.items():
        if gid not in progress_then:
            progress_after += 1 + record.feedback_count  # a goal the robot took after E-STOP answered
        else:
            progress_after += record.feedback_count - progress_then[gid]
    status, released = await race.console.post("/api/release")
    assert status == 200, released
    return RaceResult(
        estop=answer["robots"][0],
        commands_after=commands_after,
        watcher_commands_after=race.watcher.moving_after(marker),
        goal_progress_after=progress_after,
        watcher_feedback_after=race.watcher.feedback_after(marker),
        commands_before=commands_before,
        goal_ran_before=bool(set(progress_then) - goals_before),
        stream_text=text_of(stream_result),
        goal_text=text_of(goal_result) if goal_result is not None else "",
        stream_error=stream_result.is_error,
        goal_error=bool(goal_result is not None and goal_result.is_error),
    )
