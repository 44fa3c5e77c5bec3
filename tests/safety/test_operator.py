"""The person at the console, as the guard sees them: asked when the client cannot, and the latched stop."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest

from rosbridge_mcp_server.errors import PolicyRefusal
from rosbridge_mcp_server.robot.approval import Act, Answer, asking, nobody_to_ask
from rosbridge_mcp_server.safety import LATCH_RULE, Audit, AuditEntry, Operator, PolicyGuard, parse_policy

WAIT = 30.0


def twist_act(x: float = 0.2) -> Act:
    twist = {"linear": {"x": x, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
    return Act("publish_topic", "topic", "/cmd_vel", "geometry_msgs/msg/Twist", twist)


def guarded(operator: Operator, **policy: Any) -> tuple[PolicyGuard, list[AuditEntry]]:
    entries: list[AuditEntry] = []
    audit = Audit()
    audit.listen(entries.append)
    return PolicyGuard(parse_policy(policy, where="test.toml"), audit, operator), entries


async def first_pending(operator: Operator) -> str:
    """The id of the first confirmation the operator is asked (waits on the operator's change signal)."""
    changed = asyncio.Event()
    operator.listen(changed.set)
    async with asyncio.timeout(WAIT):
        while not operator.pending:
            await changed.wait()
            changed.clear()
    return operator.pending[0].id


async def test_the_console_answers_when_the_client_cannot_ask() -> None:
    """Approve lets the act through unchanged; the question names the tool and the topic."""
    operator = Operator()
    guard, entries = guarded(operator, confirm="motion")
    approving = asyncio.create_task(guard.approve(twist_act(), nobody_to_ask))
    pending_id = await first_pending(operator)
    assert "/cmd_vel" in operator.pending[0].question
    assert "publish_topic" in operator.pending[0].question
    assert operator.answer(pending_id, approve=True)
    act = await approving
    assert act == twist_act()
    assert [entry["outcome"] for entry in entries] == ["confirmed"]
    assert operator.pending == []


async def test_deny_on_the_console_refuses_the_act() -> None:
    """Deny is the person's no: a refusal saying they declined, audited as refused."""
    operator = Operator()
    guard, entries = guarded(operator, confirm="motion")
    approving = asyncio.create_task(guard.approve(twist_act(), nobody_to_ask))
    assert operator.answer(await first_pending(operator), approve=False)
    with pytest.raises(PolicyRefusal, match="declined"):
        await approving
    assert [entry["outcome"] for entry in entries] == ["refused"]


async def test_no_answer_on_the_console_within_the_timeout_is_a_no() -> None:
    """The policy's confirm_timeout bounds the console's wait too; the pending entry goes away."""
    operator = Operator()
    guard, _ = guarded(operator, confirm="motion", confirm_timeout=0.2)
    with pytest.raises(PolicyRefusal, match="did not answer"):
        await guard.approve(twist_act(), nobody_to_ask)
    assert operator.pending == []


async def test_an_elicitation_answer_wins_and_the_console_is_not_asked() -> None:
    """A client that can ask asks; the console is only the fallback."""
    operator = Operator()
    guard, _ = guarded(operator, confirm="motion")

    async def yes(question: str) -> Answer:
        return "accept"

    assert await guard.approve(twist_act(), asking(yes)) == twist_act()
    assert operator.pending == []


async def test_without_a_console_a_client_that_cannot_ask_is_refused_as_before() -> None:
    """An operator that is not present answers "unsupported", the old refusal."""
    guard, _ = guarded(Operator(present=False), confirm="motion")
    with pytest.raises(PolicyRefusal, match="cannot ask"):
        await guard.approve(twist_act(), nobody_to_ask)


async def test_a_latched_stop_refuses_every_act_until_released() -> None:
    """While latched nothing is approved, whatever the policy; after release acts pass again."""
    operator = Operator()
    guard, entries = guarded(operator)
    operator.latch("console")
    with pytest.raises(PolicyRefusal, match="E-STOP"):
        await guard.approve(twist_act(), nobody_to_ask)
    with pytest.raises(PolicyRefusal, match="E-STOP"):
        await guard.approve(
            Act("publish_service", "service", "/reset", "std_srvs/srv/Empty", {}), nobody_to_ask
        )
    assert entries[0]["detail"] == LATCH_RULE
    assert operator.release("console")
    assert not operator.release("console")
    assert await guard.approve(twist_act(), nobody_to_ask) == twist_act()


async def test_latching_denies_the_confirmations_that_wait() -> None:
    """E-STOP pressed while a motion waits for Approve: that motion is refused, not left to a later yes."""
    operator = Operator()
    guard, _ = guarded(operator, confirm="motion")
    approving = asyncio.create_task(guard.approve(twist_act(), nobody_to_ask))
    pending_id = await first_pending(operator)
    operator.latch("console")
    with pytest.raises(PolicyRefusal, match="E-STOP"):
        await approving
    assert not operator.answer(pending_id, approve=True)
