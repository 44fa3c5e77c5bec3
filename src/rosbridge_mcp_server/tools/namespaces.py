"""The ``namespace`` argument of the navigation, transform, picture and diagnose tools: a robot of several on
one bridge (``/robot2``: ``/robot2/map``, ``/robot2/tf``, ``/robot2/navigate_to_pose``).

The argument wins; else the robot's own (``namespace`` in its fleet file entry, ``Config.namespace``); else
the tool finds it (``robot/namespaces.py``): the plain names when the graph has them, the one namespace that
has them (the answer says so), or, when several do, an error listing the exact call for each.
"""

from __future__ import annotations

import inspect
import json
from collections.abc import Callable
from typing import Annotated, Any

from pydantic import Field

from rosbridge_mcp_server.robot.names import absolute_name
from rosbridge_mcp_server.robot.namespaces import (
    SeveralNamespacesError,
    find_namespace,
    namespace_name,
    under,
)
from rosbridge_mcp_server.tools.base import ToolContext, ToolFailure
from rosbridge_mcp_server.tools.typed_topics import typed_topic

__all__ = ["NamespaceArgument", "choose_one", "given_namespace", "namespaced_topic", "non_defaults"]

#: Omitted: found; ``""``: none (the tools/list budget keeps the description to an example).
NamespaceArgument = Annotated[str | None, Field(description="e.g. /robot2")]


def given_namespace(ctx: ToolContext, namespace: str | None) -> str | None:
    """The namespace asked for (the argument, else the robot's configured one), checked; ``None``: find it."""
    value = namespace if namespace is not None else ctx.config.namespace
    if value is None:
        return None
    try:
        return namespace_name(value)
    except ValueError as exc:
        raise ToolFailure(f"{exc}.") from None


def non_defaults(run: Callable[..., Any], given: dict[str, Any]) -> dict[str, Any]:
    """The arguments of a call to the tool *run* that differ from its defaults (a suggested call repeats
    them)."""
    parameters = inspect.signature(run).parameters
    return {
        key: value
        for key, value in given.items()
        if key in parameters and key != "namespace" and value != parameters[key].default
    }


def choose_one(exc: SeveralNamespacesError, tool: str, arguments: dict[str, Any]) -> ToolFailure:
    """The answer when several robots' namespaces fit: each one's exact call."""
    calls = "\n".join(
        f"→ {tool} {json.dumps({**arguments, 'namespace': ns}, ensure_ascii=False)}" for ns in exc.namespaces
    )
    return ToolFailure(
        f"{exc} Say which robot; one call each:\n{calls}\nNothing was guessed, nothing was sent."
    )


async def namespaced_topic(
    ctx: ToolContext,
    topic: str,
    argument: str,
    namespace: str | None,
    *,
    tool: str,
    arguments: dict[str, Any],
    accepts: Callable[[str], bool],
    kind: str,
    hint: str = "",
) -> tuple[str, str, str, str | None]:
    """(topic, type, namespace, note): *topic* under the namespace given, else as given, else under the one
    namespace that has it (the note says so); several: an error with each one's call. The plain topic's
    happy path asks what ``typed_topic`` asks, nothing more."""
    given = given_namespace(ctx, namespace)
    if given is not None:
        name, msg_type = await typed_topic(
            ctx, under(given, absolute_name(topic, argument)), argument, accepts=accepts, kind=kind, hint=hint
        )
        return name, msg_type, given, None
    try:
        name, msg_type = await typed_topic(ctx, topic, argument, accepts=accepts, kind=kind, hint=hint)
    except ToolFailure:
        plain = absolute_name(topic, argument)
        if await ctx.graph.topic_type(plain):
            raise  # there, of another type
        try:
            found = await find_namespace(ctx.graph, None, plain, kind="topic", present=False)
        except SeveralNamespacesError as exc:
            raise choose_one(exc, tool, arguments) from None
        if not found.namespace:
            raise
        name, msg_type = await typed_topic(
            ctx, under(found.namespace, plain), argument, accepts=accepts, kind=kind, hint=hint
        )
        return name, msg_type, found.namespace, found.note
    return name, msg_type, "", None
