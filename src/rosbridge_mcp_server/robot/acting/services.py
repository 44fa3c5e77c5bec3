"""A checked service call (:func:`call_service`): the type compared with the graph's, the request with the
type's definition, what the call does judged by the guard, then the call."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.errors import Advice, NotSentError, ServiceError
from rosbridge_mcp_server.robot.acting.context import Acting, as_read, given_name, motion_scene
from rosbridge_mcp_server.robot.approval import Act, approved, carry_out
from rosbridge_mcp_server.robot.effects import service_effects
from rosbridge_mcp_server.robot.goals.caused import caused_by_call
from rosbridge_mcp_server.robot.graph import is_missing_service
from rosbridge_mcp_server.robot.messages import require_fit
from rosbridge_mcp_server.robot.names import absolute_name, check_name_for_ros, did_you_mean

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import Dialect

__all__ = ["ServiceReply", "call_service"]


@dataclass(frozen=True)
class ServiceReply:
    """A service's response."""

    service: str
    type: str  #: as the graph reports it (or as given, when the graph cannot tell)
    response: Any  #: the response message (an object on every bridge we know)


async def call_service(
    ctx: Acting, *, tool: str, service: str, service_type: str, request: dict[str, Any], timeout: float
) -> ServiceReply:
    """Check the request when rosapi can describe the type, call the service, return its response.

    The send gate is asked right before the call's frame is written (after a lane is opened for it)."""
    ticket = ctx.gate.ticket()  # a stop from now on voids this call
    name = absolute_name(service, "service")
    dialect = await ctx.graph.dialect()
    check_name_for_ros(name, "service", dialect.version)
    srv_type = await _checked_request(ctx, dialect, name, dialect.service_type(service_type), request)
    # What the call does (an action's goal, parameter writes, motion) is judged too, not only its name.
    effects = service_effects(name, srv_type, request, dialect.version)
    scene = await motion_scene(ctx, "service", name, srv_type, request)
    act = await approved(
        ctx,
        Act(
            tool,
            "service",
            name,
            srv_type,
            request,
            effects=effects,
            given=given_name(service, name),
            scene=scene,
        ),
    )
    caused = caused_by_call(act.name, act.payload, act.effects, dialect.version)

    def check() -> None:
        ctx.gate.check(ticket, act)
        # The goal a send_goal call starts is remembered for the stops before the call goes out: its answer
        # may never come while the goal runs.
        ctx.goals.caused(caused)

    try:
        response = await carry_out(
            ctx,
            act,
            lambda: ctx.client.call_service(act.name, act.payload, timeout=timeout, check=check),
        )
    except ServiceError as exc:
        ctx.goals.forget_caused(caused)  # the bridge refused the call: no goal started
        # rosapi does not list hidden services (ROS 2 `_action/...`), so an unlisted name is still tried;
        # the bridge answers at once when nothing offers it.
        if not is_missing_service(exc):
            raise
        ctx.graph.forget_service(act.name)
        hint = did_you_mean(act.name, await ctx.graph.service_names())
        raise NotSentError(f"Service {act.name} is not offered by any node.{hint}").advise(
            Advice.SERVICES
        ) from exc
    return ServiceReply(act.name, srv_type, response)


async def _checked_request(
    ctx: Acting, dialect: Dialect, name: str, given_type: str, request: dict[str, Any]
) -> str:
    """The service's type (the graph's, else *given_type*), refused when the graph names another; the
    request checked against it when rosapi can describe it."""
    graph_type = await ctx.graph.service_type(name, cached=True)
    if graph_type and not dialect.same_type(graph_type, given_type):
        # The cached type may be stale (the service was offered anew with another type): ask once more.
        graph_type = await ctx.graph.service_type(name)
    if graph_type and not dialect.same_type(graph_type, given_type):
        raise NotSentError(
            f"Service {name} has type {graph_type}, not {given_type}. Build the request for {graph_type} "
            "and call again with that service_type."
        )
    srv_type = graph_type or given_type
    if graph_type:
        typedefs = await ctx.graph.service_request_typedefs(srv_type)
        if typedefs:
            require_fit(
                as_read(dialect, request),
                typedefs,
                ros_version=dialect.version,
                nothing_sent="The service was not called",
                looks_like="A request",
            )
    return srv_type
