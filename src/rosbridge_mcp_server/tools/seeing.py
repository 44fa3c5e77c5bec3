"""What the picture tools (``view_map``, ``view_scan``, ``plot_topic``) share: checking a topic's type,
taking one message from it, and a frame's planar pose from /tf."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Literal

from rosbridge_mcp_server.robot.frames import look_up_transform
from rosbridge_mcp_server.robot.listening import listen
from rosbridge_mcp_server.robot.messages import short_type_name
from rosbridge_mcp_server.robot.namespaces import SeveralNamespacesError
from rosbridge_mcp_server.robot.occupancy import Pose2D
from rosbridge_mcp_server.robot.transforms import TransformError
from rosbridge_mcp_server.tools.base import ToolContext, ToolFailure, absolute_name

__all__ = ["first_message", "is_type", "planar_pose", "typed_topic"]


def is_type(*names: str) -> Callable[[str], bool]:
    """A test for message types, written ``pkg/Type`` (either dialect's spelling matches)."""
    wanted = frozenset(names)
    return lambda msg_type: short_type_name(msg_type) in wanted


async def typed_topic(
    ctx: ToolContext, topic: str, argument: str, *, accepts: Callable[[str], bool], kind: str, hint: str = ""
) -> tuple[str, str]:
    """The absolute topic name and its type; a :class:`ToolFailure` naming the topics of the right kind when
    it is missing, or saying what it carries when it is of another type."""
    name = absolute_name(topic, argument)
    msg_type = await ctx.graph.topic_type(name)
    if not msg_type:
        missing, known = await ctx.graph.unknown_topic(name, among=accepts)
        kinds = f"{kind} topics" if kind else "Topics"
        listing = f" {kinds}: {', '.join(known[:20])}." if known else f" The graph has no {kinds.lower()}."
        raise ToolFailure(f"{argument}: {missing}{listing}")
    if not accepts(msg_type):
        raise ToolFailure(f"{argument}: {name} carries {msg_type}, not {kind}. {hint}".rstrip())
    return name, msg_type


async def first_message(
    ctx: ToolContext,
    name: str,
    msg_type: str,
    timeout: float,
    what: str,
    *,
    compression: Literal["cbor"] | None = None,
) -> dict[str, Any]:
    """One message from the topic within ``timeout`` seconds, else a :class:`ToolFailure`.

    ``compression="cbor"`` for large messages: numeric arrays arrive as ``array.array``, not lists."""
    heard = await listen(
        ctx.client, name, msg_type, count=1, duration=None, first_timeout=timeout, compression=compression
    )
    if not heard.messages:
        raise ToolFailure(
            f"No {what} arrived on {name} within {timeout:g} s. Is its publisher running? get_topic_info "
            "shows the topic's publishers; a larger timeout waits longer."
        )
    return heard.messages[0].message


async def planar_pose(
    ctx: ToolContext,
    target: str,
    source: str,
    timeout: float,
    *,
    namespace: str | None = "",
    topic: str = "",
) -> Pose2D | str:
    """Where ``source`` is in ``target`` (x, y, yaw) from /tf and /tf_static, or why it is not known.

    The robot's *namespace*'s tf; with none (``None``) and no tf at the root, the robot's whose namespace
    holds *topic* (``/robot2/map``: ``/robot2/tf``), or the one robot's with a tf."""
    try:
        found = await look_up_transform(
            ctx.client, ctx.graph, target, source, timeout=timeout, namespace=namespace
        )
    except SeveralNamespacesError as exc:
        owners = [ns for ns in exc.namespaces if topic.startswith(f"{ns}/")]
        if not owners:
            return str(exc)
        return await planar_pose(ctx, target, source, timeout, namespace=max(owners, key=len))
    except TransformError as exc:
        return str(exc)
    t = found.lookup.transform
    x, y, z, w = t.rotation
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return Pose2D(t.translation[0], t.translation[1], yaw)
