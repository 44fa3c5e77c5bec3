"""``publish_service``: call a ROS service and return its response."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.errors import InvalidMessageError, ServiceError
from rosbridge_mcp_server.ros import is_missing_service
from rosbridge_mcp_server.tools.base import (
    ACTS_ON_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolSpec,
    absolute_name,
    check_name_for_ros,
    compact_json,
    did_you_mean,
    parse_json_object,
)
from rosbridge_mcp_server.typecheck import check_message, example_message, short_type_name
from rosbridge_mcp_server.wire.dialect import adapt_message, normalize_type

__all__ = ["MAX_SERVICE_TIMEOUT", "SPEC", "ServiceAnswer", "run"]

MAX_SERVICE_TIMEOUT = 300.0
_EXAMPLE = '{"a": 2, "b": 3}'


class ServiceAnswer(BaseModel):
    """A service's response."""

    service: str
    service_type: str = Field(description="The service's type as the graph reports it")
    response: dict[str, Any] = Field(description="The response fields")


SPEC = ToolSpec(
    name="publish_service",
    title="Call a service",
    description=(
        "Call a ROS service and return its response. Services can change the robot (reset, spawn, set "
        "parameters). Example: service /add_two_ints, service_type example_interfaces/srv/AddTwoInts, "
        f"request {_EXAMPLE}; or service /reset, service_type std_srvs/srv/Empty, request {{}}. The request "
        "is checked against the type when rosapi can describe it; a failing service returns the bridge's "
        "error text. Use list_services to find services and their types."
    ),
    hints=ACTS_ON_ROBOT,
    output=ServiceAnswer,
)


async def run(
    ctx: ToolContext,
    service: Annotated[str, Field(description="Service name, e.g. /add_two_ints")],
    service_type: Annotated[
        str,
        Field(description="Service type, pkg/srv/Type or pkg/Type, e.g. example_interfaces/srv/AddTwoInts"),
    ],
    request: Annotated[
        dict[str, Any] | str,
        Field(description=f"Request fields as a JSON object, e.g. {_EXAMPLE}; {{}} for std_srvs/srv/Trigger"),
    ] = "{}",
    # The name is the tool's parameter name, kept from the project this one replaces.
    timeout: Annotated[
        float,
        Field(
            gt=0,
            le=MAX_SERVICE_TIMEOUT,
            description=(
                f"Seconds to wait for the response (more than 0, at most {MAX_SERVICE_TIMEOUT:g}), e.g. 10"
            ),
        ),
    ] = 10.0,
) -> ToolAnswer:
    """Check the request when the type is known, call the service, return its response."""
    name = absolute_name(service, "service")
    body = parse_json_object(request, "request", _EXAMPLE)
    info = await ctx.graph.ros_info()
    check_name_for_ros(name, "service", info.version)
    given_type = normalize_type(service_type, info.version, "srv")

    graph_type = await ctx.graph.service_type(name, cached=True)
    if graph_type and short_type_name(graph_type) != short_type_name(given_type):
        # The cached type may be stale (the service was offered anew with another type): ask once more.
        graph_type = await ctx.graph.service_type(name)
    if graph_type and short_type_name(graph_type) != short_type_name(given_type):
        raise ToolFailure(
            f"Service {name} has type {graph_type}, not {given_type}. Build the request for {graph_type} "
            "and call again with that service_type."
        )
    srv_type = graph_type or given_type
    body = adapt_message(body, info.version)
    if graph_type:
        await _check_request(ctx, body, srv_type, info.version)

    try:
        response = await ctx.client.call_service(name, body, timeout=timeout)
    except ServiceError as exc:
        # rosapi does not list hidden services (ROS 2 `_action/...`), so an unlisted name is still tried;
        # the bridge answers at once when nothing offers it.
        if not is_missing_service(exc):
            raise
        ctx.graph.forget_service(name)
        hint = did_you_mean(name, await ctx.graph.service_names())
        raise ToolFailure(
            f"Service {name} is not offered by any node.{hint} Call list_services to see the services."
        ) from exc
    text = f"Service {name} ({srv_type}) answered: {compact_json(response)}"
    # rosbridge answers a successful call with the response message as an object; anything else is kept whole.
    fields = response if isinstance(response, dict) else {"value": response}
    return ToolAnswer(text=text, data=ServiceAnswer(service=name, service_type=srv_type, response=fields))


async def _check_request(ctx: ToolContext, body: dict[str, Any], srv_type: str, ros_version: int) -> None:
    """Refuse a request that does not fit, when rosapi can describe the service type."""
    typedefs = await ctx.graph.service_request_typedefs(srv_type)
    if not typedefs:
        return
    request_type = next(iter(typedefs))
    try:
        check_message(body, request_type, typedefs, ros_version=ros_version)
    except InvalidMessageError as exc:
        shape = compact_json(example_message(request_type, typedefs, ros_version=ros_version))
        raise ToolFailure(f"{exc}. The service was not called. A request looks like {shape}.") from exc
