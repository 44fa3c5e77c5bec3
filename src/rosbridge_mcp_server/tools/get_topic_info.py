"""``get_topic_info``: a topic's type, publishers and subscribers."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolSpec,
    absolute_name,
)

__all__ = ["SPEC", "TopicInfoAnswer", "run"]


class TopicInfoAnswer(BaseModel):
    """What the graph knows about one topic."""

    topic: str
    type: str
    publishers: list[str] = Field(description="Nodes that publish the topic")
    subscribers: list[str] = Field(description="Nodes that subscribe to the topic")


SPEC = ToolSpec(
    name="get_topic_info",
    title="Topic details",
    description=(
        "A topic's type and the nodes publishing and subscribing. Read-only. "
        'Example: {"topic": "/turtle1/pose"}.'
    ),
    hints=READS_ROBOT,
    output=TopicInfoAnswer,
)


async def run(
    ctx: ToolContext,
    topic: Annotated[str, Field(description="Topic name, e.g. /turtle1/pose")],
) -> ToolAnswer:
    """Ask rosapi for the topic's type, publishers and subscribers."""
    name = absolute_name(topic, "topic")
    details = await ctx.graph.topic_details(name)
    if not details.type and not details.publishers and not details.subscribers:
        missing, _ = await ctx.graph.unknown_topic(name, " (nothing publishes or subscribes to it)")
        raise ToolFailure(f"{missing} Call list_topics to see the topics that exist.")
    answer = TopicInfoAnswer(
        topic=name,
        type=details.type,
        publishers=list(details.publishers),
        subscribers=list(details.subscribers),
    )
    text = (
        f"{name}\ntype: {details.type or 'unknown'}\npublishers ({len(answer.publishers)}): "
        f"{', '.join(answer.publishers) or 'none'}\nsubscribers ({len(answer.subscribers)}): "
        f"{', '.join(answer.subscribers) or 'none'}"
    )
    return ToolAnswer(text=text, data=answer)
