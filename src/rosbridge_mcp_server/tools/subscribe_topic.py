"""``subscribe_topic``: read one or more messages from a topic, shortened for a model."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, Field

from rosbridge_mcp_server.errors import RequestTimeoutError, ServiceError, UnknownTypeError
from rosbridge_mcp_server.robot.listening import byte_array_paths, listen, unknown_field_path
from rosbridge_mcp_server.robot.messages import TypeDef, same_type
from rosbridge_mcp_server.robot.summary import FieldPathError, select_fields, summarize
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolSpec,
    absolute_name,
    compact_json,
)
from rosbridge_mcp_server.wire.dialect import normalize_type

__all__ = ["MAX_COUNT", "MAX_DURATION", "SPEC", "SubscribeAnswer", "run"]

MAX_COUNT = 100
MAX_DURATION = 60.0
_SHOWN_IN_FULL = 10


class QosRequest(BaseModel):
    """ROS 2 quality of service for the subscription."""

    reliability: Literal["reliable", "best_effort"] | None = None
    durability: Literal["transient_local", "volatile"] | None = None
    depth: Annotated[int, Field(ge=1, le=1000)] | None = None


class ReceivedMessage(BaseModel):
    """One message as received, shortened."""

    received: float = Field(description="Seconds after the subscription started")
    message: dict[str, Any] = Field(description="The message; long arrays summarised, byte arrays omitted")
    cut: list[str] = Field(description="What was shortened, e.g. 'ranges: 720 numbers summarised'")


class SubscribeAnswer(BaseModel):
    """Messages read from a topic."""

    topic: str
    message_type: str
    messages: list[ReceivedMessage]
    rate_hz: float | None = Field(description="Observed rate between the first and last message")
    timed_out: bool = Field(description="True when no message arrived within the timeout")
    qos_note: str | None = None


SPEC = ToolSpec(
    name="subscribe_topic",
    title="Read a topic",
    description=(
        "Read messages from a topic (one by default). Read-only. Example: "
        '{"topic": "/scan", "count": 3, "fields": ["ranges"]}. Long arrays are summarised; a silent topic '
        "ends at the timeout."
    ),
    hints=READS_ROBOT,
    output=SubscribeAnswer,
)


async def run(
    ctx: ToolContext,
    *,
    topic: Annotated[str, Field(description="Topic name, e.g. /turtle1/pose")],
    message_type: Annotated[
        str | None, Field(description="e.g. sensor_msgs/msg/LaserScan (default: the graph's)")
    ] = None,
    count: Annotated[
        int | None, Field(ge=1, le=MAX_COUNT, description="Messages to read, e.g. 10 (default 1)")
    ] = None,
    duration: Annotated[
        float | None,
        Field(gt=0, le=MAX_DURATION, description="Seconds to collect (up to count), e.g. 2"),
    ] = None,
    timeout: Annotated[
        float, Field(gt=0, le=MAX_DURATION, description="Seconds to wait for a message, e.g. 5")
    ] = 5.0,
    fields: Annotated[
        list[str] | None, Field(description='Dotted paths to keep, e.g. ["pose.position", "header.stamp"]')
    ] = None,
    qos: Annotated[
        QosRequest | None,
        Field(description='ROS 2 QoS, e.g. {"durability": "transient_local"}'),
    ] = None,
) -> ToolAnswer:
    """Subscribe, collect, unsubscribe; shorten each message."""
    name = absolute_name(topic, "topic")
    info = await ctx.graph.ros_info()
    graph_type = await ctx.graph.topic_type(name)
    if message_type:
        wanted = normalize_type(message_type, info.version, "msg")
        if graph_type and not same_type(graph_type, wanted):
            raise ToolFailure(
                f"Topic {name} has type {graph_type}, not {wanted}; rosbridge would not subscribe. Leave "
                "message_type out to use the topic's own type."
            )
        msg_type = wanted
    elif graph_type:
        msg_type = graph_type
    else:
        missing, _ = await ctx.graph.unknown_topic(name, " (nothing publishes it)")
        raise ToolFailure(
            f"{missing} Call list_topics to see the topics, or give message_type to wait for a publisher "
            "that has not started yet."
        )
    typedefs = await _typedefs(ctx, msg_type)
    if fields and typedefs and (problem := unknown_field_path(msg_type, typedefs, fields)):
        raise ToolFailure(f"{problem} Nothing was subscribed; fix fields or leave them out.")
    wire_qos, qos_note = _qos(qos, info.version)
    wanted_count = count if count is not None else (MAX_COUNT if duration is not None else 1)

    async def progress(done: int) -> None:
        if wanted_count > 1:
            await ctx.report_progress(done, wanted_count, f"{done} of {wanted_count} messages from {name}")

    heard = await listen(
        ctx.client,
        name,
        msg_type,
        count=wanted_count,
        duration=duration,
        first_timeout=timeout,
        qos=wire_qos,
        on_message=progress,
    )
    byte_fields = byte_array_paths(msg_type, typedefs) if typedefs else []
    received: list[ReceivedMessage] = []
    for item in heard.messages:
        body: dict[str, Any] = item.message
        if fields:
            try:
                body = select_fields(body, fields)
            except FieldPathError as exc:
                raise ToolFailure(
                    f"{exc} Call subscribe_topic without fields to see the whole message."
                ) from None
        summary = summarize(body, byte_fields=byte_fields)
        received.append(
            ReceivedMessage(
                received=round(item.at, 3),
                message=summary.message,
                cut=sorted({cut.describe() for cut in summary.cuts}),
            )
        )
    rate = heard.rate_hz
    answer = SubscribeAnswer(
        topic=name,
        message_type=msg_type,
        messages=received,
        rate_hz=round(rate, 2) if rate is not None else None,
        timed_out=heard.first_timed_out,
        qos_note=qos_note,
    )
    return ToolAnswer(text=_text(answer, timeout), data=answer)


def _qos(qos: QosRequest | None, version: int) -> tuple[dict[str, Any] | None, str | None]:
    if qos is None:
        return None, None
    wire = qos.model_dump(exclude_none=True)
    if not wire:
        return None, None
    if version == 1:
        return None, "QoS not applied: ROS 1 has no QoS (rosbridge 0.11 ignores it)."
    if "depth" in wire:
        wire["history"] = "keep_last"
    return wire, (
        "QoS sent; rosbridge applies it from 2.0.7 (Humble), 2.7.0 (Jazzy), 3.3.0 (Kilted) on, older bridges "
        "ignore it, and only the first subscriber of a topic on the bridge sets it."
    )


async def _typedefs(ctx: ToolContext, msg_type: str) -> dict[str, TypeDef]:
    try:
        return await ctx.graph.message_typedefs(msg_type)
    except (UnknownTypeError, ServiceError, RequestTimeoutError):
        # Without a description the summary still spots byte arrays by their base64 look, and fields are
        # checked against the first message instead.
        return {}


def _text(answer: SubscribeAnswer, timeout: float) -> str:
    lines: list[str] = []
    if answer.timed_out:
        lines.append(
            f"No message on {answer.topic} ({answer.message_type}) within {timeout:g} s. Is anything "
            "publishing? get_topic_info shows its publishers; a longer timeout helps for slow topics."
        )
    else:
        count = len(answer.messages)
        rate = f", ~{answer.rate_hz:g} Hz" if answer.rate_hz else ""
        span = answer.messages[-1].received - answer.messages[0].received
        lines.append(
            f"{count} message{'s' if count != 1 else ''} on {answer.topic} ({answer.message_type})"
            f"{f' over {span:.2f} s' if count > 1 else ''}{rate}:"
        )
        limit = 600 if count <= _SHOWN_IN_FULL else 200
        for item in answer.messages:
            lines.append(f"[{item.received:.3f} s] {compact_json(item.message, limit)}")
        cuts = sorted({cut for item in answer.messages for cut in item.cut})
        if cuts:
            lines.append(f"Shortened: {'; '.join(cuts)}.")
    if answer.qos_note:
        lines.append(answer.qos_note)
    return "\n".join(lines)
