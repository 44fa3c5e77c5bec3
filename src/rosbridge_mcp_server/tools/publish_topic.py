"""``publish_topic``: check a message against its type, then publish it once."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.messages import compact_json
from rosbridge_mcp_server.robot.wording import full_stop
from rosbridge_mcp_server.tools.arguments import NO_FIELDS, JsonObject
from rosbridge_mcp_server.tools.audience import audience
from rosbridge_mcp_server.tools.base import (
    ACTS_ON_ROBOT,
    LongWork,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolSpec,
)

__all__ = ["MAX_RATE", "MAX_STREAM", "SPEC", "PublishAnswer", "run"]

#: Fastest stream rate, Hz: faster than rosbridge's JSON path and a model's use for it.
MAX_RATE = 100.0
#: Longest stream, seconds.
MAX_STREAM = 300.0
DEFAULT_RATE = 10.0
_EXAMPLE = '{"linear": {"x": 0.5}, "angular": {"z": 0.3}}'


class PublishAnswer(BaseModel):
    """What was published."""

    topic: str
    message_type: str = Field(description="The type as the bridge was given it")
    message: dict[str, Any] = Field(description="The message as sent")
    published: bool
    count: int = Field(default=1, description="Messages published (a stream sends many)")
    rate_hz: float | None = Field(default=None, description="Stream rate, when one was asked for")
    duration: float | None = Field(default=None, description="Stream length in seconds, when asked for")
    zero_sent: bool = Field(default=False, description="A stream of velocity commands ended with all zeros")
    ended_by_stop: bool = Field(
        default=False, description="The stream was ended early by a stop: stop_robot or the console's E-STOP"
    )
    adjusted: str | None = Field(
        default=None, description="How the safety policy changed the message before sending (velocity caps)"
    )
    subscribers: int | None = Field(
        default=None,
        description="Subscribers when sent; 0: nobody received it",
    )


SPEC = ToolSpec(
    name="publish_topic",
    title="Publish a message",
    description=(
        "Publish on a topic; can move the robot. Example: topic /cmd_vel, message_type "
        f"geometry_msgs/msg/Twist, message {_EXAMPLE}. rate_hz with duration streams it, a Twist ending "
        "with zeros."
    ),
    hints=ACTS_ON_ROBOT,
    acts_on="topic",
    output=PublishAnswer,
    long_work=LongWork(
        given="duration", cancelled="its stream ended (a velocity stream ends with a zero command)"
    ),
)


async def run(
    ctx: ToolContext,
    *,
    topic: Annotated[str, Field(description="e.g. /turtle1/cmd_vel")],
    message_type: Annotated[
        str,
        Field(description="e.g. geometry_msgs/msg/Twist (ROS 1: geometry_msgs/Twist)"),
    ],
    message: Annotated[
        JsonObject,
        Field(description=(f"JSON object, e.g. {_EXAMPLE}; omitted fields are 0/empty")),
    ] = NO_FIELDS,
    rate_hz: Annotated[
        float | None,
        Field(gt=0, le=MAX_RATE, description="Publish repeatedly at this rate, e.g. 10 (needs duration)"),
    ] = None,
    duration: Annotated[
        float | None,
        Field(gt=0, le=MAX_STREAM, description="Seconds to keep publishing, e.g. 3 (rate_hz default 10)"),
    ] = None,
) -> ToolAnswer:
    """Check ``message`` against ``message_type``, then publish it on ``topic`` once or as a stream."""
    from rosbridge_mcp_server.robot.acting import publish_once  # noqa: PLC0415 - on the first act

    body = message
    if rate_hz is not None or duration is not None:
        if duration is None:
            raise ToolFailure(
                f"rate_hz {rate_hz:g} needs a duration: how many seconds to publish, e.g. 3. Nothing was "
                "published."
            )
        return await _stream(
            ctx,
            topic=topic,
            message_type=message_type,
            body=body,
            rate_hz=rate_hz or DEFAULT_RATE,
            duration=duration,
        )
    async with audience(ctx, topic) as heard:
        sent = await publish_once(ctx, tool=SPEC.name, topic=topic, message_type=message_type, message=body)
    text = f"Published one {sent.type} message on {sent.topic}: {compact_json(sent.message)}"
    if sent.adjusted:
        text += f" (the safety policy {sent.adjusted})"
    if nobody := await heard.nobody_text(ctx, sent.topic):
        text = f"{full_stop(text)} {nobody}"
    return ToolAnswer(
        text=text,
        data=PublishAnswer(
            topic=sent.topic,
            message_type=sent.type,
            message=sent.message,
            published=True,
            adjusted=sent.adjusted,
            subscribers=heard.count,
        ),
    )


async def _stream(
    ctx: ToolContext, *, topic: str, message_type: str, body: dict[str, Any], rate_hz: float, duration: float
) -> ToolAnswer:
    from rosbridge_mcp_server.robot.acting import publish_stream  # noqa: PLC0415 - on the first act

    async def progress(sent: int, planned: int) -> None:
        await ctx.report_progress(sent, planned, f"{sent} of {planned} messages")

    async with audience(ctx, topic) as heard:
        streamed = await publish_stream(
            ctx,
            tool=SPEC.name,
            topic=topic,
            message_type=message_type,
            message=body,
            rate_hz=rate_hz,
            duration=duration,
            on_progress=progress,
        )
    text = (
        f"Published {streamed.sent} {streamed.type} messages on {streamed.topic} at {streamed.rate_hz:g} Hz "
        f"for {streamed.duration:g} s: {compact_json(streamed.message)}"
    )
    if streamed.stopped:
        text = (
            f"{streamed.stopped_by} ended the stream on {streamed.topic} after {streamed.sent} of "
            f"{streamed.planned} {streamed.type} messages ({compact_json(streamed.message)})"
        )
    elif streamed.rate_limited:
        text = (
            f"Published {streamed.sent} of {streamed.planned} {streamed.type} messages on {streamed.topic} "
            f"in {streamed.duration:g} s: {compact_json(streamed.message)}. The safety policy's [publish] "
            "max_rate_hz bounds every stream and publish of this server on the topic together, and other "
            "senders used the rest"
        )
    if streamed.zero is not None:
        text += "; then one all-zero message to stop"
    if streamed.adjusted:
        text += f" (the safety policy {streamed.adjusted})"
    answer = PublishAnswer(
        topic=streamed.topic,
        message_type=streamed.type,
        message=streamed.message,
        published=True,
        count=streamed.sent,
        rate_hz=streamed.rate_hz,
        duration=streamed.duration,
        zero_sent=streamed.zero is not None,
        ended_by_stop=streamed.stopped,
        adjusted=streamed.adjusted,
        subscribers=heard.count,
    )
    nobody = await heard.nobody_text(ctx, streamed.topic)
    return ToolAnswer(text=f"{text}." + (f" {nobody}" if nobody else ""), data=answer)
