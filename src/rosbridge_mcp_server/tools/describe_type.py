"""``describe_type``: the fields of a message, service or action type, and an example to send."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, Field

from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolSpec,
    compact_json,
)

__all__ = ["SPEC", "TypeAnswer", "run"]

_TOOL_FOR = {"message": "publish_topic", "service": "publish_service", "action": "publish_action"}
_EXAMPLE_PART = {"message": "message", "service": "request", "action": "goal"}


class TypePart(BaseModel):
    """One part of the type."""

    part: str = Field(description="message, request, response, goal, result or feedback")
    type: str
    outline: list[str] = Field(description="One line per field, nested fields indented")
    constants: dict[str, str]
    example: dict[str, Any]


class TypeAnswer(BaseModel):
    """A type's fields."""

    type: str
    kind: Literal["message", "service", "action"]
    parts: list[TypePart]
    example: dict[str, Any] = Field(description="What the publish tool for this kind accepts")


SPEC = ToolSpec(
    name="describe_type",
    title="Describe a type",
    description=(
        "A message, service or action type's fields as an outline, with an example to send. "
        'Read-only. Example: {"type_name": "geometry_msgs/msg/Twist"}.'
    ),
    hints=READS_ROBOT,
    output=TypeAnswer,
)


async def run(
    ctx: ToolContext,
    type_name: Annotated[
        str, Field(description="pkg/msg/T, pkg/srv/T, pkg/action/T or pkg/T, e.g. sensor_msgs/msg/LaserScan")
    ],
) -> ToolAnswer:
    """Ask rosapi for the type's definitions and outline them."""
    from rosbridge_mcp_server.robot.describing import describe_type  # noqa: PLC0415 - on first use

    found = await describe_type(ctx.graph, type_name)
    parts = [
        TypePart(
            part=title,
            type=outline.type,
            outline=list(outline.lines),
            constants=outline.constants,
            example=outline.example,
        )
        for title, outline in found.parts
    ]
    wanted = _EXAMPLE_PART[found.kind]
    example = next((part.example for part in parts if part.part == wanted), {})
    answer = TypeAnswer(type=found.type, kind=found.kind, parts=parts, example=example)
    lines = [f"{found.type} ({found.kind})"]
    for part in parts:
        if len(parts) > 1:
            lines.append(f"{part.part} ({part.type}):")
        indent = "  " if len(parts) > 1 else ""
        lines.extend(f"{indent}{line}" for line in part.outline or ["(no fields)"])
    lines.append(f"Example for {_TOOL_FOR[found.kind]}: {compact_json(example, 1500)}")
    return ToolAnswer(text="\n".join(lines), data=answer)
