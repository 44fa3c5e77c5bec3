"""Long work as MCP tasks (``server/tasks.py``) on the 2026-07-28 protocol, through the SDK's own client.

The client advertises the tasks extension (``mcp.client.extension``) and gets the task through
``call_tool(..., allow_claimed=True)``; then ``tasks/get`` is polled until the end, ``tasks/cancel`` cancels,
``tasks/update`` answers a confirmation (requests sent with the session's ``send_request``). The robot is the
simulated Nav2 world in both ROS dialects; a raw rosbridge socket sees what reaches it. The 2025-11-25 dialect
(which the SDK's client refuses to read as a tools/call answer) is tested over stdio (test_tasks_stdio.py).
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import json
import math
from collections.abc import AsyncIterator, Awaitable, Callable, Iterable
from pathlib import Path
from typing import Any, Literal

import pytest
import websockets
from mcp.client.extension import ClaimContext, ClientExtension, ResultClaim
from mcp.client.session import ClientRequestContext
from mcp.types import (
    CallToolResult,
    CancelTaskRequest,
    CancelTaskRequestParams,
    ElicitRequestParams,
    ElicitResult,
    GetTaskRequest,
    GetTaskRequestParams,
    ImageContent,
    Request,
    RequestParams,
    Result,
    TextContent,
)
from mcp_harness import Session, open_session
from pydantic import ConfigDict, TypeAdapter

from mcp import Client, MCPError
from rosbridge_mcp_server.console.hub import ConsoleHub, RobotView
from rosbridge_mcp_server.safety import Audit, Operator, emergency_stop, parse_policy
from rosbridge_mcp_server.server.fleet import Fleet
from rosbridge_mcp_server.server.tasks import TaskBoard
from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]

TASKS = "io.modelcontextprotocol/tasks"
TEST_SPEED = 8.0
POLICY = {"navigation": {"max_goal_distance": 12.0}}
#: What a poll waits at most for a state (the sim drives 8 times faster than a robot).
POLL_WAIT = 30.0
_ANY = TypeAdapter(dict[str, Any])


class CreatedTask(Result):
    """A 2026-07-28 ``CreateTaskResult`` as the client parses it."""

    model_config = ConfigDict(extra="allow")
    result_type: Literal["task"] = "task"
    task_id: str
    status: str


class TasksAd(ClientExtension):
    """The tasks extension, as a client that follows tasks itself (claimed results handed back)."""

    identifier = TASKS

    def claims(self) -> list[ResultClaim[Any]]:
        async def resolve(created: CreatedTask, ctx: ClaimContext) -> CallToolResult:
            raise AssertionError("the tests poll the task themselves")

        return [ResultClaim(result_type="task", model=CreatedTask, resolve=resolve)]


@pytest.fixture(params=["ros2", "ros1"])
async def nav2(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    robot = await make_sim(dialect=request.param, world="nav2")
    robot.nav2.navigator.speed = TEST_SPEED
    return robot


class UpdateParams(RequestParams):
    task_id: str
    input_responses: dict[str, Any]


class UpdateTaskRequest(Request[UpdateParams, Literal["tasks/update"]]):
    method: Literal["tasks/update"] = "tasks/update"
    params: UpdateParams


@contextlib.asynccontextmanager
async def tasks_session(robot: SimulatedRobot, **kwargs: Any) -> AsyncIterator[Session]:
    """A 2026-07-28 session whose client advertises the tasks extension, under the server's own guard."""
    policy = kwargs.pop("policy", POLICY)
    async with open_session(
        robot.url,
        guard=None,
        policy=parse_policy(policy, where="test.toml"),
        mode="auto",
        extensions=(TasksAd(),),
        **kwargs,
    ) as opened:
        yield opened


async def start_task(mcp: Client, name: str, arguments: dict[str, Any]) -> str:
    """Call *name*; the call must come back as a task at once: its id."""
    created = await mcp.session.call_tool(name, arguments, allow_claimed=True)
    assert isinstance(created, CreatedTask), created
    assert created.status == "working"
    return created.task_id


async def get_task(mcp: Client, task_id: str) -> dict[str, Any]:
    return await mcp.session.send_request(GetTaskRequest(params=GetTaskRequestParams(task_id=task_id)), _ANY)


async def cancel_task(mcp: Client, task_id: str) -> dict[str, Any]:
    request = CancelTaskRequest(params=CancelTaskRequestParams(task_id=task_id))
    return await mcp.session.send_request(request, _ANY)


async def poll(
    mcp: Client,
    task_id: str,
    until: Callable[[dict[str, Any]], bool],
    seen: list[dict[str, Any]] | None = None,
) -> dict[str, Any]:
    """``tasks/get`` until *until* holds (bounded); every answer is added to *seen*."""
    async with asyncio.timeout(POLL_WAIT):
        while True:
            shown = await get_task(mcp, task_id)
            if seen is not None:
                seen.append(shown)
            if until(shown):
                return shown
            await asyncio.sleep(0.05)  # the client's poll interval (shorter than the server's hint)


