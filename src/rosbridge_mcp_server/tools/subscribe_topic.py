"""``subscribe_topic``: read one or more messages from a topic, shortened for a model."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from rosbridge_mcp_server.pictures.summary import FieldPathError, select_fields, summarize
from rosbridge_mcp_server.robot.listening import Readout, read_topic
from rosbridge_mcp_server.robot.wording import counted
from rosbridge_mcp_server.tools.arguments import FROM_JSON_TEXT
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    LongWork,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolSpec,
    absolute_name,
    compact_json,
)

__all__ = ["MAX_COUNT", "MAX_DURATION", "SPEC", "SubscribeAnswer", "run"]

MAX_COUNT = 100
MAX_DURATION = 60.0
_SHOWN_IN_FULL = 10


class QosRequest(BaseModel):
    """ROS 2 quality of service for the subscription."""

    model_config = ConfigDict(extra="forbid")

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
    long_work=LongWork(given="duration"),
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
        list[str] | None,
        Field(description='Dotted paths to keep, e.g. ["pose.position", "header.stamp"]'),
        FROM_JSON_TEXT,
    ] = None,
    qos: Annotated[
        QosRequest | None,
        Field(description='ROS 2 QoS, e.g. {"durability": "transient_local"}'),
        FROM_JSON_TEXT,
    ] = None,
) -> ToolAnswer:
    """Subscribe, collect, unsubscribe (robot/'s read_topic); shorten each message."""
    wanted_count = count if count is not None else (MAX_COUNT if duration is not None else 1)

    async def progress(done: int) -> None:
        if wanted_count > 1:
            so_far = f"{done} of {wanted_count} messages" if duration is None else counted(done, "message")
            await ctx.report_progress(done, wanted_count, f"{so_far} from {name}")

    name = absolute_name(topic, "topic")
    readout = await read_topic(
        ctx.graph,
        ctx.client,
        name,
        message_type,
        count=wanted_count,
        duration=duration,
        first_timeout=timeout,
        fields=fields,
        qos=qos.model_dump(exclude_none=True) if qos is not None else None,
        on_message=progress,
    )
    heard = readout.heard
    if duration is not None and len(heard.messages) < wanted_count:
        # The duration ended before the count: the listen is done, so its progress ends at its total.
        done = f"{counted(len(heard.messages), 'message')} from {name} in {duration:g} s"
        await ctx.report_progress(wanted_count, wanted_count, done)
    answer = _answer(readout, fields)
    return ToolAnswer(text=_text(answer, timeout), data=answer)


def _answer(readout: Readout, fields: list[str] | None) -> SubscribeAnswer:
    heard = readout.heard
    return SubscribeAnswer(
        topic=readout.topic,
        message_type=readout.message_type,
        messages=[_received(item.message, item.at, fields, readout.byte_fields) for item in heard.messages],
        rate_hz=round(heard.rate_hz, 2) if heard.rate_hz is not None else None,
        timed_out=heard.first_timed_out,
        qos_note=readout.qos_note,
    )


def _received(
    message: dict[str, Any], at: float, fields: list[str] | None, byte_fields: list[str]
) -> ReceivedMessage:
    """One message as the answer shows it: the *fields* kept, long parts shortened."""
    body = message
    if fields:
        try:
            body = select_fields(body, fields)
        except FieldPathError as exc:
            raise ToolFailure(
                f"{exc} Call subscribe_topic without fields to see the whole message."
            ) from None
    summary = summarize(body, byte_fields=byte_fields)
    return ReceivedMessage(
        received=round(at, 3),
        message=summary.message,
        cut=sorted({cut.describe() for cut in summary.cuts}),
    )


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
            f"{counted(count, 'message')} on {answer.topic} ({answer.message_type})"
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
