"""``list_topics``: every topic in the ROS graph with its type."""

from __future__ import annotations

from pydantic import BaseModel, Field

from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolSpec

__all__ = ["SPEC", "TopicRow", "TopicsAnswer", "run"]


class TopicRow(BaseModel):
    """One topic."""

    name: str = Field(description="Topic name, e.g. /turtle1/cmd_vel")
    type: str = Field(
        description='Message type, e.g. geometry_msgs/msg/Twist ("" if the graph does not know it)'
    )


class TopicsAnswer(BaseModel):
    """Every topic, sorted by name."""

    count: int
    topics: list[TopicRow]


SPEC = ToolSpec(
    name="list_topics",
    title="List topics",
    description=(
        "List every ROS topic the robot has, with its message type. Read-only; start here to learn what "
        "the robot publishes (sensors, state) and what it listens to (commands such as /turtle1/cmd_vel of "
        "type geometry_msgs/msg/Twist). Takes no arguments: call it with {}."
    ),
    hints=READS_ROBOT,
    output=TopicsAnswer,
)


async def run(ctx: ToolContext) -> ToolAnswer:
    """Ask rosapi for the topics and their types."""
    topics = await ctx.graph.topics()
    rows = [TopicRow(name=topic.name, type=topic.type) for topic in topics]
    if rows:
        lines = [f"{row.name} ({row.type or 'type unknown'})" for row in rows]
        text = f"{len(rows)} topics:\n" + "\n".join(lines)
    else:
        text = "The robot has no topics right now (nothing publishes or subscribes)."
    return ToolAnswer(text=text, data=TopicsAnswer(count=len(rows), topics=rows))