def ended(shown: dict[str, Any]) -> bool:
    return shown["status"] in ("completed", "failed", "cancelled")


def result_text(shown: dict[str, Any]) -> str:
    result = CallToolResult.model_validate(shown["result"])
    return "\n".join(block.text for block in result.content if isinstance(block, TextContent))


def status_topic(robot: SimulatedRobot) -> tuple[str, str, int]:
    """The navigator's goal status list on the wire, and the status a cancelled goal ends in."""
    if robot.dialect == "ros1":
        return "/move_base/status", "actionlib_msgs/GoalStatusArray", 2  # PREEMPTED
    return "/navigate_to_pose/_action/status", "action_msgs/msg/GoalStatusArray", 5  # CANCELED


class Statuses:
    """Goal statuses seen on the wire, and a wait for one."""

    def __init__(self) -> None:
        self.seen: set[int] = set()
        self.changed = asyncio.Event()

    def add(self, statuses: Iterable[int]) -> None:
        self.seen.update(statuses)
        self.changed.set()

    async def wait_for(self, status: int) -> None:
        async with asyncio.timeout(10.0):
            while status not in self.seen:
                self.changed.clear()
                await self.changed.wait()


@contextlib.asynccontextmanager
async def watching_statuses(robot: SimulatedRobot) -> AsyncIterator[Statuses]:
    """Every goal status a raw rosbridge subscriber on its own socket sees."""
    topic, kind, _ = status_topic(robot)
    seen = Statuses()
    async with websockets.connect(robot.url) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": topic, "type": kind}))

        async def read() -> None:
            async for raw in ws:
                frame = json.loads(raw)
                if frame.get("op") == "publish" and frame.get("topic") == topic:
                    seen.add(int(entry["status"]) for entry in frame["msg"].get("status_list", []))

        reader = asyncio.create_task(read())
        try:
            yield seen
        finally:
            reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reader


async def test_a_drive_runs_as_a_task_polled_to_its_end_and_its_answer_is_kept(nav2: SimulatedRobot) -> None:
    """The call answers with a task at once; tasks/get shows the distance left while it drives; the
    answer (text, structured content and the picture) is there at the end and still after it."""
    async with tasks_session(nav2) as session:
        task_id = await start_task(session.mcp, "navigate_to", {"goal": {"x": 2.5, "y": 7.5, "yaw": 90}})
        seen: list[dict[str, Any]] = []
        final = await poll(session.mcp, task_id, ended, seen)
        again = await get_task(session.mcp, task_id)
    assert final["status"] == "completed", final
    assert any("m to go" in shown.get("statusMessage", "") for shown in seen), seen
    assert final["statusMessage"].startswith("navigate_to ended: ")
    result = CallToolResult.model_validate(again["result"])
    assert (result.structured_content or {})["succeeded"], result_text(again)
    assert "drove" in result_text(again)
    assert any(isinstance(block, ImageContent) for block in result.content)
    robot = nav2.nav2.robots[0]
    assert math.hypot(robot.x - 2.5, robot.y - 7.5) < 0.2
    assert again["ttlMs"] > 0
    assert again["pollIntervalMs"] > 0


async def test_tasks_cancel_cancels_the_goal_on_the_robot(nav2: SimulatedRobot) -> None:
    """tasks/cancel ends the drive: the raw socket sees the goal cancelled, the robot stops short, and the
    task says what was stopped."""
    robot = nav2.nav2.robots[0]
    _, _, cancelled = status_topic(nav2)
    async with tasks_session(nav2) as session, watching_statuses(nav2) as statuses:
        task_id = await start_task(session.mcp, "navigate_to", {"goal": {"x": 1.5, "y": 9.0}})
        await nav2.wait_for(lambda world: robot.linear > 0.1, timeout=10.0)
        ack = await cancel_task(session.mcp, task_id)
        assert ack.get("resultType") == "complete"
        shown = await poll(session.mcp, task_id, ended)
        await nav2.wait_for(lambda world: robot.linear == 0.0 and robot.angular == 0.0, timeout=10.0)
        await statuses.wait_for(cancelled)
    assert shown["status"] == "cancelled"
    assert "Cancelled by the client (tasks/cancel)" in shown["statusMessage"]
    assert "goal was cancelled" in shown["statusMessage"]
    assert math.hypot(robot.x - 1.5, robot.y - 9.0) > 0.5


