"""``publish_topic``: check a message against its type, then publish it once."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.errors import InvalidMessageError, RequestTimeoutError
from rosbridge_mcp_server.tools.base import (
    ACTS_ON_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolSpec,
    absolute_name,
    check_name_for_ros,
    compact_json,
    parse_json_object,
)
from rosbridge_mcp_server.typecheck import check_message, example_message, short_type_name
from rosbridge_mcp_server.wire.dialect import adapt_message, normalize_type

__all__ = ["PING_LIMIT", "SPEC", "PublishAnswer", "run"]

_EXAMPLE = '{"linear": {"x": 0.5}, "angular": {"z": 0.3}}'
#: Longest wait for the bridge's pong before a publish (less when the configured request timeout is shorter).
PING_LIMIT = 3.0


class PublishAnswer(BaseModel):
    """What was published."""

    topic: str
    message_type: str = Field(description="The type as the bridge was given it")
    message: dict[str, Any] = Field(description="The message as sent")
    published: bool


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
    name = absolute_name(topic, "topic")
    body = parse_json_object(message, "message", _EXAMPLE)
    info = await ctx.graph.ros_info()
    check_name_for_ros(name, "topic", info.version)
    bridge_type = normalize_type(message_type, info.version, "msg")
    typedefs = await ctx.graph.message_typedefs(message_type)

    graph_type = await ctx.graph.publishing_type(name)
    if graph_type and short_type_name(graph_type) != short_type_name(bridge_type):
        raise ToolFailure(
            f"Topic {name} has type {graph_type}, not {bridge_type}; rosbridge would drop the message. "
            f"Publish a {graph_type} message, or choose another topic (list_topics shows each topic's type)."
        )

    body = adapt_message(body, info.version)
    try:
        check_message(body, bridge_type, typedefs, ros_version=info.version)
    except InvalidMessageError as exc:
        shape = compact_json(example_message(bridge_type, typedefs, ros_version=info.version))
        raise ToolFailure(
            f"{exc}. Nothing was published. A {bridge_type} message looks like {shape}."
        ) from exc

    await _bridge_is_reading(ctx)
    await ctx.client.publish(name, bridge_type, body)
    ctx.graph.remember_publishing(name, bridge_type)
    text = f"Published one {bridge_type} message on {name}: {compact_json(body)}"
    return ToolAnswer(
        text=text, data=PublishAnswer(topic=name, message_type=bridge_type, message=body, published=True)
    )


async def _bridge_is_reading(ctx: ToolContext) -> None:
    """Refuse to publish into a connection the bridge is not reading.

    A frozen bridge (or a link that died without a close) still takes our frame into the socket buffer and
    acts on it whenever it wakes up: a late velocity command. Seen against a real 0.11.17 bridge stopped with
    SIGSTOP: the publish "succeeded" and the message arrived after SIGCONT. One ping round trip first proves
    it reads the connection now.
    """
    limit = min(ctx.config.request_timeout, PING_LIMIT)
    try:
        await ctx.client.ping(limit)
    except RequestTimeoutError as exc:
        raise ToolFailure(
            f"rosbridge at {ctx.client.url} did not answer a ping within {limit:g} s (the bridge is frozen, "
            "or the network to the robot is down), so nothing was published: a message sent now could reach "
            "the robot late and move it then. Check the robot and its network, then try again."
        ) from exc
