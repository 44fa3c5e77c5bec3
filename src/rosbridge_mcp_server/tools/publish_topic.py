"""``publish_topic``: check a message against its type, then publish it once."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.acting import PING_LIMIT, publish_once
from rosbridge_mcp_server.robot.messages import compact_json
from rosbridge_mcp_server.tools.base import (
    ACTS_ON_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolSpec,
    parse_json_object,
)

__all__ = ["PING_LIMIT", "SPEC", "PublishAnswer", "run"]

_EXAMPLE = '{"linear": {"x": 0.5}, "angular": {"z": 0.3}}'


class PublishAnswer(BaseModel):
    """What was published."""

    topic: str
    message_type: str = Field(description="The type as the bridge was given it")
    message: dict[str, Any] = Field(description="The message as sent")
    published: bool
    adjusted: str | None = Field(
        default=None, description="How the safety policy changed the message before sending (velocity caps)"
    )


SPEC = ToolSpec(
    name="publish_topic",
    title="Publish a message",
    description=(
        "Publish one message on a ROS topic. This can move the robot. Example: topic /turtle1/cmd_vel, "
        f"message_type geometry_msgs/msg/Twist, message {_EXAMPLE} drives forward at 0.5 m/s while turning "
        "at 0.3 rad/s (velocity commands usually act only briefly; publish again to keep moving, publish "
        "zeros to stop). The message is checked against the type first; a field that does not fit is an "
        "error naming it. Omitted fields are zero/empty; {} is a valid message for std_msgs/msg/Empty. "
        "Use list_topics and get_topic_info to find topics and types."
    ),
    hints=ACTS_ON_ROBOT,
    output=PublishAnswer,
)


async def run(
    ctx: ToolContext,
    topic: Annotated[str, Field(description="Topic to publish on, e.g. /turtle1/cmd_vel")],
    message_type: Annotated[
        str,
        Field(description="ROS message type, pkg/msg/Type or pkg/Type, e.g. geometry_msgs/msg/Twist"),
    ],
    message: Annotated[
        dict[str, Any] | str,
        Field(
            description=(
                f"The message as a JSON object, e.g. {_EXAMPLE} for a Twist (units: m/s and rad/s); omitted "
                "fields are 0/empty; {} for std_msgs/msg/Empty"
            )
        ),
    ] = "{}",
) -> ToolAnswer:
    """Check ``message`` against ``message_type``, then publish it on ``topic``."""
    body = parse_json_object(message, "message", _EXAMPLE)
    sent = await publish_once(ctx, tool=SPEC.name, topic=topic, message_type=message_type, message=body)
    text = f"Published one {sent.type} message on {sent.topic}: {compact_json(sent.message)}"
    if sent.adjusted:
        text += f" (the safety policy {sent.adjusted})"
    return ToolAnswer(
        text=text,
        data=PublishAnswer(
            topic=sent.topic,
            message_type=sent.type,
            message=sent.message,
            published=True,
            adjusted=sent.adjusted,
        ),
    )
