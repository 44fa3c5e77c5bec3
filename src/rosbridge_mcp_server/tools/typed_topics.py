"""A topic a tool reads, checked for its type (the topics of the right kind listed when it is missing or
carries another), and one message taken from it within a timeout: what the picture tools (``view_map``,
``view_scan``, ``plot_topic``) and the namespaced topics (``tools/namespaces.py``) share."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rosbridge_mcp_server.robot.listening import listen
from rosbridge_mcp_server.robot.messages import short_type_name
from rosbridge_mcp_server.tools.base import ToolContext, ToolFailure, absolute_name

__all__ = ["first_message", "is_type", "typed_topic"]


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
    ctx: ToolContext, name: str, msg_type: str, timeout: float, what: str
) -> dict[str, Any]:
    """One message from the topic within ``timeout`` seconds, else a :class:`ToolFailure`."""
    heard = await listen(ctx.client, name, msg_type, count=1, duration=None, first_timeout=timeout)
    if not heard.messages:
        raise ToolFailure(
            f"No {what} arrived on {name} within {timeout:g} s. Is its publisher running? get_topic_info "
            "shows the topic's publishers; a larger timeout waits longer."
        )
    return heard.messages[0].message