@pytest.mark.parametrize("by", ["stop_robot", "console"])
async def test_a_stop_ends_a_task_and_its_status_says_who(nav2: SimulatedRobot, by: str) -> None:
    robot = nav2.nav2.robots[0]
    async with tasks_session(nav2) as session:
        task_id = await start_task(session.mcp, "navigate_to", {"goal": {"x": 1.5, "y": 9.0}})
        await nav2.wait_for(lambda world: robot.linear > 0.1, timeout=10.0)
        if by == "stop_robot":
            await session.ok("stop_robot")
        else:
            assert session.robot is not None
            await emergency_stop(session.robot, by="console")
        shown = await poll(session.mcp, task_id, ended)
    who = "stop_robot" if by == "stop_robot" else "E-STOP on the operator console"
    assert shown["status"] == "completed"
    assert shown["statusMessage"].startswith(f"Stopped by {who}: navigate_to ended.")
    assert not (CallToolResult.model_validate(shown["result"]).structured_content or {})["succeeded"]
    assert math.hypot(robot.x - 1.5, robot.y - 9.0) > 0.5


class Nobody:
    """An elicitation handler that must not be reached: a task asks through tasks/get and tasks/update."""

    async def __call__(self, context: ClientRequestContext, params: ElicitRequestParams) -> ElicitResult:
        raise AssertionError("asked outside the task")


@pytest.mark.parametrize("approve", [True, False])
async def test_a_confirmation_inside_a_task_is_answered_through_tasks_update(
    nav2: SimulatedRobot, approve: bool
) -> None:
    """The question is the task's input_required, the same as a plain 2026-07-28 call's; a yes drives, a no
    sends nothing."""
    policy = {**POLICY, "confirm": "always"}
    before = len(nav2.world.goals)
    async with tasks_session(nav2, policy=policy, elicitation_callback=Nobody()) as session:
        task_id = await start_task(session.mcp, "navigate_to", {"goal": {"x": 2.5, "y": 7.5}})
        asked = await poll(session.mcp, task_id, lambda shown: shown["status"] != "working")
        assert asked["status"] == "input_required", asked
        ((key, question),) = asked["inputRequests"].items()
        assert question["method"] == "elicitation/create"
        assert "navigate_to" in question["params"]["message"]
        assert asked["statusMessage"] == question["params"]["message"]
        assert len(nav2.world.goals) == before  # nothing sent while the person is asked
        answer = {key: {"action": "accept", "content": {"approve": approve}}}
        request = UpdateTaskRequest(params=UpdateParams(task_id=task_id, input_responses=answer))
        await session.mcp.session.send_request(request, _ANY)
        final = await poll(session.mcp, task_id, ended)
    assert final["status"] == "completed", final
    data = CallToolResult.model_validate(final["result"])
    if approve:
        assert (data.structured_content or {})["succeeded"], result_text(final)
    else:
        assert data.is_error
        assert len(nav2.world.goals) == before


async def test_another_callers_task_is_not_found_and_a_plain_client_gets_todays_answer(
    nav2: SimulatedRobot,
) -> None:
    """An unknown task id is an error naming it; a client that does not advertise tasks gets the tool's
    answer in the call, as before."""
    async with tasks_session(nav2) as session:
        with pytest.raises(MCPError, match="Task not found"):
            await get_task(session.mcp, "no-such-task")
    async with open_session(nav2.url, guard=None, mode="auto") as plain:
        result = await plain.ok("navigate_to", {"goal": {"x": 2.5, "y": 7.5}})
    assert (result.structured_content or {})["succeeded"]


async def test_no_tasks_runs_every_call_to_its_end(nav2: SimulatedRobot) -> None:
    """--no-tasks: a client that advertises tasks gets the answer in the call."""
    async with tasks_session(nav2, tasks=False) as session:
        result = await session.mcp.session.call_tool(
            "navigate_to", {"goal": {"x": 2.5, "y": 7.5}}, allow_claimed=True
        )
    assert isinstance(result, CallToolResult)
    assert (result.structured_content or {})["succeeded"]


async def test_a_stop_while_the_person_is_asked_voids_the_task(nav2: SimulatedRobot) -> None:
    """stop_robot voids every call begun before it: a task waiting for the person's yes is one, so a yes given
    after the stop sends nothing."""
    policy = {**POLICY, "confirm": "always"}
    before = len(nav2.world.goals)
    async with tasks_session(nav2, policy=policy, elicitation_callback=Nobody()) as session:
        task_id = await start_task(session.mcp, "navigate_to", {"goal": {"x": 2.5, "y": 7.5}})
        asked = await poll(session.mcp, task_id, lambda shown: shown["status"] == "input_required")
        await session.ok("stop_robot")
        ((key, _),) = asked["inputRequests"].items()
        answer = {key: {"action": "accept", "content": {"approve": True}}}
        request = UpdateTaskRequest(params=UpdateParams(task_id=task_id, input_responses=answer))
        await session.mcp.session.send_request(request, _ANY)
        final = await poll(session.mcp, task_id, ended)
    assert final["status"] == "completed", final
    assert final["statusMessage"].startswith("Stopped by stop_robot")
    assert CallToolResult.model_validate(final["result"]).is_error
    assert "nothing" in result_text(final)
    assert len(nav2.world.goals) == before


