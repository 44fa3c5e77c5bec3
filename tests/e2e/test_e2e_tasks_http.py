"""Tasks over Streamable HTTP with two bearer tokens: a task belongs to the token that started it. Another
token's ``tasks/get`` and ``tasks/cancel`` find nothing (the same error as a task that never was) and its goal
runs on; its own caller follows and cancels it. The SDK's own client on the 2026-07-28 protocol."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any, Literal

import pytest
from e2e_transports import TOKEN, WAIT, serving
from mcp.client.extension import ClaimContext, ClientExtension, ResultClaim
from mcp.types import (
    CallToolResult,
    CancelTaskRequest,
    CancelTaskRequestParams,
    GetTaskRequest,
    GetTaskRequestParams,
    Result,
)
from pydantic import ConfigDict, TypeAdapter

from mcp import Client, MCPError
from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]

SECOND_TOKEN = "second-token-0123456789abcdef"
_ANY = TypeAdapter(dict[str, Any])


class CreatedTask(Result):
    model_config = ConfigDict(extra="allow")
    result_type: Literal["task"] = "task"
    task_id: str


class TasksAd(ClientExtension):
    """The tasks extension, for a client that follows its tasks itself."""

    identifier = "io.modelcontextprotocol/tasks"

    def claims(self) -> list[ResultClaim[Any]]:
        async def resolve(created: CreatedTask, ctx: ClaimContext) -> CallToolResult:
            raise AssertionError("the test follows the task itself")

        return [ResultClaim(result_type="task", model=CreatedTask, resolve=resolve)]


async def _get(client: Client, task_id: str) -> dict[str, Any]:
    return await client.session.send_request(
        GetTaskRequest(params=GetTaskRequestParams(task_id=task_id)), _ANY
    )


async def _cancel(client: Client, task_id: str) -> dict[str, Any]:
    request = CancelTaskRequest(params=CancelTaskRequestParams(task_id=task_id))
    return await client.session.send_request(request, _ANY)


async def test_another_token_can_neither_read_nor_cancel_a_task(make_sim: MakeSim) -> None:
    robot = await make_sim(dialect="ros2", action_step=0.2)
    arguments = {
        "action_name": "/fibonacci",
        "action_type": "example_interfaces/action/Fibonacci",
        "goal": {"order": 45},
        "timeout": 120,
    }
    async with (
        serving("http", "--url", robot.url) as served,
        served.connect(TOKEN, mode="auto", extensions=[TasksAd()]) as owner,
        served.connect(SECOND_TOKEN, mode="auto", extensions=[TasksAd()]) as other,
    ):
        created = await owner.session.call_tool("publish_action", arguments, allow_claimed=True)
        assert isinstance(created, CreatedTask), created
        task_id = created.task_id
        async with asyncio.timeout(WAIT):
            while not robot.world.goals:  # noqa: ASYNC110 (the goal arrives from the task's own run)
                await asyncio.sleep(0.05)
        (goal,) = robot.world.goals.values()
        with pytest.raises(MCPError, match="Task not found") as read:
            await _get(other, task_id)
        with pytest.raises(MCPError, match="Task not found"):
            await _cancel(other, task_id)
        with pytest.raises(MCPError, match="Task not found") as never:
            await _get(other, "no-such-task")
        shown = await _get(owner, task_id)
        assert shown["status"] == "working"
        assert not goal.finished
        assert not goal.cancel_requested
        await _cancel(owner, task_id)
        await robot.wait_for(lambda w: goal.finished, WAIT)
        ended = await _get(owner, task_id)
    # Another caller's task and no task at all read the same: nothing tells them apart.
    assert str(read.value).replace(task_id, "ID") == str(never.value).replace("no-such-task", "ID")
    assert goal.status == 5  # CANCELED
    assert ended["status"] == "cancelled"
