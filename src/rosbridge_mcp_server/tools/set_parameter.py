"""``set_parameter``: change one parameter, confirmed by reading it back."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.parameters import ParameterError
from rosbridge_mcp_server.tools.arguments import JsonValue
from rosbridge_mcp_server.tools.base import (
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolHints,
    ToolSpec,
    compact_json,
)

__all__ = ["SPEC", "SetParameterAnswer", "run"]

# Setting the same value twice changes nothing more; but it changes how the robot behaves.
_SETS_PARAMETER = ToolHints(read_only=False, destructive=True, idempotent=True)


class SetParameterAnswer(BaseModel):
    """The parameter before and after."""

    name: str
    previous: Any = Field(description="The value before")
    value: Any = Field(description="The value read back after setting")
    applied: bool = Field(description="True when the value read back is the one sent")


SPEC = ToolSpec(
    name="set_parameter",
    title="Set a parameter",
    description=(
        "Set one parameter (read back to confirm); can change the robot. Example: "
        '{"name": "/turtlesim:background_r", "value": 200}. ROS 2 keeps the type: 2.0 for a double.'
    ),
    hints=_SETS_PARAMETER,
    acts_on="parameter",
    output=SetParameterAnswer,
)


async def run(
    ctx: ToolContext,
    name: Annotated[
        str, Field(description="ROS 2 /node:name or ROS 1 /ns/name, e.g. /turtlesim:background_r")
    ],
    value: Annotated[
        JsonValue, Field(description="The new value as JSON: a number, string, bool or list, e.g. 200")
    ],
) -> ToolAnswer:
    """Set the parameter, read it back, and say whether it took."""
    from rosbridge_mcp_server.robot.acting import set_parameter  # noqa: PLC0415 - on the first act

    if value is None:
        raise ToolFailure(
            "value is null; ROS parameters cannot be null. Send a number, string, bool or list."
        )
    try:
        outcome = await set_parameter(ctx, tool=SPEC.name, name=name, value=value)
    except ParameterError as exc:
        raise ToolFailure.carrying(exc, " Nothing was set.") from None
    answer = SetParameterAnswer(
        name=outcome.name, previous=outcome.before, value=outcome.after, applied=outcome.applied
    )
    if not outcome.applied:
        raise ToolFailure(
            f"{outcome.name} was not changed: {outcome.reason}. It is {compact_json(outcome.after)} "
            f"(sent {compact_json(outcome.sent)})."
        )
    text = f"{outcome.name} = {compact_json(outcome.after)} (was {compact_json(outcome.before)})."
    return ToolAnswer(text=text, data=answer)