async def test_the_console_lists_running_tasks(nav2: SimulatedRobot) -> None:
    """The operator console's snapshot has a row for each running task: its tool, status and line."""
    boards: list[TaskBoard] = []

    def board(fleet: Fleet) -> TaskBoard:
        boards.append(TaskBoard(fleet))
        return boards[-1]

    async with tasks_session(nav2, tasks=board) as session:
        assert session.robot is not None
        hub = ConsoleHub([RobotView("robot", session.robot, Audit(io.StringIO()))], Operator())
        hub.tasks = boards[0].running_tasks
        assert hub.snapshot()["tasks"] == []
        task_id = await start_task(session.mcp, "navigate_to", {"goal": {"x": 1.5, "y": 9.0}})
        await poll(session.mcp, task_id, lambda shown: "m to go" in shown.get("statusMessage", ""))
        (row,) = hub.snapshot()["tasks"]
        await cancel_task(session.mcp, task_id)
        after = hub.snapshot()["tasks"]
    assert (row["id"], row["tool"], row["status"]) == (task_id, "navigate_to", "working")
    assert "m to go" in row["message"]
    assert after == []


async def test_tasks_cancel_ends_a_velocity_stream_with_a_zero(sim_ros2: SimulatedRobot) -> None:
    """A publish_topic stream as a task: tasks/cancel ends it, the last command the robot got is the zero,
    and the task says so."""
    cmd_vel = "/turtle1/cmd_vel"
    twist = {"linear": {"x": 0.3}, "angular": {"z": 0.1}}
    arguments = {
        "topic": cmd_vel,
        "message_type": "geometry_msgs/msg/Twist",
        "message": twist,
        "rate_hz": 10,
        "duration": 30,
    }
    async with tasks_session(sim_ros2, policy={}) as session:
        task_id = await start_task(session.mcp, "publish_topic", arguments)
        await sim_ros2.wait_for(lambda world: len(world.published.get(cmd_vel, [])) >= 3, timeout=10.0)
        await cancel_task(session.mcp, task_id)
        shown = await poll(session.mcp, task_id, ended)
    last = sim_ros2.world.published[cmd_vel][-1].msg
    assert shown["status"] == "cancelled"
    assert "its stream ended" in shown["statusMessage"]
    assert last["linear"]["x"] == 0.0
    assert last["angular"]["z"] == 0.0
    assert len(sim_ros2.world.published[cmd_vel]) < 100  # ended long before its 30 s


async def test_a_recording_as_a_task_shows_messages_and_bytes(
    sim_ros2: SimulatedRobot, tmp_path: Path
) -> None:
    async with tasks_session(sim_ros2, policy={}, record_dir=str(tmp_path)) as session:
        task_id = await start_task(session.mcp, "record", {"topics": ["/turtle1/pose"], "duration": 2})
        seen: list[dict[str, Any]] = []
        final = await poll(session.mcp, task_id, ended, seen)
    assert final["status"] == "completed", final
    assert any("messages" in shown.get("statusMessage", "") for shown in seen), seen
    data = CallToolResult.model_validate(final["result"]).structured_content or {}
    assert (tmp_path / data["file"]).exists()


async def test_beyond_the_running_bound_a_long_call_runs_as_a_plain_call(nav2: SimulatedRobot) -> None:
    def board(fleet: Fleet) -> TaskBoard:
        return TaskBoard(fleet, max_running=1)

    async with tasks_session(nav2, tasks=board) as session:
        task_id = await start_task(session.mcp, "navigate_to", {"goal": {"x": 1.5, "y": 9.0}})
        second = await session.mcp.session.call_tool(
            "subscribe_topic", {"topic": "/odom", "duration": 0.5}, allow_claimed=True
        )
        await cancel_task(session.mcp, task_id)
    assert isinstance(second, CallToolResult)
    assert not second.is_error


async def test_an_answer_is_dropped_once_its_keeping_time_is_over(nav2: SimulatedRobot) -> None:
    def board(fleet: Fleet) -> TaskBoard:
        return TaskBoard(fleet, keep_seconds=0.0)

    async with tasks_session(nav2, tasks=board) as session:
        task_id = await start_task(session.mcp, "subscribe_topic", {"topic": "/odom", "duration": 0.3})
        with pytest.raises(MCPError, match="Task not found") as gone:
            await poll(session.mcp, task_id, lambda shown: False)
    assert "kept 0 minutes after its task ends" in str(gone.value)
