"""A message published once (:func:`publish_once`), and what every publish shares: the message checked
against its type and the graph (:func:`checked_message`), the bridge proved to be reading
(:func:`bridge_is_reading`), and how the guard changed the message (:func:`adjusted_text`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rosbridge_mcp_server.errors import Advice, NotSentError, RequestTimeoutError
from rosbridge_mcp_server.robot.acting.context import Acting, as_read, given_name, motion_scene
from rosbridge_mcp_server.robot.approval import Act, approved, carry_out
from rosbridge_mcp_server.robot.effects import topic_effects
from rosbridge_mcp_server.robot.goals.caused import caused_by_publish
from rosbridge_mcp_server.robot.messages import require_fit
from rosbridge_mcp_server.robot.names import absolute_name, check_name_for_ros
from rosbridge_mcp_server.robot.velocity import clamp_text, is_velocity_type

__all__ = ["PING_LIMIT", "Published", "adjusted_text", "bridge_is_reading", "checked_message", "publish_once"]

#: Longest wait for the bridge's pong before a publish (less when the configured request timeout is shorter).
PING_LIMIT = 3.0


@dataclass(frozen=True)
class Published:
    """What was published."""

    topic: str
    type: str  #: as the bridge was given it
    message: dict[str, Any]  #: as sent
    #: How the safety policy changed the message before it was sent (velocity caps in clamp mode), or None.
    adjusted: str | None = None


async def publish_once(
    ctx: Acting, *, tool: str, topic: str, message_type: str, message: dict[str, Any]
) -> Published:
    """Check *message* against *message_type* and the topic's type in the graph, then publish it once.

    Before the publish, a ping proves the bridge reads the connection now (see :func:`bridge_is_reading`);
    then the send gate (``robot/gate.py``) says whether it may go now: no stop since the call began, no
    latched E-STOP, and a free slot within the topic's rate.
    """
    ticket = ctx.gate.ticket()  # a stop from now on voids this call
    name, bridge_type, body = await checked_message(ctx, topic, message_type, message)
    act = await approved(
        ctx,
        Act(
            tool,
            "topic",
            name,
            bridge_type,
            body,
            effects=topic_effects(name, bridge_type),
            given=given_name(topic, name),
            scene=await motion_scene(ctx, "topic", name, bridge_type, body),
        ),
    )
    # A goal it starts (a goal topic, a goal pose) is remembered for the stops once it is sent.
    caused = caused_by_publish(act.name, act.payload, act.effects, (await ctx.graph.dialect()).version)

    async def send() -> None:
        await bridge_is_reading(ctx)
        # Advertised first, so that nothing but the message itself is sent after the gate said yes.
        await ctx.client.advertise(act.name, act.type)
        await ctx.gate.pace(ticket, act)
        await ctx.client.publish(act.name, act.type, act.payload)
        ctx.goals.caused(caused)
        ctx.graph.remember_publishing(act.name, act.type)
        # stop_robot zeroes every velocity topic this session has driven.
        ctx.activity.published(act.name, act.type, act.payload)

    await carry_out(ctx, act, send)
    adjusted = adjusted_text(act.type, body, act.payload)
    return Published(act.name, act.type, act.payload, adjusted)


async def checked_message(
    ctx: Acting, topic: str, message_type: str, message: dict[str, Any]
) -> tuple[str, str, dict[str, Any]]:
    """The absolute topic, the type as the bridge spells it, and the message, checked."""
    name = absolute_name(topic, "topic")
    dialect = await ctx.graph.dialect()
    check_name_for_ros(name, "topic", dialect.version)
    bridge_type = dialect.message_type(message_type)
    typedefs = await ctx.graph.message_typedefs(message_type)

    graph_type = await ctx.graph.publishing_type(name)
    if graph_type and not dialect.same_type(graph_type, bridge_type):
        raise NotSentError(
            f"Topic {name} has type {graph_type}, not {bridge_type}; rosbridge would drop the message."
        ).advise(Advice.TOPIC_TYPE, graph_type)
    require_fit(
        as_read(dialect, message),
        typedefs,
        type_name=bridge_type,
        ros_version=dialect.version,
        nothing_sent="Nothing was published",
        looks_like=f"A {bridge_type} message",
    )
    return name, bridge_type, message


def adjusted_text(type_name: str, before: Any, after: Any) -> str | None:
    """How the guard changed a message before it was sent, or ``None``: a velocity command scaled to the caps,
    or a motion goal's speed (DriveOnHeading, BackUp, carried by a topic) lowered to them."""
    if after == before:
        return None
    if is_velocity_type(type_name):
        return clamp_text(type_name, before, after)
    return "lowered the goal's speed to the [velocity] max_linear cap"


async def bridge_is_reading(ctx: Acting) -> None:
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
        raise NotSentError(
            f"rosbridge at {ctx.client.url} did not answer a ping within {limit:g} s (the bridge is frozen, "
            "or the network to the robot is down), so nothing was published: a message sent now could reach "
            "the robot late and move it then. Check the robot and its network, then try again."
        ) from exc
