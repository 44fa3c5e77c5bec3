"""Tasks in the 2025-11-25 dialect over the real command's stdio, spoken by hand (the SDK's client will not
read a task as a ``tools/call`` answer in that dialect): the handshake says which tools may run as tasks, a
goal called with ``task`` answers with one at once, ``tasks/get`` follows its feedback, ``tasks/result`` gives
the tool's answer, ``tasks/cancel`` and the server's shutdown cancel the goal on the robot."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

from test_e2e_stdio import WAIT, StdioServer, _finish, _start

from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]

FIBONACCI = {"action_name": "/fibonacci", "action_type": "example_interfaces/action/Fibonacci"}


async def _initialized(server: StdioServer) -> dict[str, Any]:
    answer = await server.request(
        "initialize",
        {
            "protocolVersion": "2025-11-25",
            "capabilities": {"tasks": {"cancel": {}}},
            "clientInfo": {"name": "e2e-tasks", "version": "0"},
        },
    )
    await server.send({"jsonrpc": "2.0", "method": "notifications/initialized"})
    return answer["result"]


async def _task(server: StdioServer, order: int) -> str:
    arguments = {**FIBONACCI, "goal": {"order": order}, "timeout": 120}
    answer = await server.request(
        "tools/call", {"name": "publish_action", "arguments": arguments, "task": {"ttl": 60000}}
    )
    task = answer["result"]["task"]
    assert task["status"] == "working", answer
    return str(task["taskId"])


async def _until(server: StdioServer, task_id: str, done: Callable[[dict[str, Any]], bool]) -> dict[str, Any]:
    async with asyncio.timeout(WAIT):
        while True:
            shown = (await server.request("tasks/get", {"taskId": task_id}))["result"]
            if done(shown):
                return shown
            await asyncio.sleep(0.05)  # the client's poll interval


async def test_a_goal_as_a_task_is_followed_and_its_answer_fetched(make_sim: MakeSim) -> None:
    robot = await make_sim(dialect="ros2", action_step=0.05)
    server = await _start("--url", robot.url)
    try:
        started = await _initialized(server)
        assert started["capabilities"]["tasks"]["requests"] == {"tools": {"call": {}}}
        tools = {tool["name"]: tool for tool in (await server.request("tools/list"))["result"]["tools"]}
        assert tools["publish_action"]["execution"] == {"taskSupport": "optional"}
        assert "execution" not in tools["list_topics"]
        task_id = await _task(server, 8)
        working = await _until(server, task_id, lambda shown: "feedback" in shown.get("statusMessage", ""))
        assert working["status"] == "working"
        answer = (await server.request("tasks/result", {"taskId": task_id}))["result"]
        ended = (await server.request("tasks/get", {"taskId": task_id}))["result"]
    finally:
        _rest, stderr, code = await _finish(server)
    assert code == 0, stderr.decode()
    assert answer["structuredContent"]["status"] == "succeeded", answer
    assert answer["_meta"]["io.modelcontextprotocol/related-task"] == {"taskId": task_id}
    assert ended["status"] == "completed"
    assert ended["statusMessage"].startswith("publish_action ended: ")


async def test_tasks_cancel_cancels_the_goal_and_says_so(make_sim: MakeSim) -> None:
    robot = await make_sim(dialect="ros2", action_step=0.2)
    server = await _start("--url", robot.url)
    try:
        await _initialized(server)
        task_id = await _task(server, 45)
        await _until(server, task_id, lambda shown: "feedback" in shown.get("statusMessage", ""))
        (goal,) = robot.world.goals.values()
        cancelled = (await server.request("tasks/cancel", {"taskId": task_id}))["result"]
        again = await server.request("tasks/cancel", {"taskId": task_id})
    finally:
        _rest, stderr, code = await _finish(server)
    assert code == 0, stderr.decode()
    assert cancelled["status"] == "cancelled"
    assert "Cancelled by the client (tasks/cancel)" in cancelled["statusMessage"]
    assert "already ended" in again["error"]["message"]
    await robot.wait_for(lambda w: goal.finished, WAIT)
    assert goal.cancel_requested
    assert goal.status == 5  # CANCELED


async def test_the_servers_shutdown_cancels_a_running_task_on_the_robot(make_sim: MakeSim) -> None:
    """The call was answered long ago: closing stdin still cancels the task's goal before the server exits."""
    robot = await make_sim(dialect="ros2", action_step=0.2)
    server = await _start("--url", robot.url)
    try:
        await _initialized(server)
        task_id = await _task(server, 45)
        await _until(server, task_id, lambda shown: "feedback" in shown.get("statusMessage", ""))
        (goal,) = robot.world.goals.values()
        assert not goal.finished
    finally:
        _rest, stderr, code = await _finish(server)
    assert code == 0, stderr.decode()
    await robot.wait_for(lambda w: goal.finished, WAIT)
    assert goal.cancel_requested
    assert goal.status == 5  # CANCELED


async def test_a_confirmation_asked_mid_task_shows_as_input_required(
    make_sim: MakeSim, tmp_path: Path
) -> None:
    """2025-11-25: the question goes out as ``elicitation/create`` while the task says ``input_required``
    with the question; the person's yes lets the goal go and the task goes on to its end."""
    robot = await make_sim(dialect="ros2", action_step=0.05)
    policy = tmp_path / "policy.toml"
    policy.write_text('confirm = "always"\n')
    server = await _start("--url", robot.url, "--policy", str(policy))
    kept: list[dict[str, Any]] = []
    try:
        await server.request(
            "initialize",
            {
                "protocolVersion": "2025-11-25",
                "capabilities": {"tasks": {"cancel": {}}, "elicitation": {"form": {}}},
                "clientInfo": {"name": "e2e-tasks", "version": "0"},
            },
        )
        await server.send({"jsonrpc": "2.0", "method": "notifications/initialized"})
        arguments = {**FIBONACCI, "goal": {"order": 5}, "timeout": 60}
        await server.send(
            {
                "jsonrpc": "2.0",
                "id": 50,
                "method": "tools/call",
                "params": {"name": "publish_action", "arguments": arguments, "task": {"ttl": 60000}},
            }
        )
        # The task's answer and the question come in either order.
        while not (_asked(kept) and any(m.get("id") == 50 for m in kept)):
            kept.append(await server.read_message())
        task_id = next(m for m in kept if m.get("id") == 50 and "result" in m)["result"]["task"]["taskId"]
        question = _asked(kept)
        assert question is not None
        waiting = (await server.request("tasks/get", {"taskId": task_id}))["result"]
        assert robot.world.goals == {}  # nothing sent while the person is asked
        yes = {"action": "accept", "content": {"approve": True}}
        await server.send({"jsonrpc": "2.0", "id": question["id"], "result": yes})
        answer = (await server.request("tasks/result", {"taskId": task_id}))["result"]
    finally:
        _rest, stderr, code = await _finish(server)
    assert code == 0, stderr.decode()
    assert waiting["status"] == "input_required"
    assert waiting["statusMessage"] == question["params"]["message"]
    assert "publish_action" in waiting["statusMessage"]
    assert answer["structuredContent"]["status"] == "succeeded", answer


def _asked(messages: list[dict[str, Any]]) -> dict[str, Any] | None:
    return next((m for m in messages if m.get("method") == "elicitation/create"), None)
