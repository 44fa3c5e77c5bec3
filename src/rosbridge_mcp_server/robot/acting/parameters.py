"""A checked parameter write (:func:`set_parameter`): planned, approved, written and read back."""

from __future__ import annotations

from typing import Any

from rosbridge_mcp_server.robot.acting.context import Acting, given_name
from rosbridge_mcp_server.robot.approval import Act, approved, carry_out
from rosbridge_mcp_server.robot.effects import parameter_write
from rosbridge_mcp_server.robot.parameters import SetOutcome, apply_set, plan_set

__all__ = ["set_parameter"]


async def set_parameter(ctx: Acting, *, tool: str, name: str, value: Any) -> SetOutcome:
    """Check the parameter (name form, and on ROS 2 that its node has it), then set it and read it back."""
    ticket = ctx.gate.ticket()  # a stop from now on voids this call
    planned = await plan_set(ctx.graph, ctx.client, name, value)
    full = planned.name.full
    dialect = await ctx.graph.dialect()
    act = await approved(
        ctx,
        Act(
            tool,
            "parameter",
            full,
            "",
            planned.value,
            effects=(parameter_write(full, dialect.version),),
            given=given_name(name, full),
        ),
    )
    outcome: SetOutcome = await carry_out(
        ctx,
        act,
        lambda: apply_set(
            ctx.graph, ctx.client, planned, act.payload, before_write=lambda: ctx.gate.check(ticket, act)
        ),
    )
    return outcome
